"""Gearbox modes: the reduced model linearised at its static state (paper section II.B):
natural frequencies, damping ratios, the subsystem and gear-mesh strain-energy share of each
mode, and the resonance speeds where a mesh order meets a mesh-active mode.

Rigid-body modes (eigenvalues at round-off distance from zero: a drive train free to turn, a
shaft without axial support) are counted, not listed, as in the rotor analysis.  A mesh
whose deformation sits exactly on its contact boundary (zero backlash, no load) is
linearised as closed: its tangent stiffness is the mesh stiffness, as for any small motion
into the flank (the contact law's non-strict side).
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..pipeline.outcome import AnalysisOutcome, RunContext

__all__ = ["run", "reference_rpm", "linearisation_model", "RIGID_TOL", "GearboxModesResult"]


@dataclasses.dataclass(frozen=True, eq=False)
class GearboxModesResult:
    """What :mod:`vibrogear.report.writers.gearbox_modes` writes: the elastic modes of the
    reduced model linearised at its static state, and the speed range of the resonance map.

    K elastic modes (rigid-body modes counted, not listed), S subsystems, M meshes.

    Fields:

    - ``f_hz``: (K,) [Hz] natural frequencies |lambda| / 2 pi, ascending.
    - ``fd_hz``: (K,) [Hz] damped natural frequencies.
    - ``zeta``: (K,) [1] modal damping ratios.
    - ``names``: (S,) the subsystems (shafts, the housing); ``shares``: (S, K) [1] each
      subsystem's share of each mode's energy (a column sums to 1).
    - ``mesh_names``: (M,) the gear meshes; ``mesh``: (M, K) [1] each mesh's share of each
      mode's strain energy.
    - ``mesh_teeth``: the driving gear's teeth of the first mesh.
    - ``rpm``: [rpm] the speed of the static state; ``rpm_lo``, ``rpm_hi``: [rpm] the
      resonance map's speed range.
    - ``title``: the study's title.
    - ``orders``: ((mesh name, [Hz/rpm]) ...) each mesh's frequency per driving rpm.
    - ``resonances``: the resonance speeds (dicts: ``rpm``, ``frequency_hz``, ``mesh``,
      ``mesh_order``, ...; as in summary.json).

    :meth:`arrays`: the columns of ``modes.csv`` (``frequency_hz``, ``damped_frequency_hz``,
    ``damping_ratio``, ``share`` (K,) [1] the dominant subsystem's, ``dominant`` (K,) str,
    ``mesh_energy_<mesh>`` (K,) [1]); :meth:`plot`: the resonance map."""
    f_hz: np.ndarray
    fd_hz: np.ndarray
    zeta: np.ndarray
    names: tuple[str, ...]
    shares: np.ndarray
    mesh: np.ndarray
    mesh_names: tuple[str, ...]
    mesh_teeth: int
    rpm: float
    rpm_lo: float
    rpm_hi: float
    title: str
    orders: tuple = ()              # (mesh name, mesh frequency per driving rpm [Hz/rpm])
    resonances: tuple = ()          # the resonance speeds (dicts, as in the summary)

    def arrays(self) -> dict[str, np.ndarray]:
        """The columns of ``modes.csv`` as arrays, by the same names (see the class docstring)."""
        k = np.argmax(self.shares, axis=0) if self.f_hz.size else np.zeros(0, int)
        out = {"frequency_hz": np.asarray(self.f_hz, float),
               "damped_frequency_hz": np.asarray(self.fd_hz, float),
               "damping_ratio": np.asarray(self.zeta, float),
               "dominant": np.array([self.names[i] for i in k], dtype=str),
               "share": np.array([self.shares[i, j] for j, i in enumerate(k)], float)}
        for j, name in enumerate(self.mesh_names):
            out[f"mesh_energy_{name}"] = np.asarray(self.mesh[j], float)
        return out

    def plot(self):
        """The resonance map (``resonance_map.png``) as a matplotlib Figure: natural
        frequencies against every mesh's orders over the speed range."""
        from ..report.plots.gearbox import resonance_map_figure
        return resonance_map_figure(self)

#: a mode is rigid when its natural frequency is below this fraction of the highest one
RIGID_TOL = 1e-7


