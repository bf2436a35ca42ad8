"""Runner glue for gearbox scenes: modes, time response, speed sweep, orbit continuation.

The scene's parameter is the driving-shaft speed in rpm; the excitation period is the mesh
period of ``meshes[0]``; the monitored quantity is that mesh's deformation (m).  The model
is built once per run (shared by the analyses through ``ctx.results``) and every analysis
starts from the static equilibrium at its speed (paper eq. (9)).
"""
from __future__ import annotations

import time

import numpy as np

from ..pipeline.outcome import NumericalFailure, RunContext
from .impact import integration_options, jumps

__all__ = ["gearbox_model", "start_state", "run_modes", "run_time_response", "run_sweep",
           "run_continuation", "reference_rpm"]

_MODEL = "_gearbox_model"


def gearbox_model(scene, ctx: RunContext):
    """The scene's GearboxModel, built on first use and shared by the analyses."""
    from ..models.gearbox import build_gearbox

    gm = ctx.results.get(_MODEL)
    if gm is None:
        gm = ctx.results[_MODEL] = build_gearbox(scene)
    return gm


def start_state(gm, rpm: float) -> np.ndarray:
    from ..solvers.static import static_equilibrium

    st = static_equilibrium(gm.reduced, rpm)
    if not st.converged:
        raise NumericalFailure(f"static equilibrium at {rpm:g} rpm: {st.message} "
                               f"(residual {st.residual:.3g} after {st.iterations} iterations)")
    return st.u0


def reference_rpm(scene) -> float:
    if scene.time_response is not None:
        return scene.time_response.omega
    for sec in (scene.sweep, scene.continuation):
        if sec is not None:
            return 0.5 * (sec.omega_min + sec.omega_max)
    return 0.0


def _title(scene, gm) -> str:
    m = gm.reduced.n_modes
    parts = "+".join(str(s.n_modes) for s in gm.subsystems)
    return f"{scene.scene.name}: m = {m} ({parts})"


def _monitor_backlash(scene) -> float:
    return scene.gearbox.meshes[0].backlash if scene.gearbox.meshes else 0.0


# ------------------------------------------------------------------ modes

