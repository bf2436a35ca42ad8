"""Pseudo-arclength continuation of periodic orbits in the excitation parameter.

Problem: H(u0, p) = u(T(p); u0, p) - u0 = 0 (shooting, :mod:`.shooting`), unknowns
z = (u0, p/param_scale).  Predictor along the tangent (null vector of dH), Newton
corrector on [H; t.(z - z_pred)] (Keller), adaptive step.  Floquet multipliers at
every point; test functions locate folds (LP: the parameter component of the
tangent changes sign), period doublings (PD: det(M + I) changes sign) and
Neimark-Sacker points (NS: prod_{i<j}(mu_i mu_j - 1) changes sign with a complex
pair on the unit circle), each located by bisection in arclength.  At the first PD
the solver switches onto the period-2 branch (the shooting problem over 2T, started
along the flip eigenvector, orthogonal to the period-1 tangent) and continues it.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..models.reduced import ReducedModel
from .floquet import stability, test_functions
from .integrate import IntegrationOptions, integrate
from .shooting import PeriodicFlow, periodic_flow, residual_norm, shoot

__all__ = ["ContinuationOptions", "BranchPoint", "Branch", "continue_orbits"]


@dataclass(frozen=True)
class ContinuationOptions:
    param_min: float
    param_max: float
    ds: float = 0.02
    ds_min: float = 1e-6
    ds_max: float = 0.1
    max_points: int = 2000
    max_corrector_iter: int = 8
    tol: float = 1e-9
    param_scale: float = 1.0
    locate_iter: int = 10
    max_angle: float = 0.35          # radians between successive tangents
    period_doubling_branch: bool = True

    def __post_init__(self):
        if not self.param_min < self.param_max:
            raise ValueError("param_min must be < param_max")
        if not 0 < self.ds_min <= self.ds <= self.ds_max:
            raise ValueError("need 0 < ds_min <= ds <= ds_max")
        if self.max_points < 2 or self.max_corrector_iter < 1:
            raise ValueError("max_points >= 2 and max_corrector_iter >= 1 required")


@dataclass(frozen=True, eq=False)
class BranchPoint:
    param: float
    u0: np.ndarray
    floquet: np.ndarray
    residual: float
    qmin: float
    qmax: float
    impacts: int
    tangent: np.ndarray
    label: str = ""
    iterations: int = 0

    @property
    def stable(self) -> bool:
        return stability(self.floquet)


@dataclass(frozen=True, eq=False)
class Branch:
    points: list            # BranchPoint, in order of continuation
    n_periods: int          # 1: period-1 branch, 2: period-2 branch
    status: int             # 0 left the range / finished, 1 stopped early (see message)
    message: str
    period_scale: float     # period of the orbit = n_periods * 2 pi / (omega_per_param * param)
    counters: dict = field(default_factory=dict)
    wall_time: float = 0.0

    def array(self, name: str) -> np.ndarray:
        return np.array([getattr(p, name) for p in self.points])


class _Problem:
    """Evaluations of H and its Jacobian, with counters."""

    def __init__(self, model, n_periods, options, scale):
        self.model, self.n_periods, self.opts, self.scale = model, n_periods, options, scale
        self.flows = 0
        self.rhs_calls = 0

    def flow(self, z: np.ndarray) -> PeriodicFlow:
        self.flows += 1
        f = periodic_flow(self.model, z[-1] * self.scale, z[:-1], n_periods=self.n_periods,
                          options=self.opts)
        self.rhs_calls += f.trajectory.rhs_calls
        return f

    def jac(self, f: PeriodicFlow) -> np.ndarray:
        return np.hstack([f.dG_du0, (f.dG_dparam * self.scale)[:, None]])


def _tangent(J: np.ndarray, prev: np.ndarray | None) -> np.ndarray:
    """Unit null vector of the n x (n+1) Jacobian, oriented along ``prev``."""
    _, _, vt = np.linalg.svd(J)
    t = vt[-1]
    if prev is not None and t @ prev < 0:
        t = -t
    return t / np.linalg.norm(t)


def _correct(prob: _Problem, z_pred: np.ndarray, t: np.ndarray, max_iter: int, tol: float):
    """Newton on [H(z); t.(z - z_pred)] = 0. Returns (z, flow, iterations) or None."""
    z = z_pred.copy()
    for it in range(max_iter + 1):
        if not z[-1] * prob.scale > 0:
            return None
        f = prob.flow(z)
        if not f.ok:
            return None
        res = residual_norm(f.G, z[:-1])
        if res < tol:
            return z, f, it, res
        if it == max_iter:
            return None
        A = np.vstack([prob.jac(f), t[None, :]])
        rhs = -np.concatenate([f.G, [t @ (z - z_pred)]])
        try:
            dz = np.linalg.solve(A, rhs)
        except np.linalg.LinAlgError:
            return None
        z = z + dz
        if not np.all(np.isfinite(z)):
            return None
    return None


def _point(prob: _Problem, z, f: PeriodicFlow, t, it, res, label="") -> BranchPoint:
    tr = f.trajectory
    return BranchPoint(param=float(z[-1] * prob.scale), u0=z[:-1].copy(),
                       floquet=np.linalg.eigvals(f.monodromy), residual=res,
                       qmin=tr.monitor_min, qmax=tr.monitor_max, impacts=tr.monitor_losses,
                       tangent=t.copy(), label=label, iterations=it)


def _locate(prob, za, ta, ds_total, fa, fb, which, opts):
    """Regula falsi (Illinois) in arclength between point a (test value ``fa``, s = 0)
    and the next point (``fb``, s = ds_total) for the zero of test function ``which``."""
    lo, hi = 0.0, ds_total
    f_lo, f_hi = fa, fb
    best = None
    side = 0
    for _ in range(opts.locate_iter):
        if f_hi != f_lo:
            mid = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        else:
            mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            mid = 0.5 * (lo + hi)
        got = _correct(prob, za + mid * ta, ta, opts.max_corrector_iter, opts.tol)
        if got is None:
            break
        z, f, it, res = got
        t = _tangent(prob.jac(f), ta)
        val = test_functions(f.monodromy, t)[which]
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


def continue_orbits(model: ReducedModel, u0_start, param_start: float,
                    options: ContinuationOptions, *, direction: int = -1, n_periods: int = 1,
                    integration: IntegrationOptions = IntegrationOptions(),
                    callback: Callable | None = None) -> list[Branch]:
    """Continue the period-``n_periods`` orbit through ``(u0_start, param_start)``.

    ``u0_start`` must be (close to) a periodic orbit; ``direction`` = -1 continues
    towards smaller parameter first.  Returns the branch and, when a PD is found and
    ``options.period_doubling_branch``, the period-2 branch switched onto there.
    """
    sh = shoot(model, param_start, u0_start, n_periods=n_periods, options=integration,
               tol=options.tol, max_iter=options.max_corrector_iter * 3)
    if not sh.converged:
        return [Branch([], n_periods, 1, f"no starting orbit: {sh.message}", 0.0)]
    z0 = np.concatenate([sh.u0, [param_start / options.param_scale]])
    t0 = np.zeros_like(z0)
    t0[-1] = float(direction)
    branch = _run_branch(model, z0, t0, options, n_periods, integration, callback)
    out = [branch]
    pd = [i for i, p in enumerate(branch.points) if p.label == "PD"]
    if options.period_doubling_branch and pd and n_periods == 1:
        out.append(_switch_period_doubling(model, branch.points[pd[0]], options, integration,
                                           callback))
    return out


def _run_branch(model, z0, t_hint, options, n_periods, integration, callback) -> Branch:
    wall = time.perf_counter()
    prob = _Problem(model, n_periods, integration, options.param_scale)
    f = prob.flow(z0)
    t = _tangent(prob.jac(f), t_hint)
    pts = [_point(prob, z0, f, t, 0, residual_norm(f.G, z0[:-1]))]
    if callback:
        callback(pts[-1])
    z = z0
    ds = options.ds
    status, message = 0, "left the parameter range"
    tests_prev = test_functions(f.monodromy, t)
    t_prev, ds_prev = None, ds
    d_prev = _half_defect(model, z0, options, integration, n_periods) if n_periods > 1 else None
    while True:
        if len(pts) >= options.max_points:
            status, message = 1, "maximum number of points reached"
            break
        p = z[-1] * options.param_scale
        # a start on the range's end (p = param_max / scale * scale) may lie an ulp
        # outside it: only a point beyond the range by more than round-off ends the branch
        slack = 1e-9 * (abs(options.param_max) + abs(options.param_min))
        if p < options.param_min - slack or p > options.param_max + slack:
            break
        pred = z + ds * t
        if t_prev is not None:
            # second-order predictor: the tangent's change estimates the curvature
            bend = 0.5 * ds * ds * (t - t_prev) / ds_prev
            if np.linalg.norm(bend) < 0.25 * ds:
                pred = pred + bend
        got = _correct(prob, pred, t, options.max_corrector_iter, options.tol)
        t_new = None
        if got is not None:
            z_new, f_new, it, res = got
            t_new = _tangent(prob.jac(f_new), t)
            angle = np.arccos(np.clip(t_new @ t, -1, 1))
            if angle > options.max_angle and ds > options.ds_min:
                got = None
        if got is None:
            ds *= 0.5
            if ds < options.ds_min:
                status, message = 1, f"step size below ds_min at param = {p:.6g}"
                break
            continue
        tests = test_functions(f_new.monodromy, t_new)
        labels = []
        for which in ("LP", "PD", "NS"):
            a, b = tests_prev[which], tests[which]
            if which == "NS" and not tests["NS_valid"] and not tests_prev["NS_valid"]:
                continue
            if np.sign(a) != np.sign(b) and a != 0:
                labels.append(which)
        if labels:
            which = labels[0]
            loc = _locate(prob, z, t, ds, tests_prev[which], tests[which], which, options)
            if loc is not None:
                zl, fl, tl, itl, resl = loc
                special = _point(prob, zl, fl, tl, itl, resl, label=which)
                if not (which == "NS" and not test_functions(fl.monodromy, tl)["NS_valid"]):
                    pts.append(special)
                    if callback:
                        callback(special)
        ds_used = ds
        ds = min(ds * 1.5, options.ds_max) if it <= 2 else (ds * 0.7 if it >= 5 else ds)
        ds = max(ds, options.ds_min)
        if n_periods > 1:
            # the signed half-period defect changes sign where the branch passes
            # through the period-1 orbit (the other PD): there it has rejoined
            d_new = _half_defect(model, z_new, options, integration, n_periods)
            if d_prev is not None and d_new @ d_prev < 0:
                p_new = z_new[-1] * options.param_scale
                status, message = 0, (f"period-{n_periods} branch rejoined the period-1 branch "
                                      f"between param = {p:.6g} and {p_new:.6g}")
                break
            d_prev = d_new
        t_prev, ds_prev = t, ds_used
        z, f, t, tests_prev = z_new, f_new, t_new, tests
        pts.append(_point(prob, z, f, t, it, res))
        if callback:
            callback(pts[-1])
    return Branch(pts, n_periods, status, message, 2 * np.pi * n_periods / model.omega_per_param,
                  counters={"flows": prob.flows, "rhs_calls": prob.rhs_calls},
                  wall_time=time.perf_counter() - wall)


def _half_defect(model, z, options, integration, n_periods) -> np.ndarray:
    """u(T/n) - u0: zero on a period-1 orbit, sign-reversing through it."""
    p = z[-1] * options.param_scale
    tr = integrate(model, p, z[:-1], 0.0, model.excitation_period(p), options=integration)
    return tr.u_end - z[:-1]


def _switch_period_doubling(model, pd: BranchPoint, options, integration, callback) -> Branch:
    """Start the period-2 branch at a PD point along the flip eigenvector."""
    mu, vecs = np.linalg.eig(periodic_flow(model, pd.param, pd.u0, options=integration).monodromy)
    k = int(np.argmin(np.abs(mu + 1.0)))
    w = np.real(vecs[:, k])
    w /= np.linalg.norm(w)
    t1 = pd.tangent
    t2 = np.concatenate([w, [0.0]])
    t2 = t2 - (t2 @ t1) * t1
    t2 /= np.linalg.norm(t2)
    prob = _Problem(model, 2, integration, options.param_scale)
    z_pd = np.concatenate([pd.u0, [pd.param / options.param_scale]])
    for ds in (options.ds, 0.3 * options.ds, 0.1 * options.ds, 3 * options.ds):
        got = _correct(prob, z_pd + ds * t2, t2, options.max_corrector_iter, options.tol)
        if got is None:
            continue
        z, f, it, res = got
        half = integrate(model, z[-1] * options.param_scale, z[:-1], 0.0, f.period / 2,
                         options=integration)
        if np.linalg.norm(half.u_end - z[:-1]) > 1e-6 * (1 + np.linalg.norm(z[:-1])):
            t = _tangent(prob.jac(f), None)
            # continue away from the PD point
            if t @ (z - z_pd) < 0:
                t = -t
            return _run_branch(model, z, t, options, 2, integration, callback)
    return Branch([], 2, 1, f"could not switch onto the period-2 branch at param = {pd.param:.6g}",
                  2 * np.pi * 2 / model.omega_per_param)