def reference_rpm(scene) -> float:
    """The speed the modes are computed at: ``gearbox.modes_rpm``, else the time response's
    speed, else the middle of the sweep (or continuation) range, else 0."""
    if scene.gearbox is not None and scene.gearbox.modes_rpm is not None:
        return float(scene.gearbox.modes_rpm)
    tr = scene.time_response
    if tr is not None:
        return float(tr.param if hasattr(tr, "param") else tr.omega)
    for sec in (scene.sweep, scene.continuation):
        if sec is not None:
            return 0.5 * sum(sec.param_range())
    return 0.0


def linearisation_model(model, x0):
    """``model`` with each contact whose deformation at ``x0`` lies exactly on a closed
    boundary of zero width (gap_lo == gap_hi: a zero-backlash mesh, unloaded) moved just
    inside its upper contact, so the linearisation takes its stiffness (non-strict
    inequality); every other contact is left as it is."""
    ct = model.contacts
    if not ct.count:
        return model
    d = ct.directions @ np.asarray(x0, float)[:model.n_modes]
    scale = np.maximum(np.abs(ct.gap_hi), 1e-12)
    on = (ct.gap_hi == ct.gap_lo) & (np.abs(d - ct.gap_hi) <= 1e-9 * scale) & (ct.exponent == 1.0)
    if not np.any(on):
        return model
    gap_hi = np.where(on, d - 1e-9 * scale, ct.gap_hi)
    return dataclasses.replace(model, contacts=dataclasses.replace(ct, gap_hi=gap_hi))


def run(study, scene, ctx: RunContext) -> AnalysisOutcome:
    """Modes of the reduced model linearised at the static state (mesh strain-energy share
    per mode, resonance speeds of the mesh orders); the files (``modes.csv``,
    ``resonance_map.png/.svg``) are written by :mod:`vibrogear.report.writers.gearbox_modes`."""
    from ..solvers.linear import linear_modes

    gm = study.gearbox
    rpm = reference_rpm(scene)
    u0 = study.start(rpm)
    t0 = time.perf_counter()
    model = linearisation_model(gm.reduced, u0)
    lm = linear_modes(model, u0, rpm)
    wall = time.perf_counter() - t0
    f_all = lm.frequency * gm.omega_ref
    elastic = f_all > RIGID_TOL * max(float(f_all.max(initial=0.0)), 1e-300)
    # rigid-body modes: zero eigenvalues of the tangent stiffness (their state-space pairs
    # are round-off, some without an imaginary part, so they are counted here)
    n_rigid = int(np.sum(lm.undamped <= RIGID_TOL * max(float(lm.undamped.max(initial=0.0)),
                                                        1e-300)))
    f_hz = f_all[elastic]
    fd_hz = f_hz * np.sqrt(np.clip(1.0 - lm.damping_ratio[elastic] ** 2, 0.0, None))
    zeta = lm.damping_ratio[elastic]
    shares, names = _subsystem_shares(gm, lm.vectors[:, elastic])
    mesh = _mesh_energy(gm, model, lm, u0)[:, elastic]
    if scene.sweep is not None:
        lo, hi = scene.sweep.param_range()
    elif rpm > 0:
        lo, hi = 0.5 * rpm, 1.5 * rpm
    else:            # at rest: the speeds up to the 1x resonance of the highest mode listed
        lo, hi = 0.0, 1.1 * 60.0 * float(f_hz.max(initial=1.0)) / gm.mesh_teeth
    orders = mesh_orders_per_rpm(scene.gearbox)
    crit = resonance_crossings(f_hz, mesh.max(axis=0) if mesh.size else np.zeros_like(f_hz),
                               orders, lo, hi)
    result = GearboxModesResult(
        f_hz=f_hz, fd_hz=fd_hz, zeta=zeta, names=tuple(names), shares=shares, mesh=mesh,
        mesh_names=tuple(c.name for c in gm.contacts if c.kind == "mesh"),
        mesh_teeth=gm.mesh_teeth, rpm=rpm, rpm_lo=lo, rpm_hi=hi,
        orders=tuple(orders), resonances=tuple(crit),
        title=study.title + f", linearised at {rpm:g} rpm")
    summary = {"rpm": rpm, "modes": int(f_hz.size), "n_rigid": n_rigid,
            "first_frequencies_hz": [float(f) for f in f_hz[:12]],
            "resonance_speeds_rpm": crit, "wall_s": wall,
            "mesh_stiffness": gm.mesh_stiffness_summary(),
            "torque_orders": list(gm.torque_orders),
            # the forcing's common period (None: longer than the model's limit) and the
            # period the sweep, states and map sample (1 where multi-frequency)
            "excitation_period_mesh_periods": gm.reduced.forcing_period_multiple,
            "sampled_period_mesh_periods": gm.reduced.period_multiple,
            "multi_frequency": gm.reduced.multi_frequency,
            "mesh_frequency_ratios": {m.name: f"{r.numerator}/{r.denominator}" for m, r in
                                      zip(scene.gearbox.meshes,
                                          scene.gearbox.mesh_frequency_ratios())},
            "build_timings_s": gm.timings,
            "error_estimate": {"note": "linearised reduced model; see reduction_accuracy"}}
    return AnalysisOutcome(summary=summary, result=result)


