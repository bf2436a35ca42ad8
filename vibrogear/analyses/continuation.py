"""Shooting + pseudo-arclength continuation of periodic orbits over the study's parameter,
with Floquet stability and LP / PD / NS points (paper Figs 4-8), for any study.

The starting orbit is found from the static equilibrium at the range's start end by
``transient_periods`` excitation periods of integration, then shooting.  For a dimensional
model (gearbox: states ~1e-5 m, speeds ~1e3 rpm) the arclength is measured in parameter
units: the parameter is scaled by range / |u|, so ``ds``, ``ds_min``, ``ds_max`` are given in
the scene's parameter unit (:class:`~vibrogear.config.options.ContinuationSteps`).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ..solvers.continuation import (ContinuationResult, PeriodicOrbitProblem, PseudoArclength,
                                    continuation)
from ..solvers.integrate import integrate
from .study import Study, integration_options

__all__ = ["ContinuationStudyResult", "run"]


@dataclass(frozen=True, eq=False)
class ContinuationStudyResult:
    result: ContinuationResult
    study: Study

    @property
    def branches(self) -> tuple:
        return self.result.branches


def run(study: Study, scene, ctx: RunContext) -> AnalysisOutcome:
    cfg = scene.continuation
    model = study.model
    opts = integration_options(scene)
    options = cfg.options()
    lo, hi = options.param_min, options.param_max
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
    problem = PeriodicOrbitProblem(model, warm.u_end, p0,
                                   direction=-1 if cfg.start == "max" else 1)
    method = PseudoArclength(integration=opts, tol=scene.shooting.tol, param_scale=scale)
    with ctx.progress(options.max_points, "continuation") as bar:
        res = continuation(problem, method, options,
                           callback=lambda p: bar.update(1, f"{p.param:.4g} {study.param_unit}"))
    wall = time.perf_counter() - t0
    branches = res.branches
    if not branches[0].points:
        raise NumericalFailure(f"continuation: {res.message}")
    special = [{"label": s.label, study.param_name: float(s.param), "branch": s.branch,
                "qmax": float(branches[s.branch].points[s.index].qmax)}
               for s in res.special_points]
    summary = {
        "status": "ok",
        "message": res.message,
        "branches": [{"n_periods": b.n_periods, "points": len(b.points),
                      "status": b.status.text, "message": b.message, **b.counters,
                      "wall_s": b.wall_time}
                     for b in branches],
        "special_points": special,
        "folds": [s[study.param_name] for s in special if s["label"] == "LP" and s["branch"] == 0],
        "counters": res.counters,
        "solver_wall_s": wall,
        "error_estimate": {**res.error_estimate, "shooting_tol": scene.shooting.tol,
                           "rtol": opts.rtol},
    }
    return AnalysisOutcome(summary=summary, result=ContinuationStudyResult(res, study))
