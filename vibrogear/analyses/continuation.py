"""Shooting + pseudo-arclength continuation of periodic orbits over the study's parameter,
with Floquet stability and LP / PD / NS points (paper Figs 4-8), for any study.

The starting orbit is found from the static equilibrium at the range's start end by
``transient_periods`` excitation periods of integration, then shooting.  For a dimensional
model (gearbox: states ~1e-5 m, speeds ~1e3 rpm) the arclength is measured in parameter
units: the parameter is scaled by range / |u|, so ``ds``, ``ds_min``, ``ds_max`` are given in
the scene's parameter unit.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ..solvers.continuation import ContinuationOptions, continue_orbits
from ..solvers.integrate import integrate
from .study import Study, integration_options
from .sweep import param_range

__all__ = ["ContinuationStudyResult", "run", "liouville_error"]


@dataclass(frozen=True, eq=False)
class ContinuationStudyResult:
    branches: tuple
    study: Study


def liouville_error(model, branches) -> float | None:
    """max |prod mu - exp(tr J T)| / exp(tr J T) over the branch points: Liouville's formula
    det M = exp(integral of tr J), exact when the trace of the Jacobian is constant along
    the orbit, i.e. when no contact has damping (the trace is then -sum of the modal damping
    - tr(P^T Bc(s) P)).  None where a contact is damped."""
    if np.any(model.contacts.damping != 0.0):
        return None
    cp = model.coupling
    worst = None
    for br in branches:
        for p in br.points:
            s = model.spin_per_param * p.param
            tr = -float(np.sum(model.damping))
            if cp.P.shape[0]:
                tr -= float(np.trace(cp.P.T @ (cp.Bc0 + s * cp.Bc1) @ cp.P))
            T = br.n_periods * model.excitation_period(p.param)
            ref = np.exp(tr * T)
            err = abs(float(np.prod(p.floquet).real) - ref) / ref
            worst = err if worst is None else max(worst, err)
    return worst


def run(study: Study, scene, ctx: RunContext) -> AnalysisOutcome:
    cfg = scene.continuation
    model = study.model
    opts = integration_options(scene)
    lo, hi = param_range(cfg)
    p0 = hi if cfg.start == "max" else lo
    t0 = time.perf_counter()
    warm = integrate(model, p0, study.start(p0), 0.0,
                     max(cfg.transient_periods, 1) * model.excitation_period(p0), options=opts)
    if not warm.ok:
        raise NumericalFailure(f"continuation start at {study.param_name} = {p0:g}: "
                               f"{warm.message}")
    scale = 1.0
    if study.balance_arclength:
        scale = (hi - lo) / max(float(np.linalg.norm(warm.u_end)), 1e-300)
    copts = ContinuationOptions(param_min=lo, param_max=hi, ds=cfg.ds / scale,
                                ds_min=cfg.ds_min / scale, ds_max=cfg.ds_max / scale,
                                max_points=cfg.max_points,
                                max_corrector_iter=cfg.max_corrector_iter, tol=scene.shooting.tol,
                                period_doubling_branch=cfg.period_doubling_branch,
                                param_scale=scale)
    with ctx.progress(cfg.max_points, "continuation") as bar:
        branches = continue_orbits(
            model, warm.u_end, p0, copts, direction=-1 if cfg.start == "max" else 1,
            integration=opts,
            callback=lambda p: bar.update(1, f"{p.param:.4g} {study.param_unit}"))
    wall = time.perf_counter() - t0
    if not branches[0].points:
        raise NumericalFailure(f"continuation: {branches[0].message}")
    special = [{"label": p.label, study.param_name: float(p.param), "branch": b,
                "qmax": float(p.qmax)}
               for b, br in enumerate(branches) for p in br.points if p.label]
    residuals = [p.residual for br in branches for p in br.points]
    summary = {
        "status": "ok",
        "branches": [{"n_periods": b.n_periods, "points": len(b.points), "status": b.status,
                      "message": b.message, **b.counters, "wall_s": b.wall_time}
                     for b in branches],
        "special_points": special,
        "folds": [s[study.param_name] for s in special if s["label"] == "LP" and s["branch"] == 0],
        "solver_wall_s": wall,
        "error_estimate": {"max_periodicity_residual": float(np.max(residuals)),
                           "shooting_tol": scene.shooting.tol, "rtol": opts.rtol,
                           "liouville_det_error": liouville_error(model, branches)},
    }
    return AnalysisOutcome(summary=summary,
                           result=ContinuationStudyResult(tuple(branches), study))