def _subsystem_shares(gm, vectors):
    from ..models.gearbox.synthesis import subsystem_offsets

    off = subsystem_offsets(gm.subsystems)
    energy = np.abs(vectors) ** 2
    shares = np.array([energy[off[k]:off[k + 1]].sum(axis=0) for k in range(len(off) - 1)])
    shares /= np.maximum(shares.sum(axis=0), 1e-300)
    return shares, [s.name for s in gm.subsystems]


def _mesh_energy(gm, model, lm, x0) -> np.ndarray:
    """(n_meshes, n_modes): strain-energy share k'_mesh (c . phi)^2 / (phi^T K_t phi) of
    each mesh (k': its tangent stiffness at the static state, 0 in the backlash) in the
    undamped elastic mode nearest in frequency to each damped mode (rigid undamped modes,
    whose strain energy is zero, are never the nearest)."""
    from ..solvers.linear import contact_slopes

    idx = gm.contact_indices("mesh")
    if idx.size == 0:
        return np.zeros((0, lm.frequency.size))
    d = model.contacts.directions[idx]
    k = contact_slopes(model, x0[:model.n_modes])[0][idx][:, None]
    fu = lm.undamped
    elastic = fu > RIGID_TOL * max(float(fu.max(initial=0.0)), 1e-300)
    phi = lm.undamped_vectors[:, elastic]
    w2 = (2 * np.pi * fu[elastic]) ** 2
    share = k * (d @ phi) ** 2 / (w2 * np.sum(phi ** 2, axis=0))
    if not np.any(elastic):
        return np.zeros((idx.size, lm.frequency.size))
    nearest = np.abs(lm.frequency[:, None] - fu[elastic][None, :]).argmin(axis=1)
    return share[:, nearest]


def mesh_orders_per_rpm(gearbox) -> list[tuple[str, float]]:
    """(mesh name, mesh frequency per driving-shaft rpm [Hz/rpm]) of every mesh of a
    ``[gearbox]`` config: teeth x |spin of gear_a| / 60, the gears' spins from the speed
    ratios of the fixed-gear chain (a free gear takes its fixed partner's)."""
    _, gear_p = gearbox.speed_ratios()
    out = []
    for m in gearbox.meshes:
        a = gearbox.gear_index(m.gear_a, "")
        out.append((m.name, abs(gear_p[a]) * gearbox.gears[a].teeth / 60.0))
    return out


def resonance_crossings(f_hz, share, orders, rpm_lo, rpm_hi, *, threshold: float = 0.05,
                        harmonics=(1, 2)) -> list[dict]:
    """The resonance speeds: where an order h x f_mesh of a mesh (``orders``: [(mesh name,
    Hz per rpm)]) meets a mode whose largest mesh strain-energy share ``share`` exceeds
    ``threshold``, inside [rpm_lo, rpm_hi]; sorted by speed."""
    out = []
    for i in np.flatnonzero(np.asarray(share) > threshold):
        for name, per_rpm in orders:
            for h in harmonics:
                rpm = float(f_hz[i]) / (h * per_rpm)
                if rpm_lo <= rpm <= rpm_hi:
                    out.append({"mode": int(i), "frequency_hz": float(f_hz[i]), "mesh": name,
                                "mesh_order": h, "rpm": rpm,
                                "mesh_energy_share": float(share[i])})
    return sorted(out, key=lambda c: c["rpm"])
