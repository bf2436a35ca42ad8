"""Pseudo-arclength continuation of periodic orbits in the excitation parameter.

Problem: H(u0, p) = u(T(p); u0, p) - u0 = 0 (shooting, :mod:`.shooting`), unknowns
z = (u0, p/param_scale).  Predictor along the tangent (null vector of dH), Newton
corrector on [H; t.(z - z_pred)] (Keller; Broyden's method on orbits without the
variational equations first, :mod:`.corrector`), adaptive step.  Floquet multipliers at
every point; test functions locate folds (LP: the parameter component of the
tangent changes sign), period doublings (PD: det(M + I) changes sign) and
Neimark-Sacker points (NS: prod_{i<j}(mu_i mu_j - 1) changes sign with a complex
pair on the unit circle), each located by regula falsi in arclength; a crossing that
changes no stability (the orbit unstable on both sides) by one orbit only, and every
special point reports the parameter interval that holds its crossing
(``located_within``); where the stable orbit ends at an NS (onto a torus) the branch's
message says so.  At the first PD the solver switches onto the period-2n branch (the
shooting problem over 2nT, started along the flip eigenvector, orthogonal to the
period-n tangent) and continues it until it rejoins the period-n branch (or leaves the
range); a PD on that branch (the next step of a cascade) is labelled and the branch goes
on through it: the period-2n orbits beyond it exist, unstable.

Orbit families (a free gear that touches nothing): the k neutral directions V of the
orbit (:meth:`.shooting.PeriodicFlow.neutral`) are bordered out of the augmented system,
[[M - I, dH/dp, B], [V^T, 0, 0]] (n + k rows, n + 1 + k columns, B the left null vectors
with their multipliers), whose one null vector is the tangent; the corrector appends the
arclength row.  The k trivial multipliers 1 are stored per point (``neutral``) and left
out of stability and the test functions.  Where k changes between two points a free
coordinate has started (or stopped) touching a contact: the branch ends there as a
grazing (GRAZING_END), as it does when the steps shrink below ds_min on an orbit whose
integration failed on a grazing switch, or where the last orbits' contact switches
differ (a contact interval appears or vanishes: :func:`.special_points.grazing_note`).

Call shape (BifurcationKit's): ``continuation(problem, method, options, callback)`` ->
:class:`~.branch.ContinuationResult`, with the problem, method and result types in
:mod:`.branch` and the options in :mod:`vibrogear.config.options`.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ...config.options import ContinuationOptions, ShootingOptions
from ...pipeline.executors import blas_threads
from .branch import (Branch, BranchPoint, ContinuationResult, PeriodicOrbitProblem,
                     PseudoArclength, SpecialPoint, stability_notes)
from .floquet import flip_vector, liouville_error, stability, test_functions
from ..integrator.integrate import integrate
from .corrector import (QUASI_NEWTON_MOVE, CorrectorProblem, adapted_step, correct,
                        predictor, tangent, tangent_and_start, tangent_turned)
from .shooting import PeriodicFlow, periodic_flow, residual_norm, shoot
from .special_points import COARSE_LOCATE_ITER, grazing_note, locate, switch_counts
from ..integrator.split_flow import ColumnSplit
from ...status import Status

__all__ = ["PeriodicOrbitProblem", "PseudoArclength", "ContinuationOptions", "BranchPoint",
           "Branch", "SpecialPoint", "ContinuationResult", "continuation"]

log = logging.getLogger(__name__)


class _Stop(Exception):
    """The callback returned False."""


def _point(prob: CorrectorProblem, z, f: PeriodicFlow, t, it, res, label="",
           within=0.0) -> BranchPoint:
    tr = f.trajectory
    p = float(z[-1] * prob.scale)
    mu = f.multipliers()
    return BranchPoint(param=p, u0=z[:-1].copy(), floquet=mu, residual=res,
                       qmin=tr.monitor_min, qmax=tr.monitor_max, impacts=tr.monitor_losses,
                       tangent=t.copy(), label=label, iterations=it,
                       integration_error=tr.error_estimate,
                       liouville_det_error=liouville_error(prob.model, p, f.period, mu),
                       neutral=prob.neutral(f), located_within=within)


def continuation(problem: PeriodicOrbitProblem, method: PseudoArclength,
                 options: ContinuationOptions,
                 callback: Callable[[BranchPoint], bool | None] | None = None
                 ) -> ContinuationResult:
    """Continue the periodic orbit of ``problem`` over [param_min, param_max].

    Returns the branch and, when a PD is found and ``options.period_doubling_branch``, the
    period-doubled branch switched onto there.  ``callback(point)`` is called with every
    new point (special points included); returning False stops the run with status
    STOPPED_BY_CALLBACK, keeping the points so far.

    One BLAS thread; orbits with the monodromy share their tangent's columns with a
    second process where the model is big enough (:mod:`.split_flow`).
    """
    with blas_threads(1), ColumnSplit(problem.model, method.split_columns) as split:
        return _continuation(problem, method, options, callback, split)


def _continuation(problem, method, options, callback, split) -> ContinuationResult:
    wall = time.perf_counter()
    model, n_periods = problem.model, problem.n_periods
    sh = shoot(model, problem.param, problem.u0, n_periods=n_periods,
               options=method.integration, split=split,
               shooting=ShootingOptions(tol=method.tol, max_iter=method.start_max_iter
                                        or 3 * options.max_corrector_iter))
    period_scale = n_periods * model.excitation_period(1.0)
    if not sh.converged:
        msg = f"{Status.NO_START.message}: {sh.message}"
        branches = (Branch((), n_periods, Status.NO_START, msg, period_scale,
                           counters=dict(sh.counters)),)
    else:
        z0 = np.concatenate([sh.u0, [problem.param / method.param_scale]])
        t0 = np.zeros_like(z0)
        t0[-1] = float(problem.direction)
        # an even period: the branch can pass through the half-period orbit (a PD of it),
        # where an n-period orbit is also one of n / 2 periods: it has rejoined there
        branches = (_run_branch(model, z0, t0, method, options, n_periods, callback,
                                doubled=n_periods % 2 == 0, split=split),)
        first = branches[0]
        pd = [p for p in first.points if p.label == "PD"]
        if (options.period_doubling_branch and pd
                and first.status != Status.STOPPED_BY_CALLBACK):
            branches += (_switch_period_doubling(model, pd[0], method, options, callback,
                                                 n_periods, split),)
    special = tuple(SpecialPoint(p.label, p.param, b, i) for b, br in enumerate(branches)
                    for i, p in enumerate(br.points) if p.label)
    status = branches[0].status
    for br in branches[1:]:
        if not br.status.success:
            status = br.status
            break
    message = "; ".join(f"period-{br.n_periods} branch: {br.message}" for br in branches)
    counters = {"points": sum(len(b.points) for b in branches), "start_flows": sh.flows,
                "flows": sh.flows + sum(b.counters.get("flows", 0) for b in branches),
                "plain_flows": sum(b.counters.get("plain_flows", 0) for b in branches),
                "rhs_calls": sh.rhs_calls + sum(b.counters.get("rhs_calls", 0) for b in branches),
                "split_columns": split.active, "split_fallbacks": split.fallbacks}
    log.info("continuation: %s (%d points, %d flows)", message, counters["points"],
             counters["flows"])
    return ContinuationResult(branches=branches, special_points=special, status=status,
                              message=message, counters=counters,
                              wall_time=time.perf_counter() - wall)


def _run_branch(model, z0, t_hint, method, options, n_periods, callback,
                doubled: bool = False, split=None) -> Branch:
    wall = time.perf_counter()
    prob = CorrectorProblem(model, n_periods, method, split)
    pts: list[BranchPoint] = []

    def emit(point):
        pts.append(point)
        if callback is not None and callback(point) is False:
            raise _Stop

    status, message = Status.LEFT_RANGE, Status.LEFT_RANGE.message
    try:
        f = prob.flow(z0)
        t = tangent(prob.jac(f), t_hint)
        emit(_point(prob, z0, f, t, 0, residual_norm(f.G, z0[:-1])))
        status, message = _walk(prob, z0, f, t, method, options, n_periods, emit, doubled)
    except _Stop:
        status = Status.STOPPED_BY_CALLBACK
        message = f"{status.message} after {len(pts)} points"
    message += stability_notes(pts, model.param_name)
    return Branch(tuple(pts), n_periods, status, message,
                  n_periods * model.excitation_period(1.0),
                  counters={"flows": prob.flows, "plain_flows": prob.plain_flows,
                            "rhs_calls": prob.rhs_calls,
                            "rejected_angle": prob.rejected["angle"],
                            "rejected_corrector": prob.rejected["corrector"]},
                  wall_time=time.perf_counter() - wall)


def _walk(prob, z, f, t, method, options, n_periods, emit, doubled) -> tuple[Status, str]:
    """The predictor-corrector loop; each new point goes to ``emit``."""
    model, scale = prob.model, method.param_scale
    ds = options.ds / scale
    ds_min, ds_max = options.ds_min / scale, options.ds_max / scale
    walk = _Count(1, test_functions(f.monodromy, t, prob.neutral(f), f.multipliers()))
    k_prev = prob.neutral(f)
    J = prob.jac(f)             # the last point's bordered Jacobian: the corrector's start
    H = tangent_and_start(J, t)[1]      # and the inverse the corrector starts from
    qn_failed = 0               # successive failed correctors
    t_prev, ds_prev = None, ds
    d_prev = _half_defect(model, z, scale, method, n_periods) if doubled else None
    # contact switches per contact of the last two accepted orbits: a change is a grazing
    sw_before = sw_last = switch_counts(model, f.trajectory)
    # a start on the range's end may lie an ulp outside it: only a point beyond the range
    # by more than round-off ends the branch
    slack = 1e-9 * (abs(options.param_max) + abs(options.param_min))
    # the last accepted point is finished (test functions, special point, emitted) during
    # the next step's corrector, after its quasi-Newton stage, while its multipliers'
    # eigen-solve ran in a thread (20 ms a point at 292 states, ~15 % of a step)
    pending: list = []

    def finish():
        while pending:
            _finish(prob, options, method, emit, walk, *pending.pop())

    while True:
        if pending and walk.points + 1 >= options.max_points:
            finish()            # its special point, if any, counts too
        if walk.points >= options.max_points:
            finish()
            return Status.MAX_POINTS, Status.MAX_POINTS.message
        p = z[-1] * scale
        if p < options.param_min - slack or p > options.param_max + slack:
            finish()
            return Status.LEFT_RANGE, Status.LEFT_RANGE.message
        pred = predictor(z, t, ds, t_prev, ds_prev)
        prob.last_failure = None
        # a failed quasi-Newton corrector first halves the step; the exact Newton corrector
        # (an orbit with the variational equations per iterate) only after a second failure
        got = correct(prob, pred, t, options.max_corrector_iter, k_prev,
                      J if method.quasi_newton else None,
                      exact_fallback=qn_failed > 0 or ds <= 2 * ds_min,
                      max_move=QUASI_NEWTON_MOVE * ds, z_base=z,
                      max_angle=method.max_angle if ds > ds_min else None, between=finish,
                      H0=H)
        finish()
        qn_failed = qn_failed + 1 if got is None and not prob.secant_rejected else 0
        t_new = None
        if got is not None:
            z_new, f_new, it, res = got
            J_new = prob.jac(f_new)
            t_new, H_new = tangent_and_start(J_new, t)
            if ds > ds_min and tangent_turned(prob, t_new, t, method.max_angle):
                got = None
        else:
            prob.rejected["angle" if prob.secant_rejected else "corrector"] += 1
        if got is None:
            ds *= 0.5
            if ds < ds_min:
                if prob.last_failure in (Status.GRAZING, Status.GRAZING_END):
                    why = ("integration fails on a grazing switch" if prob.last_failure
                           == Status.GRAZING else "a contact of the free coordinate closes")
                    return Status.GRAZING_END, (f"{Status.GRAZING_END.message}: {why} "
                                                f"beyond {model.param_name} = {p:.6g}")
                tried = prob.last_orbit
                why = grazing_note(model, sw_before, sw_last) or (
                    "" if tried is None else grazing_note(model, sw_last,
                                                          switch_counts(model, tried)))
                if why:
                    # the steps shrank where a contact interval appears or vanishes: the
                    # flow is not differentiable there (a grazing bifurcation)
                    return Status.GRAZING_END, (f"{Status.GRAZING_END.message}: {why} near "
                                                f"{model.param_name} = {p:.6g}")
                return Status.DS_TOO_SMALL, f"{Status.DS_TOO_SMALL.message} at param = {p:.6g}"
            continue
        k_new = prob.neutral(f_new)
        p_new = z_new[-1] * scale
        if k_new != k_prev:
            # a free coordinate starts (k drops) or stops (k grows) touching a contact
            walk.points += 1
            emit(_point(prob, z_new, f_new, t_new, it, res))
            return Status.GRAZING_END, (
                f"{Status.GRAZING_END.message}: the orbit family's neutral directions go "
                f"from {k_prev} to {k_new} between {model.param_name} = {p:.6g} and "
                f"{p_new:.6g}")
        if doubled:
            # the signed half-period defect changes sign where the branch passes
            # through the period-n orbit (the other PD): there it has rejoined (before
            # any label: the 2nT problem's branch turns in the parameter right there)
            d_new = _half_defect(model, z_new, scale, method, n_periods)
            if d_prev is not None and d_new @ d_prev < 0:
                return Status.REJOINED, (f"period-{n_periods} branch rejoined the "
                                         f"period-{n_periods // 2} branch between param = "
                                         f"{p:.6g} and {p_new:.6g}")
            d_prev = d_new
        f_new.prefetch_multipliers()
        pending.append(((z, f, t, J, k_prev), ds, (z_new, f_new, t_new, k_new, it, res)))
        t_prev, ds_prev = t, ds
        ds = adapted_step(ds, prob, it, ds_min, ds_max)
        z, f, t, k_prev, J, H = z_new, f_new, t_new, k_new, J_new, H_new
        sw_before, sw_last = sw_last, switch_counts(model, f.trajectory)
        walk.points += 1


@dataclass
class _Count:
    """The walk's points so far (special points included) and the last point's tests."""
    points: int
    tests: dict


def _finish(prob, options, method, emit, walk: _Count, last, ds, new) -> None:
    """Finish the step from point ``last`` = (z, flow, tangent, bordered Jacobian, neutral
    count) to the accepted point ``new`` = (z, flow, tangent, neutral count, iterations,
    residual): its test functions against the last point's (``walk.tests``), a special
    point between the two located and emitted where one changes sign, then the new point."""
    z, f, t, J, k_prev = last
    z_new, f_new, t_new, k_new, it, res = new
    tests = test_functions(f_new.monodromy, t_new, k_new, f_new.multipliers())
    labels = []
    for which in ("LP", "PD", "NS"):
        a, b = walk.tests[which], tests[which]
        if which == "NS" and not tests["NS_valid"] and not walk.tests["NS_valid"]:
            continue
        if np.sign(a) != np.sign(b) and a != 0:
            labels.append(which)
    if labels:
        which = labels[0]
        # a special point on an orbit unstable on both sides (another multiplier already
        # outside the unit circle) changes no stability and bounds no stable window: one
        # regula-falsi orbit, its bracket reported (the first PD stays exact where the
        # period-doubled branch starts from it; at a fold the parameter is extremal, so
        # one orbit near the zero of the tangent's parameter part is within O(ds^2))
        coarse = (which != "PD" or not options.period_doubling_branch) and not (
            stability(f.multipliers(), trivial=k_prev)
            or stability(f_new.multipliers(), trivial=k_new))
        loc = locate(prob, z, t, ds, walk.tests[which], tests[which], which, options,
                     z_new[-1] * prob.scale, k_prev, J if method.quasi_newton else None,
                     COARSE_LOCATE_ITER if coarse else None)
        if loc is not None:
            zl, fl, tl, itl, resl, within = loc
            if not (which == "NS" and not test_functions(fl.monodromy, tl, k_new,
                                                         fl.multipliers())["NS_valid"]):
                walk.points += 1
                emit(_point(prob, zl, fl, tl, itl, resl, label=which, within=within))
    walk.tests = tests
    emit(_point(prob, z_new, f_new, t_new, it, res))


def _half_defect(model, z, scale, method, n_periods) -> np.ndarray:
    """u(T/2) - u0 of a period-doubled orbit: zero on the period-halved orbit,
    sign-reversing through it."""
    p = z[-1] * scale
    tr = integrate(model, p, z[:-1], 0.0, (n_periods // 2) * model.excitation_period(p),
                   options=method.integration)
    return tr.u_end - z[:-1]


def _switch_period_doubling(model, pd: BranchPoint, method, options, callback,
                            n_periods: int = 1, split=None) -> Branch:
    """Start the period-2n branch at a PD point of the period-n branch along the flip
    eigenvector."""
    scale = method.param_scale
    w = flip_vector(periodic_flow(model, pd.param, pd.u0, n_periods=n_periods,
                                  options=method.integration).monodromy)
    t1 = pd.tangent
    t2 = np.concatenate([w, [0.0]])
    t2 = t2 - (t2 @ t1) * t1
    t2 /= np.linalg.norm(t2)
    prob = CorrectorProblem(model, 2 * n_periods, method, split)
    z_pd = np.concatenate([pd.u0, [pd.param / scale]])
    ds0 = options.ds / scale
    for ds in (ds0, 0.3 * ds0, 0.1 * ds0, 3 * ds0):
        got = correct(prob, z_pd + ds * t2, t2, options.max_corrector_iter)
        if got is None:
            continue
        z, f, it, res = got
        half = integrate(model, z[-1] * scale, z[:-1], 0.0, f.period / 2,
                         options=method.integration)
        if np.linalg.norm(half.u_end - z[:-1]) > 1e-6 * (1 + np.linalg.norm(z[:-1])):
            t = tangent(prob.jac(f), None, z.size)
            # continue away from the PD point
            if t @ (z - z_pd) < 0:
                t = -t
            br = _run_branch(model, z, t, method, options, 2 * n_periods, callback,
                             doubled=True, split=split)
            br.counters["switch_flows"] = prob.flows
            return br
    return Branch((), 2 * n_periods, Status.SWITCH_FAILED,
                  f"{Status.SWITCH_FAILED.message} at param = {pd.param:.6g}",
                  2 * n_periods * model.excitation_period(1.0),
                  counters={"flows": prob.flows, "rhs_calls": prob.rhs_calls})
