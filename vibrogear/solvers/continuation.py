"""Pseudo-arclength continuation of periodic orbits in the excitation parameter.

Problem: H(u0, p) = u(T(p); u0, p) - u0 = 0 (shooting, :mod:`.shooting`), unknowns
z = (u0, p/param_scale).  Predictor along the tangent (null vector of dH), Newton
corrector on [H; t.(z - z_pred)] (Keller), adaptive step.  Floquet multipliers at
every point; test functions locate folds (LP: the parameter component of the
tangent changes sign), period doublings (PD: det(M + I) changes sign) and
Neimark-Sacker points (NS: prod_{i<j}(mu_i mu_j - 1) changes sign with a complex
pair on the unit circle), each located by bisection in arclength; where the stable orbit
ends at an NS (onto a torus) the branch's message says so.  At the first PD the solver
switches onto the period-2n branch (the shooting problem over 2nT, started along the flip
eigenvector, orthogonal to the period-n tangent) and continues it until it rejoins the
period-n branch (or leaves the range); a PD on that branch (the next step of a cascade) is
labelled and the branch goes on through it: the period-2n orbits beyond it exist, unstable.

Orbit families (a free gear that touches nothing): the k neutral directions V of the
orbit (:meth:`.shooting.PeriodicFlow.neutral`) are bordered out of the augmented system,
[[M - I, dH/dp, B], [V^T, 0, 0]] (n + k rows, n + 1 + k columns, B the left null vectors
with their multipliers), whose one null vector is the tangent; the corrector appends the
arclength row.  The k trivial multipliers 1 are stored per point (``neutral``) and left
out of stability and the test functions.  Where k changes between two points a free
coordinate has started (or stopped) touching a contact: the branch ends there as a
grazing (GRAZING_END), as it does when the steps shrink below ds_min on an orbit whose
integration failed on a grazing switch.

Call shape (BifurcationKit's): ``continuation(problem, method, options, callback)`` ->
:class:`~.branch.ContinuationResult`, with the problem, method and result types in
:mod:`.branch` and the options in :mod:`vibrogear.config.options`.
"""
from __future__ import annotations

import logging
import time
from typing import Callable

import numpy as np

from ..config.options import ContinuationOptions
from .branch import (Branch, BranchPoint, ContinuationResult, PeriodicOrbitProblem,
                     PseudoArclength, SpecialPoint, stability_notes)
from .floquet import flip_vector, floquet_multipliers, liouville_error, test_functions
from .integrate import integrate
from .shooting import PeriodicFlow, periodic_flow, residual_norm, shoot
from .status import Status

__all__ = ["PeriodicOrbitProblem", "PseudoArclength", "ContinuationOptions", "BranchPoint",
           "Branch", "SpecialPoint", "ContinuationResult", "continuation"]

log = logging.getLogger(__name__)


class _Stop(Exception):
    """The callback returned False."""


class _Problem:
    """Evaluations of H and its Jacobian in z = (u0, p / scale), with counters."""

    def __init__(self, model, n_periods, method: PseudoArclength):
        self.model, self.n_periods, self.method = model, n_periods, method
        self.scale = method.param_scale
        self.flows = 0
        self.rhs_calls = 0
        self.last_failure = None        # Status of the last failed integration
        self.rejected = {"angle": 0, "corrector": 0}    # rejected steps by reason

    def flow(self, z: np.ndarray) -> PeriodicFlow:
        self.flows += 1
        f = periodic_flow(self.model, z[-1] * self.scale, z[:-1], n_periods=self.n_periods,
                          options=self.method.integration)
        self.rhs_calls += f.trajectory.rhs_calls
        return f

    def neutral(self, f: PeriodicFlow) -> int:
        return f.neutral(self.model)[0].shape[1]

    def jac(self, f: PeriodicFlow) -> np.ndarray:
        """[[dH/du0, dH/dp, B], [V^T, 0, 0]]: (n + k) x (n + 1 + k), k neutral directions."""
        V, B = f.neutral(self.model)
        n, k = f.G.size, V.shape[1]
        J = np.zeros((n + k, n + 1 + k))
        J[:n, :n] = f.dG_du0
        J[:n, n] = f.dG_dparam * self.scale
        J[:n, n + 1:] = B
        J[n:, :n] = V.T
        return J


def _tangent(J: np.ndarray, prev: np.ndarray | None, nz: int | None = None) -> np.ndarray:
    """Unit null vector of the bordered Jacobian, its z = (u0, p) part (the leading ``nz``
    entries, default ``prev.size``; the k multipliers' entries are zero on a family),
    oriented along ``prev``."""
    _, _, vt = np.linalg.svd(J)
    t = vt[-1][:prev.size if nz is None else nz]
    if prev is not None and t @ prev < 0:
        t = -t
    return t / np.linalg.norm(t)


