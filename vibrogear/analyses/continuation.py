"""Shooting + pseudo-arclength continuation of periodic orbits over the study's parameter,
with Floquet stability and LP / PD / NS points (paper Figs 4-8), for any study.

The starting orbit at the range's start end (:func:`starting_orbit`): ``transient_periods``
excitation periods from the static equilibrium settle the motion; the sweep's period
detection (:func:`~vibrogear.solvers.sequential.sweep.classify_period` on ``RECORD_PERIODS``
stroboscopic states) gives its period n (a rattle cycle of a free gear spans n mesh
periods), and shooting over n periods converges onto it.  Where that shooting fails, or
the settled motion is not periodic (chaotic rattle: then before a period-1 Newton from the
settled motion), the period-1 orbit that continues the static equilibrium is shot from the
equilibrium itself: it exists, unstable, inside the rattle windows, and its branch shows
where stability is lost (PD / NS / LP).  For a dimensional
model (gearbox: states ~1e-5 m, speeds ~1e3 rpm) the arclength is measured in parameter
units: the parameter is scaled by range / |u|, so ``ds``, ``ds_min``, ``ds_max`` are given in
the scene's parameter unit (:class:`~vibrogear.config.options.ContinuationSteps`).

With ``from_sweep`` also a branch both ways from each distinct period-n window of the sweep
(this run's sweep outcome, or an earlier run's ``sweep.npz`` in the output folder, which the
runner loads: ``previous["sweep"]``), each half ending with its reason
(:mod:`.sweep.branches`).

The summary's status is ``ok`` only where every branch ended for a reason that belongs to
the branch (it left the range, rejoined the period-1 branch, or reached a grazing orbit);
a branch that stopped on the method (a step below ``ds_min``, the point limit, a failed
switch) makes it ``partial``, and ``coverage`` says which branches ended where and which
share of the parameter range the branches cover (:func:`coverage`).
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from ..pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ..status import Status
from ..solvers.periodic.continuation import (ContinuationResult, PeriodicOrbitProblem, PseudoArclength,
                                    SpecialPoint, continuation)
from ..solvers.integrator.integrate import integrate
from ..solvers.periodic.shooting import shoot
from ..solvers.periodic.starting_orbit import starting_orbit
from .study import Study, integration_options
from ..config.options import ShootingOptions

__all__ = ["ContinuationStudyResult", "run", "starting_orbit", "coverage"]


@dataclass(frozen=True, eq=False)
class ContinuationStudyResult:
    """A continuation: branches of periodic orbits with their Floquet stability.

    - ``result``: the :class:`~vibrogear.solvers.periodic.branch.ContinuationResult`
      (``help()`` lists its fields and the arrays with shapes and units).
    - ``study``: the :class:`~vibrogear.analyses.study.Study`.
    - ``branches`` (property): ``result.branches``.

    :meth:`arrays`: the arrays of ``branch.npz`` by the same names: per point of all branches
    ``param`` (M,) [rpm or Omega], ``qmin`` / ``qmax`` (M,) [m for a gearbox], ``stable``
    (M,), ``label`` (M,) ("LP", "PD", "NS" or ""), ``branch`` (M,), ``floquet`` (M, n), ...;
    :meth:`plot`: a branch figure."""
    result: ContinuationResult
    study: Study

    @property
    def branches(self) -> tuple:
        return self.result.branches

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays of ``branch.npz``, by the same names (``help(ContinuationResult)``)."""
        return self.result.arrays()

    def plot(self, quantity: str = "qmax", sweep=None):
        """The maxima (``quantity="qmax"``, ``branch_max.png``) or minima (``"qmin"``,
        ``branch_min.png``) of the monitored deformation along the branches as a matplotlib
        Figure (display units; stable solid, unstable dashed, LP / PD / NS marked);
        ``sweep``: a sweep's result (``run.results["sweep"]``) to overlay."""
        from ..report.plots.bifurcation import branch_figure
        return branch_figure(self, quantity, sweep)