def run_modes(scene, ctx: RunContext) -> dict:
    from ..report.gearbox_plots import plot_resonance_map, write_modes_csv
    from ..solvers.linear import linear_modes

    gm = gearbox_model(scene, ctx)
    rpm = reference_rpm(scene)
    u0 = start_state(gm, rpm)
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
                       title=_title(scene, gm) + f", linearised at {rpm:g} rpm")
    return {"status": "ok", "rpm": rpm, "modes": int(f_hz.size),
            "first_frequencies_hz": [float(f) for f in f_hz[:12]],
            "resonance_speeds_rpm": crit, "wall_s": wall,
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


# ------------------------------------------------------------------ time response

def run_time_response(scene, ctx: RunContext) -> dict:
    from ..report.gearbox_plots import plot_gearbox_time_response, write_contact_history
    from ..solvers.contact_eval import contact_history
    from ..solvers.integrate import integrate

    cfg = scene.time_response
    gm = gearbox_model(scene, ctx)
    r, rpm = gm.reduced, cfg.omega
    T = r.excitation_period(rpm)
    n = int(round(cfg.periods * cfg.samples_per_period))
    t_eval = np.linspace(0.0, cfg.periods * T, n + 1)
    tr = integrate(r, rpm, start_state(gm, rpm), 0.0, cfg.periods * T, t_eval=t_eval,
                   options=integration_options(scene))
    if not tr.ok:
        raise NumericalFailure(f"time response at {rpm:g} rpm: {tr.message}")
    delta, ddot, force = contact_history(r, rpm, tr.t, tr.u)
    force = force * gm.omega_ref ** 2                       # model units -> N
    ddot = ddot * gm.omega_ref                              # per model time -> m/s
    t_s = tr.t / gm.omega_ref
    names = [c.name for c in gm.contacts]
    write_contact_history(ctx.out, t_s, delta, ddot, force, names)
    mesh = gm.contact_indices("mesh")
    groups = _bearing_groups(gm)
    plot_gearbox_time_response(ctx.out / "time_response", t_s, delta[mesh], ddot[mesh],
                               force[mesh], [names[j] for j in mesh],
                               {g: force[idx].sum(axis=0) for g, idx in groups.items()},
                               mesh_period_s=T / gm.omega_ref,
                               backlash=[gm.contacts[j].gap_lo for j in mesh],
                               title=_title(scene, gm) + f", {rpm:g} rpm")
    half = tr.t >= 0.5 * tr.t[-1]
    losses = {names[j]: int(np.sum(np.diff((delta[j, half] > 0).astype(int)) < 0))
              for j in mesh}
    return {"status": "ok", "rpm": rpm, "mesh_periods": cfg.periods,
            "mesh_frequency_hz": gm.mesh_frequency_hz(rpm), "steps": tr.steps,
            "rejected": tr.rejected, "rhs_calls": tr.rhs_calls, "events": tr.events,
            "integrator_wall_s": tr.wall_time,
            "mesh_deformation_m": {names[j]: [float(delta[j, half].min()),
                                              float(delta[j, half].max())] for j in mesh},
            "contact_losses_second_half": losses,
            "error_estimate": {"rtol": scene.integration.rtol, "atol": scene.integration.atol}}


def _bearing_groups(gm) -> dict:
    groups: dict[str, list[int]] = {}
    for j, c in enumerate(gm.contacts):
        if c.kind == "bearing":
            groups.setdefault(c.group, []).append(j)
    return {g: np.array(v) for g, v in groups.items()}


# ------------------------------------------------------------------ sweep

def run_sweep(scene, ctx: RunContext) -> dict:
    from ..pipeline.executors import is_root
    from ..report.sweep_io import read_sweep_npz, resumable_sweep, sweep_arrays
    from ..report.sweep_plots import plot_bifurcation

    cfg = scene.sweep
    gm = gearbox_model(scene, ctx)
    params = np.linspace(cfg.omega_min, cfg.omega_max, cfg.n_points)
    u0 = start_state(gm, params[0])
    total = len(cfg.directions) * params.size
    with ctx.progress(total, "sweep") as bar:
        res, paths = resumable_sweep(
            gm.reduced, params, ctx.out,
            callback=lambda rec: bar.update(1, f"{rec.param:.0f} rpm P{rec.period_n}"),
            directions=cfg.directions, transient_periods=cfg.transient_periods,
            record_periods=cfg.record_periods,
            extra_transient_periods=cfg.extra_transient_periods, max_period=cfg.max_period,
            period_tol=cfg.period_tol, options=integration_options(scene), u0=u0,
            segments=cfg.segments, workers=cfg.workers)
    data = read_sweep_npz(paths["npz"]) if is_root() else sweep_arrays(res)
    if is_root():
        um = dict(data)                               # the figure in micrometres
        for key in ("qmin", "qmax", "poincare"):
            um[key] = np.asarray(data[key], dtype=float) * 1e6
        back = -_monitor_backlash(scene) * 1e6
        near = np.nanmin(um["qmin"], initial=0.0) < 0.5 * back
        plot_bifurcation(um, ctx.out / "bifurcation", param_label="driving speed [rpm]",
                         deformation_label=f"{gm.contacts[0].name} mesh deformation [um]",
                         zero_line=True, bounds=(back,) if near else (),
                         title=_title(scene, gm) + ": below 0 the mesh is interrupted")
    ctx.results["sweep"] = data
    up = res.direction == "up"
    classes = {str(int(k)): int(np.sum(res.period_n == k)) for k in np.unique(res.period_n)}
    return {"status": "ok" if res.status_code == 0 else "partial",
            "message": res.status_message, "points": int(res.param.size),
            "failed_points": int(np.sum(res.status != 0)), "period_classes": classes,
            "points_with_mesh_interruption": int(np.sum(res.impacts > 0)),
            "steps": res.steps, "rhs_calls": res.rhs_calls, "events": res.events,
            "solver_wall_s": res.wall_time,
            "jumps_up_rpm": jumps(res.param[up], res.qmax[up]),
            "jumps_down_rpm": jumps(res.param[~up], res.qmax[~up]),
            "error_estimate": res.error_estimate}


# ------------------------------------------------------------------ continuation

def run_continuation(scene, ctx: RunContext) -> dict:
    from ..report.branch_io import branch_arrays, write_branches
    from ..solvers.continuation import ContinuationOptions, continue_orbits
    from ..solvers.integrate import integrate

    cfg = scene.continuation
    gm = gearbox_model(scene, ctx)
    r = gm.reduced
    opts = integration_options(scene)
    p0 = cfg.omega_max if cfg.start == "max" else cfg.omega_min
    t0 = time.perf_counter()
    warm = integrate(r, p0, start_state(gm, p0), 0.0,
                     max(cfg.transient_periods, 1) * r.excitation_period(p0), options=opts)
    if not warm.ok:
        raise NumericalFailure(f"continuation start at {p0:g} rpm: {warm.message}")
    # arclength in rpm-equivalents: the state (~1e-5) and the speed (~1e3 rpm) are balanced
    # by scaling the speed with range / |u|; ds, ds_min, ds_max are given in rpm
    scale = (cfg.omega_max - cfg.omega_min) / max(float(np.linalg.norm(warm.u_end)), 1e-300)
    copts = ContinuationOptions(param_min=cfg.omega_min, param_max=cfg.omega_max,
                                ds=cfg.ds / scale, ds_min=cfg.ds_min / scale,
                                ds_max=cfg.ds_max / scale, max_points=cfg.max_points,
                                max_corrector_iter=cfg.max_corrector_iter, tol=scene.shooting.tol,
                                period_doubling_branch=cfg.period_doubling_branch,
                                param_scale=scale)
    with ctx.progress(cfg.max_points, "continuation") as bar:
        branches = continue_orbits(r, warm.u_end, p0, copts,
                                   direction=-1 if cfg.start == "max" else 1, integration=opts,
                                   callback=lambda p: bar.update(1, f"{p.param:.0f} rpm"))
    wall = time.perf_counter() - t0
    if not branches[0].points:
        raise NumericalFailure(f"continuation: {branches[0].message}")
    write_branches(branches, r.omega_per_param, ctx.out)
    arrays = branch_arrays(branches, r.omega_per_param)
    ctx.results["branch"] = arrays
    _plot_branches(scene, gm, ctx, arrays)
    special = [{"label": str(lab), "rpm": float(p), "branch": int(bb)}
               for lab, p, bb in zip(arrays["label"], arrays["param"], arrays["branch"]) if lab]
    return {"status": "ok",
            "branches": [{"n_periods": br.n_periods, "points": len(br.points),
                          "status": br.status, "message": br.message, **br.counters,
                          "wall_s": br.wall_time} for br in branches],
            "special_points": special, "solver_wall_s": wall,
            "error_estimate": {"max_periodicity_residual": float(np.max(arrays["residual"])),
                               "shooting_tol": scene.shooting.tol, "rtol": opts.rtol}}


def _um(data: dict | None, keys) -> dict | None:
    if data is None:
        return None
    out = dict(data)
    for k in keys:
        out[k] = np.asarray(data[k], dtype=float) * 1e6
    return out


def _plot_branches(scene, gm, ctx, arrays) -> None:
    """Branch figures in micrometres with the sweep overlaid (the back-flank line only when
    the branch reaches it)."""
    from ..report.branch_plots import plot_branches

    br = _um(arrays, ("qmin", "qmax"))
    sw = _um(ctx.results.get("sweep"), ("qmin", "qmax", "poincare"))
    back = -_monitor_backlash(scene) * 1e6
    near = np.nanmin(br["qmin"], initial=0.0) < 0.5 * back
    for q, lab in (("qmax", "max"), ("qmin", "min")):
        plot_branches(br, ctx.out / f"branch_{lab}", quantity=q,
                      ylabel=f"{lab} {gm.contacts[0].name} mesh deformation [um]",
                      xlabel="driving speed [rpm]", title=_title(scene, gm), sweep=sw,
                      bounds=(0.0, back) if near else (0.0,))