def _correct(prob: _Problem, z_pred: np.ndarray, t: np.ndarray, max_iter: int,
             k_ref: int | None = None):
    """Newton on [H(z) + B lam; V^T dz = 0; t.(z - z_pred)] = 0. Returns (z, flow,
    iterations, residual) or None (why in ``prob.last_failure``: the integrator's failure,
    or GRAZING_END where an iterate's number of neutral directions differs from ``k_ref``:
    a contact of the free coordinate opens or closes, the flow is not smooth there)."""
    tol = prob.method.tol
    z = z_pred.copy()
    for it in range(max_iter + 1):
        if not z[-1] * prob.scale > 0:
            return None
        f = prob.flow(z)
        if not f.ok:
            prob.last_failure = f.trajectory.status
            return None
        if k_ref is not None and prob.neutral(f) != k_ref:
            prob.last_failure = Status.GRAZING_END
            return None
        res = residual_norm(f.G, z[:-1])
        if res < tol:
            return z, f, it, res
        if it == max_iter:
            return None
        J = prob.jac(f)
        n1 = z.size
        A = np.vstack([J, np.concatenate([t, np.zeros(J.shape[1] - n1)])[None, :]])
        rhs = -np.concatenate([f.G, np.zeros(J.shape[0] - f.G.size), [t @ (z - z_pred)]])
        try:
            dz = np.linalg.solve(A, rhs)[:n1]
        except np.linalg.LinAlgError:
            return None
        z = z + dz
        if not np.all(np.isfinite(z)):
            return None
    return None


def _point(prob: _Problem, z, f: PeriodicFlow, t, it, res, label="") -> BranchPoint:
    tr = f.trajectory
    p = float(z[-1] * prob.scale)
    mu = floquet_multipliers(f.monodromy)
    return BranchPoint(param=p, u0=z[:-1].copy(), floquet=mu, residual=res,
                       qmin=tr.monitor_min, qmax=tr.monitor_max, impacts=tr.monitor_losses,
                       tangent=t.copy(), label=label, iterations=it,
                       integration_error=tr.error_estimate,
                       liouville_det_error=liouville_error(prob.model, p, f.period, mu),
                       neutral=prob.neutral(f))


def _locate(prob, za, ta, ds_total, fa, fb, which, options, k_ref=None):
    """Regula falsi (Illinois) in arclength between point a (test value ``fa``, s = 0)
    and the next point (``fb``, s = ds_total) for the zero of test function ``which``."""
    lo, hi = 0.0, ds_total
    f_lo, f_hi = fa, fb
    best = None
    side = 0
    for _ in range(prob.method.locate_iter):
        if f_hi != f_lo:
            mid = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        else:
            mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            mid = 0.5 * (lo + hi)
        got = _correct(prob, za + mid * ta, ta, options.max_corrector_iter, k_ref)
        if got is None:
            break
        z, f, it, res = got
        t = _tangent(prob.jac(f), ta)
        val = test_functions(f.monodromy, t, k_ref or 0)[which]
        best = (z, f, t, it, res)
        if np.sign(val) == np.sign(f_lo):
            lo, f_lo = mid, val
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = mid, val
            if side == 1:
                f_lo *= 0.5
            side = 1
        if hi - lo < 1e-6 * ds_total or abs(val) < 1e-9:
            break
    return best


def continuation(problem: PeriodicOrbitProblem, method: PseudoArclength,
                 options: ContinuationOptions,
                 callback: Callable[[BranchPoint], bool | None] | None = None
                 ) -> ContinuationResult:
    """Continue the periodic orbit of ``problem`` over [param_min, param_max].

    Returns the branch and, when a PD is found and ``options.period_doubling_branch``, the
    period-doubled branch switched onto there.  ``callback(point)`` is called with every
    new point (special points included); returning False stops the run with status
    STOPPED_BY_CALLBACK, keeping the points so far.
    """
    wall = time.perf_counter()
    model, n_periods = problem.model, problem.n_periods
    sh = shoot(model, problem.param, problem.u0, n_periods=n_periods,
               options=method.integration, tol=method.tol,
               max_iter=method.start_max_iter or 3 * options.max_corrector_iter)
    period_scale = 2 * np.pi * n_periods / model.omega_per_param
    if not sh.converged:
        msg = f"{Status.NO_START.message}: {sh.message}"
        branches = (Branch((), n_periods, Status.NO_START, msg, period_scale,
                           counters=dict(sh.counters)),)
    else:
        z0 = np.concatenate([sh.u0, [problem.param / method.param_scale]])
        t0 = np.zeros_like(z0)
        t0[-1] = float(problem.direction)
        branches = (_run_branch(model, z0, t0, method, options, n_periods, callback),)
        first = branches[0]
        pd = [p for p in first.points if p.label == "PD"]
        if (options.period_doubling_branch and pd
                and first.status != Status.STOPPED_BY_CALLBACK):
            branches += (_switch_period_doubling(model, pd[0], method, options, callback,
                                                 n_periods),)
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
                "rhs_calls": sh.rhs_calls + sum(b.counters.get("rhs_calls", 0) for b in branches)}
    log.info("continuation: %s (%d points, %d flows)", message, counters["points"],
             counters["flows"])
    return ContinuationResult(branches=branches, special_points=special, status=status,
                              message=message, counters=counters,
                              wall_time=time.perf_counter() - wall)