def run(study: Study, scene, ctx: RunContext, previous=None) -> AnalysisOutcome:
    cfg = scene.continuation
    model = study.model
    opts = integration_options(scene, section=scene.continuation, study=study)
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
    # a gearbox's special points to 2e-4 of the step (ds <= 60 rpm: 0.012 rpm), each
    # regula-falsi iterate an orbit with the variational equations
    method = PseudoArclength(integration=opts, tol=scene.shooting.tol, param_scale=scale,
                             **({"locate_tol": 2e-4} if study.balance_arclength else {}))
    with ctx.progress(options.max_points, "continuation") as bar:
        res = continuation(problem, method, options,
                           callback=lambda p: bar.update(1, f"{p.param:.4g} {study.param_unit}"))
    if not res.branches[0].points:
        raise NumericalFailure(f"continuation: {res.message}")
    from_sweep = None
    if getattr(cfg, "from_sweep", False):
        res, from_sweep = _from_sweep(study, (previous or {}).get("sweep"), res, method,
                                      options, cfg)
    wall = time.perf_counter() - t0
    branches = res.branches
    special = [{"label": s.label, study.param_name: float(s.param), "branch": s.branch,
                "qmax": float(branches[s.branch].points[s.index].qmax),
                # the parameter interval known to hold the crossing (an NS / PD that changes
                # no stability is located by one regula-falsi orbit only)
                f"located_within_{study.param_name}":
                    float(branches[s.branch].points[s.index].located_within)}
               for s in res.special_points]
    cover = coverage(branches, lo, hi)
    # status, message, counters, wall time, error estimate: the runner's spine from this
    # Outcome (partial where a branch ended for the method's reason before the range's end)
    outcome = dataclasses.replace(res.outcome,
                                  status=Status.PARTIAL if cover["ended_early"] else Status.OK,
                                  message=_coverage_text(cover, study) + res.message,
                                  wall_s=wall)
    summary = {
        "coverage": cover,
        "start": {study.param_name: p0, "n_periods": n_periods, "how": how},
        "branches": [{"n_periods": b.n_periods, "points": len(b.points),
                      "param_range": [float(min(p.param for p in b.points)),
                                      float(max(p.param for p in b.points))]
                      if b.points else None,
                      "neutral_points": sum(1 for p in b.points if p.neutral),
                      "status": b.status.text, "message": b.message, **b.counters,
                      "wall_s": b.wall_time}
                     for b in branches],
        "special_points": special,
        "folds": [s[study.param_name] for s in special if s["label"] == "LP" and s["branch"] == 0],
        **({"from_sweep": from_sweep} if from_sweep is not None else {}),
        "error_estimate": {"shooting_tol": scene.shooting.tol, "rtol": opts.rtol},
    }
    return AnalysisOutcome(summary=summary, result=ContinuationStudyResult(res, study),
                           solver=outcome)


def coverage(branches, lo: float, hi: float) -> dict:
    """How much of [lo, hi] the ``branches`` trace: ``fraction``, the share of the range
    inside at least one branch's parameter interval; ``intervals``, those intervals merged;
    ``ended_early``, the branches whose status is not a success (a step below ``ds_min``,
    the point limit, a stop, a failed switch: the method stopped, not the branch), each
    with its index, period, status and the parameter of its last point (None: no point)."""
    spans = sorted((max(lo, min(p.param for p in b.points)),
                    min(hi, max(p.param for p in b.points))) for b in branches if b.points)
    merged: list[list[float]] = []
    for a, b in spans:
        if b < a:                           # wholly outside the range
            continue
        if merged and a <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    width = hi - lo
    covered = sum(b - a for a, b in merged)
    early = [{"branch": i, "n_periods": b.n_periods, "status": b.status.text,
              "ended_at": float(b.points[-1].param) if b.points else None}
             for i, b in enumerate(branches) if not b.status.success]
    return {"fraction": float(covered / width) if width > 0 else 1.0,
            "range": [float(lo), float(hi)], "intervals": [[float(a), float(b)] for a, b in merged],
            "branches": len(branches), "ended_early": early}


def _coverage_text(cover: dict, study) -> str:
    """Which branches ended early and where, and the share of the range covered, as the
    head of the summary's message ("" when every branch ended by itself over the range)."""
    name, unit = study.param_name, f" {study.param_unit}" if study.param_unit else ""
    lo, hi = cover["range"]
    share = (f"the branches cover {100 * cover['fraction']:.0f} % of {name} = {lo:g}-{hi:g}"
             f"{unit}; ")
    early = cover["ended_early"]
    if not early:
        return share if cover["fraction"] < 0.995 else ""
    how = ", ".join(e["status"] + ("" if e["ended_at"] is None else
                                   f" at {name} = {e['ended_at']:.6g}{unit}") for e in early)
    return (f"{len(early)} of {cover['branches']} branches stopped before the end of the "
            f"range ({how}); " + share)


