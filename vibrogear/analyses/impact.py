"""Runner glue for impact-pair scenes: build the model, call the solvers, write files."""
from __future__ import annotations

import time

import numpy as np

from ..models.impact_pair import impact_pair_from_config
from ..pipeline.outcome import NumericalFailure, RunContext
from ..solvers.continuation import ContinuationOptions, continue_orbits
from ..solvers.integrate import IntegrationOptions, integrate
from ..solvers.static import static_equilibrium
from ..solvers.sweep import sweep

__all__ = ["run_time_response", "run_sweep", "run_continuation", "integration_options",
           "jumps"]


def integration_options(scene) -> IntegrationOptions:
    c = scene.integration
    return IntegrationOptions(rtol=c.rtol, atol=c.atol, max_steps=c.max_steps,
                              max_events_per_step=c.max_events_per_step)


def _start_state(model) -> np.ndarray:
    st = static_equilibrium(model)
    return st.u0 if st.converged else np.zeros(model.n_states)


def _title(scene) -> str:
    c = scene.impact_pair
    return (f"{scene.scene.name}: zeta={c.zeta:g}, kappa={c.kappa:g}, f_m={c.f_m:g}, "
            f"f_p={c.f_p:g}, b_r={c.b_r:g}")


# ------------------------------------------------------------------ time response

def run_time_response(scene, ctx: RunContext) -> dict:
    from ..report.time_plots import plot_time_response, write_time_response

    cfg = scene.time_response
    model = impact_pair_from_config(scene.impact_pair)
    T = model.excitation_period(cfg.omega)
    t1 = cfg.periods * T
    n = int(round(cfg.periods * cfg.samples_per_period))
    t_eval = np.linspace(0.0, t1, n + 1)
    u0 = _start_state(model)
    tr = integrate(model, cfg.omega, u0, 0.0, t1, t_eval=t_eval, options=integration_options(scene))
    if not tr.ok:
        raise NumericalFailure(f"time response at Omega = {cfg.omega:g}: {tr.message}")
    write_time_response(ctx.out, tr.t, tr.u, model.state_names)
    plot_time_response(ctx.out / "time_response", tr.t, tr.u[:, 0], tr.u[:, 1],
                       period=T, bounds=(-scene.impact_pair.b_r, scene.impact_pair.b_r),
                       title=_title(scene) + f", Omega={cfg.omega:g}")
    return {"status": "ok", "omega": cfg.omega, "periods": cfg.periods, "steps": tr.steps,
            "rejected": tr.rejected, "rhs_calls": tr.rhs_calls, "events": tr.events,
            "integrator_wall_s": tr.wall_time, "q_min": tr.monitor_min, "q_max": tr.monitor_max,
            "error_estimate": {"rtol": scene.integration.rtol, "atol": scene.integration.atol}}


# ------------------------------------------------------------------ sweep

def jumps(param, q, rel: float = 0.15) -> list[float]:
    """Midpoints between successive sweep points whose q differs by > rel * range."""
    q = np.asarray(q, float)
    ok = np.isfinite(q)
    span = np.ptp(q[ok]) if np.any(ok) else 0.0
    out = []
    for k in range(1, len(q)):
        if ok[k] and ok[k - 1] and abs(q[k] - q[k - 1]) > rel * span > 0:
            out.append(0.5 * (param[k] + param[k - 1]))
    return out


def run_sweep(scene, ctx: RunContext) -> dict:
    from ..pipeline.executors import is_root
    from ..report.sweep_io import (NOT_IN_SIGNATURE, PartialWriter, read_partial, read_sweep_npz,
                                   sweep_arrays, sweep_signature, write_sweep)
    from ..report.sweep_plots import plot_bifurcation

    cfg = scene.sweep
    model = impact_pair_from_config(scene.impact_pair)
    params = np.linspace(cfg.omega_min, cfg.omega_max, cfg.n_points)
    opts = integration_options(scene)
    settings = [(k, v) for k, v in cfg.__dict__.items() if k not in NOT_IN_SIGNATURE]
    sig = sweep_signature(model, params, impact_pair=list(scene.impact_pair.__dict__.items()),
                          sweep=settings, rtol=opts.rtol, atol=opts.atol)
    partial = ctx.out / "sweep.partial.jsonl"
    root = is_root()                     # under mpirun only rank 0 touches files
    try:
        done = read_partial(partial, sig) if root else {}
    except ValueError:
        partial.unlink()
        done = {}
    writer = PartialWriter(partial, sig) if root else None
    total = len(cfg.directions) * params.size
    with ctx.progress(total, "sweep") as bar:
        bar.update(len(done))

        def on_point(rec):
            writer(rec)
            bar.update(1, f"{model.param_name}={rec.param:.4g} P{rec.period_n}")

        res = sweep(model, params, directions=cfg.directions,
                    transient_periods=cfg.transient_periods, record_periods=cfg.record_periods,
                    extra_transient_periods=cfg.extra_transient_periods,
                    max_period=cfg.max_period, period_tol=cfg.period_tol, options=opts,
                    u0=_start_state(model), callback=on_point, done=done,
                    segments=cfg.segments, workers=cfg.workers)
    if root:
        write_sweep(res, ctx.out)
        data = read_sweep_npz(ctx.out / "sweep.npz")
        b = scene.impact_pair.b_r
        plot_bifurcation(data, ctx.out / "bifurcation", param_label="Omega",
                         deformation_label="q", zero_line=False, bounds=(-b, b),
                         title=_title(scene))
        writer.remove()
    else:
        data = sweep_arrays(res)
    ctx.results["sweep"] = data
    if "branch" in ctx.results:
        _overlay(scene, ctx)
    up = res.direction == "up"
    classes = {str(int(k)): int(np.sum(res.period_n == k)) for k in np.unique(res.period_n)}
    return {
        "status": "ok" if res.status_code == 0 else "partial",
        "message": res.status_message, "points": int(res.param.size),
        "resumed_points": len(done), "failed_points": int(np.sum(res.status != 0)),
        "period_classes": classes, "steps": res.steps, "rhs_calls": res.rhs_calls,
        "events": res.events, "solver_wall_s": res.wall_time,
        "jumps_up": jumps(res.param[up], res.qmax[up]),
        "jumps_down": jumps(res.param[~up], res.qmax[~up]),
        "error_estimate": res.error_estimate,
    }


