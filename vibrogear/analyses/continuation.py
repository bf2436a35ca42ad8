"""Shooting + pseudo-arclength continuation of periodic orbits over the study's parameter,
with Floquet stability and LP / PD / NS points (paper Figs 4-8), for any study.

The starting orbit at the range's start end (:func:`starting_orbit`): ``transient_periods``
excitation periods from the static equilibrium settle the motion; the sweep's period
detection (:func:`~vibrogear.solvers.sweep.classify_period` on ``RECORD_PERIODS``
stroboscopic states) gives its period n (a rattle cycle of a free gear spans n mesh
periods), and shooting over n periods converges onto it.  Where the settled motion is not
periodic (chaotic rattle) or that shooting fails, the period-1 orbit that continues the
static equilibrium is shot from the equilibrium itself: it exists, unstable, inside the
rattle windows, and its branch shows where stability is lost (PD / NS / LP).  For a dimensional
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
from ..solvers.shooting import shoot
from ..solvers.sweep import classify_period
from .study import Study, integration_options

__all__ = ["ContinuationStudyResult", "run", "starting_orbit"]

#: stroboscopic periods recorded after the transient to detect the period of the start
RECORD_PERIODS = 24


@dataclass(frozen=True, eq=False)
class ContinuationStudyResult:
    result: ContinuationResult
    study: Study

    @property
    def branches(self) -> tuple:
        return self.result.branches


def starting_orbit(model, p0: float, u_static, *, transient_periods: int, options, tol: float,
                   max_iter: int, max_period: int = 8, period_tol: float = 1e-4):
    """(u0, n_periods, guess, how): a converged periodic orbit at ``p0`` to start from (see
    the module docstring), the state Newton started from, and ``how``, which start worked.
    u0 is None when none did."""
    T = model.excitation_period(p0)
    warm = integrate(model, p0, u_static, 0.0, max(int(transient_periods), 1) * T,
                     options=options)
    tried = []
    if warm.ok:
        R = max(RECORD_PERIODS, 2 * int(max_period) + 1)
        rec = integrate(model, p0, warm.u_end, 0.0, R * T, t_eval=np.arange(R + 1) * T,
                        options=options)
        n, _ = (classify_period(rec.u, max_period, period_tol, split=model.n_modes)
                if rec.ok else (0, np.nan))
        if not n:
            tried.append("settled motion not classified periodic")
        for k in dict.fromkeys((n, 1)):
            if k >= 1:
                sh = shoot(model, p0, warm.u_end, n_periods=k, options=options, tol=tol,
                           max_iter=max_iter)
                if sh.converged:
                    note = f" ({'; '.join(tried)})" if tried else ""
                    return sh.u0, k, warm.u_end, f"period-{k} orbit from the settled motion{note}"
                tried.append(f"period-{k} from the settled motion: {sh.message}")
    else:
        tried.append(f"transient: {warm.message}")
    sh = shoot(model, p0, u_static, options=options, tol=tol, max_iter=max_iter)
    if sh.converged:
        note = "; ".join(tried)
        return sh.u0, 1, u_static, f"period-1 orbit from the static equilibrium ({note})"
    tried.append(f"from the static equilibrium: {sh.message}")
    return None, 1, u_static, "; ".join(tried)


def run(study: Study, scene, ctx: RunContext) -> AnalysisOutcome:
    cfg = scene.continuation
    model = study.model
    opts = integration_options(scene)
    options = cfg.options()
    lo, hi = options.param_min, options.param_max
    p0 = hi if cfg.start == "max" else lo
    t0 = time.perf_counter()
    sw = getattr(scene, "sweep", None)
    u0, n_periods, guess, how = starting_orbit(
        model, p0, study.start(p0), transient_periods=cfg.transient_periods, options=opts,
        tol=scene.shooting.tol, max_iter=3 * options.max_corrector_iter,
        max_period=getattr(sw, "max_period", 8), period_tol=getattr(sw, "period_tol", 1e-4))
    if u0 is None:
        raise NumericalFailure(f"continuation: no starting orbit at {study.param_name} = "
                               f"{p0:g}: {how}")
    scale = 1.0
    if study.balance_arclength:
        # the size of the state Newton started from (the settled motion, or the static
        # equilibrium): it sets the arclength metric
        scale = (hi - lo) / max(float(np.linalg.norm(guess)), 1e-300)
    problem = PeriodicOrbitProblem(model, u0, p0, n_periods=n_periods,
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
        "start": {study.param_name: p0, "n_periods": n_periods, "how": how},
        "branches": [{"n_periods": b.n_periods, "points": len(b.points),
                      "neutral_points": sum(1 for p in b.points if p.neutral),
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