def _run_branch(model, z0, t_hint, method, options, n_periods, callback,
                doubled: bool = False) -> Branch:
    wall = time.perf_counter()
    prob = _Problem(model, n_periods, method)
    pts: list[BranchPoint] = []

    def emit(point):
        pts.append(point)
        if callback is not None and callback(point) is False:
            raise _Stop

    status, message = Status.LEFT_RANGE, Status.LEFT_RANGE.message
    try:
        f = prob.flow(z0)
        t = _tangent(prob.jac(f), t_hint)
        emit(_point(prob, z0, f, t, 0, residual_norm(f.G, z0[:-1])))
        status, message = _walk(prob, z0, f, t, method, options, n_periods, emit, doubled)
    except _Stop:
        status = Status.STOPPED_BY_CALLBACK
        message = f"{status.message} after {len(pts)} points"
    message += stability_notes(pts, model.param_name)
    return Branch(tuple(pts), n_periods, status, message,
                  2 * np.pi * n_periods / model.omega_per_param,
                  counters={"flows": prob.flows, "rhs_calls": prob.rhs_calls,
                            "rejected_angle": prob.rejected["angle"],
                            "rejected_corrector": prob.rejected["corrector"]},
                  wall_time=time.perf_counter() - wall)


def _walk(prob, z, f, t, method, options, n_periods, emit, doubled) -> tuple[Status, str]:
    """The predictor-corrector loop; each new point goes to ``emit``."""
    model, scale = prob.model, method.param_scale
    ds = options.ds / scale
    ds_min, ds_max = options.ds_min / scale, options.ds_max / scale
    n_points = 1
    k_prev = prob.neutral(f)
    tests_prev = test_functions(f.monodromy, t, k_prev)
    t_prev, ds_prev = None, ds
    d_prev = _half_defect(model, z, scale, method, n_periods) if doubled else None
    # a start on the range's end may lie an ulp outside it: only a point beyond the range
    # by more than round-off ends the branch
    slack = 1e-9 * (abs(options.param_max) + abs(options.param_min))
    while True:
        if n_points >= options.max_points:
            return Status.MAX_POINTS, Status.MAX_POINTS.message
        p = z[-1] * scale
        if p < options.param_min - slack or p > options.param_max + slack:
            return Status.LEFT_RANGE, Status.LEFT_RANGE.message
        pred = z + ds * t
        if t_prev is not None:
            # second-order predictor: the tangent's change estimates the curvature
            bend = 0.5 * ds * ds * (t - t_prev) / ds_prev
            if np.linalg.norm(bend) < 0.25 * ds:
                pred = pred + bend
        prob.last_failure = None
        got = _correct(prob, pred, t, options.max_corrector_iter, k_prev)
        t_new = None
        if got is not None:
            z_new, f_new, it, res = got
            t_new = _tangent(prob.jac(f_new), t)
            angle = np.arccos(np.clip(t_new @ t, -1, 1))
            if angle > method.max_angle and ds > ds_min:
                got = None
                prob.rejected["angle"] += 1
        else:
            prob.rejected["corrector"] += 1
        if got is None:
            ds *= 0.5
            if ds < ds_min:
                if prob.last_failure in (Status.GRAZING, Status.GRAZING_END):
                    why = ("integration fails on a grazing switch" if prob.last_failure
                           == Status.GRAZING else "a contact of the free coordinate closes")
                    return Status.GRAZING_END, (f"{Status.GRAZING_END.message}: {why} "
                                                f"beyond {model.param_name} = {p:.6g}")
                return Status.DS_TOO_SMALL, f"{Status.DS_TOO_SMALL.message} at param = {p:.6g}"
            continue
        k_new = prob.neutral(f_new)
        p_new = z_new[-1] * scale
        if k_new != k_prev:
            # a free coordinate starts (k drops) or stops (k grows) touching a contact
            n_points += 1
            emit(_point(prob, z_new, f_new, t_new, it, res))
            return Status.GRAZING_END, (
                f"{Status.GRAZING_END.message}: the orbit family's neutral directions go "
                f"from {k_prev} to {k_new} between {model.param_name} = {p:.6g} and "
                f"{p_new:.6g}")
        tests = test_functions(f_new.monodromy, t_new, k_new)
        labels = []
        for which in ("LP", "PD", "NS"):
            a, b = tests_prev[which], tests[which]
            if which == "NS" and not tests["NS_valid"] and not tests_prev["NS_valid"]:
                continue
            if np.sign(a) != np.sign(b) and a != 0:
                labels.append(which)
        if labels:
            which = labels[0]
            loc = _locate(prob, z, t, ds, tests_prev[which], tests[which], which, options,
                          k_prev)
            if loc is not None:
                zl, fl, tl, itl, resl = loc
                if not (which == "NS" and not test_functions(fl.monodromy, tl,
                                                             k_new)["NS_valid"]):
                    n_points += 1
                    emit(_point(prob, zl, fl, tl, itl, resl, label=which))
        ds_used = ds
        ds = min(ds * 1.5, ds_max) if it <= 2 else (ds * 0.7 if it >= 5 else ds)
        ds = max(ds, ds_min)
        if doubled:
            # the signed half-period defect changes sign where the branch passes
            # through the period-n orbit (the other PD): there it has rejoined
            d_new = _half_defect(model, z_new, scale, method, n_periods)
            if d_prev is not None and d_new @ d_prev < 0:
                return Status.REJOINED, (f"period-{n_periods} branch rejoined the "
                                         f"period-{n_periods // 2} branch between param = "
                                         f"{p:.6g} and {p_new:.6g}")
            d_prev = d_new
        t_prev, ds_prev = t, ds_used
        z, f, t, tests_prev, k_prev = z_new, f_new, t_new, tests, k_new
        n_points += 1
        emit(_point(prob, z, f, t, it, res))