# ------------------------------------------------------------------ continuation

def _liouville_error(scene, arrays) -> float | None:
    """|prod mu - exp(-2 zeta T)| / exp(-2 zeta T): det M is exact when the trace of the
    Jacobian is -2 zeta everywhere (no contact damping)."""
    c = scene.impact_pair
    if c.contact_damping != 0.0 or arrays["param"].size == 0:
        return None
    prod = np.prod(arrays["floquet"], axis=1).real
    ref = np.exp(-2.0 * c.zeta * arrays["period"])
    return float(np.max(np.abs(prod - ref) / ref))


def run_continuation(scene, ctx: RunContext) -> dict:
    from ..report.branch_io import branch_arrays, write_branches

    cfg = scene.continuation
    model = impact_pair_from_config(scene.impact_pair)
    opts = integration_options(scene)
    p0 = cfg.omega_max if cfg.start == "max" else cfg.omega_min
    direction = -1 if cfg.start == "max" else 1
    t0 = time.perf_counter()
    warm = integrate(model, p0, _start_state(model), 0.0,
                     max(cfg.transient_periods, 1) * model.excitation_period(p0), options=opts)
    if not warm.ok:
        raise NumericalFailure(f"continuation start at Omega = {p0:g}: {warm.message}")
    copts = ContinuationOptions(param_min=cfg.omega_min, param_max=cfg.omega_max, ds=cfg.ds,
                                ds_min=cfg.ds_min, ds_max=cfg.ds_max, max_points=cfg.max_points,
                                max_corrector_iter=cfg.max_corrector_iter, tol=scene.shooting.tol,
                                period_doubling_branch=cfg.period_doubling_branch)
    with ctx.progress(cfg.max_points, "continuation") as bar:
        branches = continue_orbits(model, warm.u_end, p0, copts, direction=direction,
                                   integration=opts,
                                   callback=lambda p: bar.update(1, f"Omega={p.param:.4g}"))
    wall = time.perf_counter() - t0
    if not branches[0].points:
        raise NumericalFailure(f"continuation: {branches[0].message}")
    write_branches(branches, model.omega_per_param, ctx.out)
    arrays = branch_arrays(branches, model.omega_per_param)
    ctx.results["branch"] = arrays
    _plot_branches(scene, ctx, arrays, ctx.results.get("sweep"))
    special = [{"label": str(lab), "param": float(p), "branch": int(b), "qmax": float(q)}
               for lab, p, b, q in zip(arrays["label"], arrays["param"], arrays["branch"],
                                       arrays["qmax"]) if lab]
    return {
        "status": "ok",
        "branches": [{"n_periods": b.n_periods, "points": len(b.points), "status": b.status,
                      "message": b.message, **b.counters, "wall_s": b.wall_time}
                     for b in branches],
        "special_points": special,
        "folds": [s["param"] for s in special if s["label"] == "LP" and s["branch"] == 0],
        "solver_wall_s": wall,
        "error_estimate": {"max_periodicity_residual": float(np.max(arrays["residual"])),
                           "shooting_tol": scene.shooting.tol, "rtol": opts.rtol,
                           "liouville_det_error": _liouville_error(scene, arrays)},
    }


def _plot_branches(scene, ctx, arrays, sweep_data) -> None:
    from ..report.branch_plots import plot_branches

    b = scene.impact_pair.b_r
    title = _title(scene)
    plot_branches(arrays, ctx.out / "branch_amplitude", quantity="qmax", ylabel="max q",
                  title=title, sweep=sweep_data, bounds=(b,))
    plot_branches(arrays, ctx.out / "branch_minima", quantity="qmin", ylabel="min q",
                  title=title, sweep=sweep_data, bounds=(-b, b))


def _overlay(scene, ctx) -> None:
    _plot_branches(scene, ctx, ctx.results["branch"], ctx.results["sweep"])
