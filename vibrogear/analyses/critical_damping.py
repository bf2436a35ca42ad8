"""Critical damping of the impact pair: the zeta at which the primary-resonance folds meet.

Below the critical damping the period-1 branch of the main resonance bends over (the
hardening contact nonlinearity) and has a pair of turning points (LP, folds) with
hysteresis between them; as zeta grows the two folds approach each other and meet at a
cusp, above which the branch is single-valued.  :func:`critical_zeta` finds that zeta by
bisection: at each trial zeta one pseudo-arclength continuation over the window
[omega_min, omega_max] (which must contain the primary resonance and nothing else with
folds) counts the LP points of the period-1 branch.

At a cusp the two fold curves meet tangentially: with the normal form x^3 + a x + b = 0
(a ~ zeta - zeta_c, b ~ Omega - Omega_c) the folds lie on 4 a^3 + 27 b^2 = 0, so their
separation in Omega shrinks like (zeta_c - zeta)^(3/2) (in amplitude like the square
root).  The separations of the runs nearest the cusp, raised to the power 2/3, are fitted
by a straight line in zeta; its zero is reported as an independent (extrapolated)
estimate of zeta_c, a check that the bisection did not stop early on a missed fold pair.
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..models.impact_pair import impact_pair_from_config
from ..pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ..solvers.periodic.continuation import (ContinuationOptions, PeriodicOrbitProblem, PseudoArclength,
                                    continuation)
from ..solvers.integrator.integrate import IntegrationOptions, integrate
from ..solvers.static import static_equilibrium
from ..status import Outcome, Status

__all__ = ["FoldScan", "CriticalDampingResult", "CriticalDampingFigures", "fold_scan",
           "critical_zeta", "run_critical_damping"]


@dataclass(frozen=True)
class FoldScan:
    """One continuation at one zeta: the folds (LP parameters) of the period-1 branch."""
    zeta: float
    folds: tuple[float, ...]
    points: int
    status: Status
    message: str
    wall_time: float
    #: the scan's solves (static state, transient, continuation) as one outcome, with the
    #: period-1 branch's status
    outcome: Outcome | None = None

    @property
    def has_fold_pair(self) -> bool:
        return len(self.folds) >= 2


@dataclass(frozen=True)
class CriticalDampingResult:
    zeta_critical: float            # midpoint of the final bracket
    bracket: tuple[float, float]    # (largest zeta with folds, smallest zeta without)
    folds_at_bracket: tuple[float, ...]   # fold parameters at bracket[0]
    zeta_extrapolated: float        # zero of the linear fit of (fold gap)^(2/3) in zeta
    continuations: int
    scans: list = field(default_factory=list)   # FoldScan, in the order run
    wall_time: float = 0.0

    @property
    def fold_gap(self) -> float:
        f = self.folds_at_bracket
        return float(max(f) - min(f)) if len(f) >= 2 else float("nan")


@dataclass(frozen=True, eq=False)
class CriticalDampingFigures:
    """What :mod:`vibrogear.report.writers.critical_damping` draws: the bisection's result,
    the extra fold scans between zeta_lo and the cusp, and the figure title."""
    result: CriticalDampingResult
    extra_scans: tuple
    title: str


def _start_state(model, omega: float, periods: int,
                 options: IntegrationOptions) -> tuple[np.ndarray, list]:
    """(the state after the transient, the outcomes of the static solve and the transient)."""
    st = static_equilibrium(model)
    u = st.u0 if st.converged else np.zeros(model.n_states)
    tr = integrate(model, omega, u, 0.0, periods * model.excitation_period(omega), options=options)
    if not tr.ok:
        raise NumericalFailure(f"critical damping: transient at Omega = {omega:g} failed: "
                               f"{tr.message}")
    return tr.u_end, [st.outcome, tr.outcome]


def fold_scan(cfg_impact_pair, zeta: float, options: ContinuationOptions,
              method: PseudoArclength = PseudoArclength(), *,
              transient_periods: int = 300) -> FoldScan:
    """Continue the period-1 branch from param_max down to param_min at this zeta (the
    options' period-doubling switch is not used: only period-1 folds count)."""
    wall = time.perf_counter()
    model = impact_pair_from_config(dataclasses.replace(cfg_impact_pair, zeta=float(zeta)))
    lo, hi = options.param_min, options.param_max
    u0, solves = _start_state(model, hi, transient_periods, method.integration)
    if options.period_doubling_branch:
        options = dataclasses.replace(options, period_doubling_branch=False)
    res = continuation(PeriodicOrbitProblem(model, u0, hi, direction=-1), method, options)
    branch = res.branches[0]
    folds = tuple(sorted(s.param for s in res.special_points
                         if s.branch == 0 and s.label == "LP" and lo <= s.param <= hi))
    wall = time.perf_counter() - wall
    return FoldScan(zeta=float(zeta), folds=folds, points=len(branch.points),
                    status=branch.status, message=branch.message, wall_time=wall,
                    outcome=Outcome.combine([*solves, res.outcome], status=branch.status,
                                            message=branch.message, wall_s=wall))


def _extrapolate(scans) -> float:
    """zeta where a straight-line fit of (fold gap)^(2/3) against zeta reaches zero."""
    pts = sorted((s.zeta, (max(s.folds) - min(s.folds)) ** (2.0 / 3.0))
                 for s in scans if s.has_fold_pair)
    pts = pts[-3:]   # the ones nearest the cusp
    if len(pts) < 2:
        return float("nan")
    z, g2 = np.array(pts).T
    if np.ptp(z) == 0:
        return float("nan")
    a, b = np.polyfit(z, g2, 1)
    return float(-b / a) if a < 0 else float("nan")


def critical_zeta(cfg_impact_pair, options: ContinuationOptions,
                  method: PseudoArclength = PseudoArclength(), *, zeta_lo: float,
                  zeta_hi: float, tol: float = 1e-4, transient_periods: int = 300,
                  callback: Callable[[FoldScan], None] | None = None) -> CriticalDampingResult:
    """Bisect in zeta for the damping above which the primary resonance has no fold pair.

    ``zeta_lo`` must give a fold pair in the options' window [param_min, param_max] and
    ``zeta_hi`` none;
    the bracket is halved until it is narrower than ``tol``.  Raises
    :class:`~vibrogear.runner.NumericalFailure` when the ends do not bracket the cusp or
    a continuation stops before leaving the window (its verdict would be unreliable).
    """
    if not 0.0 <= zeta_lo < zeta_hi:
        raise ValueError("need 0 <= zeta_lo < zeta_hi")
    wall = time.perf_counter()
    scans: list[FoldScan] = []

    def scan(z: float) -> FoldScan:
        s = fold_scan(cfg_impact_pair, z, options, method,
                      transient_periods=transient_periods)
        scans.append(s)
        if callback is not None:
            callback(s)
        if not s.status.success:
            raise NumericalFailure(f"critical damping: continuation at zeta = {z:.6g} stopped "
                                   f"early: {s.message}")
        return s

    lo, hi = scan(zeta_lo), scan(zeta_hi)
    if not lo.has_fold_pair:
        raise NumericalFailure(f"critical damping: zeta_lo = {zeta_lo:g} has no fold pair in "
                               f"Omega [{options.param_min:g}, {options.param_max:g}] (folds {list(lo.folds)}): "
                               "lower zeta_lo")
    if hi.has_fold_pair:
        raise NumericalFailure(f"critical damping: zeta_hi = {zeta_hi:g} still has folds "
                               f"{list(hi.folds)}: raise zeta_hi")
    while hi.zeta - lo.zeta > tol:
        mid = scan(0.5 * (lo.zeta + hi.zeta))
        if mid.has_fold_pair:
            lo = mid
        else:
            hi = mid
    return CriticalDampingResult(
        zeta_critical=0.5 * (lo.zeta + hi.zeta), bracket=(lo.zeta, hi.zeta),
        folds_at_bracket=lo.folds, zeta_extrapolated=_extrapolate(scans),
        continuations=len(scans), scans=scans, wall_time=time.perf_counter() - wall)


def run_critical_damping(scene, ctx: RunContext) -> AnalysisOutcome:
    """Runner entry: the critical zeta and the fold curves; the summary is also written
    as ``critical_damping.json``, with ``critical_damping.png/.svg``, by
    :mod:`vibrogear.report.writers.critical_damping`."""
    from .study import integration_options

    cfg = scene.critical_damping
    c = scene.impact_pair
    options = cfg.options()
    method = PseudoArclength(integration=integration_options(scene), tol=scene.shooting.tol)
    n_max = 2 + int(np.ceil(np.log2(max((cfg.zeta_hi - cfg.zeta_lo) / cfg.tol, 1.0))))
    with ctx.progress(n_max, "critical zeta") as bar:
        res = critical_zeta(
            c, options, method, zeta_lo=cfg.zeta_lo, zeta_hi=cfg.zeta_hi, tol=cfg.tol,
            transient_periods=cfg.transient_periods,
            callback=lambda s: bar.update(1, f"zeta={s.zeta:.5g} LP={len(s.folds)}"))
    # extra zetas between zeta_lo and the cusp, only to draw the two fold curves
    tried = [fold_scan(c, float(z), options, method, transient_periods=cfg.transient_periods)
             for z in np.linspace(cfg.zeta_lo, res.bracket[0], cfg.curve_points + 2)[1:-1]]
    extra = [s for s in tried if s.status.success]

    def as_json(s: FoldScan) -> dict:
        return {f.name: getattr(s, f.name) for f in dataclasses.fields(s)
                if f.name != "outcome"} | {"folds": list(s.folds), "status": s.status.text,
                                           "has_fold_pair": s.has_fold_pair}

    scans = [as_json(s) for s in res.scans]
    out = {
        "zeta_critical": res.zeta_critical,
        "bracket": list(res.bracket),
        "bracket_width": res.bracket[1] - res.bracket[0],
        "folds_at_bracket": list(res.folds_at_bracket),
        "fold_gap_at_bracket": res.fold_gap,
        "zeta_extrapolated": res.zeta_extrapolated,
        "continuations": res.continuations,
        "window": [cfg.omega_min, cfg.omega_max],
        "scans": scans,
        "curve_scans": [as_json(s) for s in extra],
        "error_estimate": {"zeta_half_bracket": 0.5 * (res.bracket[1] - res.bracket[0]),
                           "extrapolation_minus_bisection": res.zeta_extrapolated
                           - res.zeta_critical},
    }
    title = (f"{scene.scene.name}: kappa={c.kappa:g}, f_m={c.f_m:g}, f_p={c.f_p:g}, "
             f"b_r={c.b_r:g}")
    # the runner's solver entries: every scan's solves, those of the bisection and of the
    # curves (a curve scan that stopped early is left out of the figure, not of the count)
    return AnalysisOutcome(summary=out, result=CriticalDampingFigures(
        result=res, extra_scans=tuple(extra), title=title),
        solver=Outcome.combine(s.outcome for s in (*res.scans, *tried)))