def _half_defect(model, z, scale, method, n_periods) -> np.ndarray:
    """u(T/2) - u0 of a period-doubled orbit: zero on the period-halved orbit,
    sign-reversing through it."""
    p = z[-1] * scale
    tr = integrate(model, p, z[:-1], 0.0, (n_periods // 2) * model.excitation_period(p),
                   options=method.integration)
    return tr.u_end - z[:-1]


def _switch_period_doubling(model, pd: BranchPoint, method, options, callback,
                            n_periods: int = 1) -> Branch:
    """Start the period-2n branch at a PD point of the period-n branch along the flip
    eigenvector."""
    scale = method.param_scale
    w = flip_vector(periodic_flow(model, pd.param, pd.u0, n_periods=n_periods,
                                  options=method.integration).monodromy)
    t1 = pd.tangent
    t2 = np.concatenate([w, [0.0]])
    t2 = t2 - (t2 @ t1) * t1
    t2 /= np.linalg.norm(t2)
    prob = _Problem(model, 2 * n_periods, method)
    z_pd = np.concatenate([pd.u0, [pd.param / scale]])
    ds0 = options.ds / scale
    for ds in (ds0, 0.3 * ds0, 0.1 * ds0, 3 * ds0):
        got = _correct(prob, z_pd + ds * t2, t2, options.max_corrector_iter)
        if got is None:
            continue
        z, f, it, res = got
        half = integrate(model, z[-1] * scale, z[:-1], 0.0, f.period / 2,
                         options=method.integration)
        if np.linalg.norm(half.u_end - z[:-1]) > 1e-6 * (1 + np.linalg.norm(z[:-1])):
            t = _tangent(prob.jac(f), None, z.size)
            # continue away from the PD point
            if t @ (z - z_pd) < 0:
                t = -t
            br = _run_branch(model, z, t, method, options, 2 * n_periods, callback,
                             doubled=True)
            br.counters["switch_flows"] = prob.flows
            return br
    return Branch((), 2 * n_periods, Status.SWITCH_FAILED,
                  f"{Status.SWITCH_FAILED.message} at param = {pd.param:.6g}",
                  2 * np.pi * 2 * n_periods / model.omega_per_param,
                  counters={"flows": prob.flows, "rhs_calls": prob.rhs_calls})