def _least_period(model, w, method):
    """(u0, n): the orbit shot over the window's n periods from its sweep state, and its
    least period d (the smallest divisor of n with |u(d T) - u0| <= 1e-6 |u0|: shooting
    over n periods also converges onto an orbit of period d | n); (None, n) where it
    fails."""
    sh = shoot(model, w.param, w.u0, n_periods=w.n, options=method.integration, shooting=ShootingOptions(tol=method.tol, max_iter=method.start_max_iter or 24))
    if not sh.converged:
        return None, w.n
    T = model.excitation_period(w.param)
    for d in range(1, w.n):
        if w.n % d == 0:
            tr = integrate(model, w.param, sh.u0, 0.0, d * T, options=method.integration)
            if tr.ok and np.linalg.norm(tr.u_end - sh.u0) <= 1e-6 * np.linalg.norm(sh.u0):
                return sh.u0, d
    return sh.u0, w.n


def _sweep_arrays(result) -> dict:
    """The arrays the windows need, from this run's sweep result or a saved ``sweep.npz``
    (a dict of its arrays, loaded by the runner)."""
    if isinstance(result, dict):
        return result
    sw = getattr(result, "sweep", result)
    data = {k: getattr(sw, k) for k in ("param", "direction", "status", "period_n", "qmax",
                                         "u_end")}
    data["param_name"] = sw.param_name
    return data


def _from_sweep(study, sweep, res: ContinuationResult, method, options, cfg):
    """Branches started both ways from each distinct period-n window of ``sweep`` (the
    outcome of this run's sweep, or of an earlier run's ``sweep.npz`` in the output folder,
    handed over by the runner) that no branch traced so far passes through
    (:mod:`.sweep.branches`).  Returns (the result with them appended, a summary of the
    windows: where each started and how each half ended)."""
    import dataclasses

    from .sweep.branches import on_branch, period_windows

    if sweep is None or sweep.result is None:
        return res, {"windows": [], "note": "no sweep in this run or in the output folder"}
    data = _sweep_arrays(sweep.result)
    if str(data.get("param_name", study.model.param_name)) != study.model.param_name:
        return res, {"windows": [], "note": "sweep.npz is over another parameter"}
    lo, hi = options.param_min, options.param_max
    windows = [w for w in period_windows(data, study.model.n_states)
               if lo <= w.param <= hi]
    grid = np.diff(np.unique(np.asarray(data["param"], dtype=float)))
    grid = float(grid.min()) if grid.size else options.ds
    branches, counters, notes = list(res.branches), dict(res.counters), []
    for w in windows:
        item = {"n_periods": w.n, "direction": w.direction, "range": [w.lo, w.hi],
                "points": w.points, "start": w.param}
        notes.append(item)
        u0, n = _least_period(study.model, w, method)
        if u0 is None:
            item["traced"] = "no periodic orbit from the sweep's state (shooting failed)"
            continue
        if n != w.n:
            item["least_period"] = n          # a period-d orbit is also period-n for d | n
        if on_branch(branches, n, w.param, w.qmax, 1e-3):
            item["traced"] = "already on a branch"
            continue
        # first steps of an eighth of the window (one grid step added on each side): a
        # narrow window (a period-4 window between two PDs) is not stepped over
        ds = min(options.ds, max(options.ds_min, (w.hi - w.lo + 2 * grid) / 8))
        half = dataclasses.replace(options, max_points=cfg.from_sweep_max_points,
                                   period_doubling_branch=False, ds=ds)
        item["halves"] = []
        for sign in (-1, 1):
            got = continuation(PeriodicOrbitProblem(study.model, u0, w.param, n_periods=n,
                                                    direction=sign), method, half)
            br = got.branches[0]
            item["halves"].append({"branch": len(branches), "points": len(br.points),
                                   "status": br.status.text, "message": br.message})
            for k in ("flows", "rhs_calls", "points"):
                counters[k] = counters.get(k, 0) + got.counters.get(k, 0)
            if br.points:
                branches.append(br)
    special = tuple(SpecialPoint(p.label, p.param, b, i) for b, br in enumerate(branches)
                    for i, p in enumerate(br.points) if p.label)
    out = ContinuationResult(branches=tuple(branches), special_points=special,
                             status=res.status, message=res.message, counters=counters,
                             wall_time=res.wall_time)
    return out, {"windows": notes, "source": sweep.summary.get("loaded_from", "this run's sweep")}
