"""Gearbox modes: the reduced model linearised at its static state (paper section II.B):
natural frequencies, damping ratios, the subsystem and gear-mesh strain-energy share of each
mode, and the resonance speeds where a mesh order meets a mesh-active mode."""
from __future__ import annotations

import time

import numpy as np

from ..pipeline.outcome import RunContext

__all__ = ["run", "reference_rpm"]


def reference_rpm(scene) -> float:
    if scene.time_response is not None:
        return scene.time_response.omega
    for sec in (scene.sweep, scene.continuation):
        if sec is not None:
            return 0.5 * (sec.omega_min + sec.omega_max)
    return 0.0


def run(study, scene, ctx: RunContext) -> dict:
    """Modes of the reduced model linearised at the static state (mesh strain-energy share
    per mode, resonance speeds of the mesh orders)."""
    from ..report.gearbox_plots import plot_resonance_map, write_modes_csv
    from ..solvers.linear import linear_modes

    gm = study.gearbox
    rpm = reference_rpm(scene)
    u0 = study.start(rpm)
    t0 = time.perf_counter()
    lm = linear_modes(gm.reduced, u0, rpm)
    wall = time.perf_counter() - t0
    f_hz = lm.frequency * gm.omega_ref
    shares, names = _subsystem_shares(gm, lm.vectors)
    mesh = _mesh_energy(gm, lm, u0)
    write_modes_csv(ctx.out / "modes.csv", f_hz, lm.damping_ratio, names, shares, mesh,
                    [c.name for c in gm.contacts if c.kind == "mesh"])
    lo, hi = (scene.sweep.omega_min, scene.sweep.omega_max) if scene.sweep else (0.5 * rpm, 1.5 * rpm)
    crit = _resonance_speeds(gm, f_hz, mesh, lo, hi)
    plot_resonance_map(ctx.out / "resonance_map", f_hz, mesh, gm.mesh_teeth, lo, hi,
                       title=study.title + f", linearised at {rpm:g} rpm")
    return {"status": "ok", "rpm": rpm, "modes": int(f_hz.size),
            "first_frequencies_hz": [float(f) for f in f_hz[:12]],
            "resonance_speeds_rpm": crit, "wall_s": wall,
            "mesh_stiffness": gm.mesh_stiffness_summary(),
            "build_timings_s": gm.timings,
            "error_estimate": {"note": "linearised reduced model; see reduction_accuracy"}}


def _subsystem_shares(gm, vectors):
    from ..models.synthesis import subsystem_offsets

    off = subsystem_offsets(gm.subsystems)
    energy = np.abs(vectors) ** 2
    shares = np.array([energy[off[k]:off[k + 1]].sum(axis=0) for k in range(len(off) - 1)])
    shares /= np.maximum(shares.sum(axis=0), 1e-300)
    return shares, [s.name for s in gm.subsystems]


def _mesh_energy(gm, lm, x0) -> np.ndarray:
    """(n_meshes, n_modes): strain-energy share k'_mesh (c . phi)^2 / (phi^T K_t phi) of
    each mesh (k': its tangent stiffness at the static state, 0 in the backlash) in the
    undamped mode nearest in frequency to each damped mode."""
    from ..solvers.linear import contact_slopes

    r = gm.reduced
    idx = gm.contact_indices("mesh")
    if idx.size == 0:
        return np.zeros((0, lm.frequency.size))
    d = r.contacts.directions[idx]
    k = contact_slopes(r, x0[:r.n_modes])[0][idx][:, None]
    phi = lm.undamped_vectors
    w2 = np.maximum((2 * np.pi * lm.undamped) ** 2, 1e-300)
    share = k * (d @ phi) ** 2 / (w2 * np.sum(phi ** 2, axis=0))
    nearest = np.abs(lm.frequency[:, None] - lm.undamped[None, :]).argmin(axis=1)
    return share[:, nearest]


def _resonance_speeds(gm, f_hz, mesh, lo, hi, threshold=0.05) -> list[dict]:
    out = []
    if mesh.size == 0:
        return out
    share = mesh.max(axis=0)
    for i in np.flatnonzero(share > threshold):
        for order in (1, 2):
            rpm = 60.0 * f_hz[i] / (order * gm.mesh_teeth)
            if lo <= rpm <= hi:
                out.append({"mode": int(i), "frequency_hz": float(f_hz[i]), "mesh_order": order,
                            "rpm": float(rpm), "mesh_energy_share": float(share[i])})
    return out


