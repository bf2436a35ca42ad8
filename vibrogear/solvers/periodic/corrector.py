"""The corrector of pseudo-arclength continuation (:mod:`.continuation`): the shooting
problem's evaluations with counters, the tangent, and the Newton corrector on the
bordered system, with a quasi-Newton (Broyden) stage first.

Every exact Newton iterate integrates the orbit with the variational equations (the
monodromy), which costs ~200 orbits without them on the two-stage gearbox (292 states:
0.39 s against 2 ms).  So the corrector starts with Broyden's method from the last
point's bordered Jacobian, whose iterates are orbits alone, and only the converged point
integrates the variational equations: it needs its monodromy anyway, for the Floquet
multipliers, the test functions and the next tangent.  Where Broyden does not converge
within :data:`QUASI_NEWTON_ITER` iterations or its residual diverges, the exact
Newton iteration starts from the predictor as before.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

from .branch import PseudoArclength
from .shooting import PeriodicFlow, periodic_flow, periodic_residual, residual_norm
from ...status import Status

__all__ = ["CorrectorProblem", "tangent", "tangent_and_start", "correct", "predictor",
           "adapted_step", "tangent_turned", "QUASI_NEWTON_ITER",
           "QUASI_NEWTON_GROW", "QUASI_NEWTON_SHRINK", "QUASI_NEWTON_MOVE"]

#: quasi-Newton iterations of a corrector before the exact Newton iteration takes over
QUASI_NEWTON_ITER = 24
#: ... or until its residual exceeds this many times the smallest so far
DIVERGED = 10.0
#: a quasi-Newton correction farther than this times the step from the predictor is refused
QUASI_NEWTON_MOVE = 0.5
#: ... and an exact Newton correction farther than this times that
EXACT_MOVE = 2.0
#: ... up to this many the step grows, from the second this many on it shrinks
QUASI_NEWTON_GROW, QUASI_NEWTON_SHRINK = 5, 12
#: the exact Newton corrector gives up after this many successive iterates that do not
#: shrink the residual by NEWTON_CONTRACTION each: near a regular point Newton contracts
#: quadratically; where it does not, the flow is not smooth there (a grazing) and its
#: iterates cycle (measured at the two-stage branch's end: periods 2-3 over all 9 iterates,
#: 0.7 s per failed corrector); the caller halves the step
NEWTON_CONTRACTION, NEWTON_STALLED = 0.5, 2


class CorrectorProblem:
    """Evaluations of H and its Jacobian in z = (u0, p / scale), with counters."""

    def __init__(self, model, n_periods, method: PseudoArclength, split=None):
        self.model, self.n_periods, self.method = model, n_periods, method
        self.split = split              # ColumnSplit: orbits with the monodromy on two cores
        self.scale = method.param_scale
        self.flows = 0
        self.plain_flows = 0            # orbits without the variational equations
        self.quasi_newton_iterations = None   # of the last corrector (None: exact Newton)
        self.secant_rejected = False          # the last corrector refused by its secant
        self.rhs_calls = 0
        self.last_failure = None        # Status of the last failed integration
        self.last_orbit = None          # Trajectory of the last orbit integrated
        self.rejected = {"angle": 0, "corrector": 0}    # rejected steps by reason
        # every orbit's first trial step: the step the first orbit's controller proposed
        # at its end (one value for the whole branch, so the residual stays one function
        # of z); the default start spent 6 of 50 steps of a two-stage orbit growing it
        self.first_step = None

    def flow(self, z: np.ndarray) -> PeriodicFlow:
        self.flows += 1
        f = periodic_flow(self.model, z[-1] * self.scale, z[:-1], n_periods=self.n_periods,
                          options=self.method.integration, split=self.split,
                          first_step=self.first_step)
        self._ran(f.trajectory)
        return f

    def plain(self, z: np.ndarray):
        """The orbit without variational equations (its ``u_end - u0`` is G)."""
        self.plain_flows += 1
        tr = periodic_residual(self.model, z[-1] * self.scale, z[:-1],
                               n_periods=self.n_periods, options=self.method.integration,
                               first_step=self.first_step)
        self._ran(tr)
        return tr

    def _ran(self, tr) -> None:
        self.rhs_calls += tr.rhs_calls
        self.last_orbit = tr
        if self.first_step is None and tr.ok:
            self.first_step = tr.next_first_step

    def neutral(self, f: PeriodicFlow) -> int:
        return f.neutral(self.model)[0].shape[1]

    def borders(self, f: PeriodicFlow) -> tuple[np.ndarray, np.ndarray]:
        """(V, B) of the bordered Jacobian: the orbit family's neutral directions."""
        return f.neutral(self.model)

    def jac(self, f: PeriodicFlow) -> np.ndarray:
        """[[dH/du0, dH/dp, B], [V^T, 0, 0]]: (n + k) x (n + 1 + k), k bordered directions
        (:meth:`borders`)."""
        V, B = self.borders(f)
        n, k = f.G.size, V.shape[1]
        J = np.zeros((n + k, n + 1 + k))
        J[:n, :n] = f.dG_du0
        J[:n, n] = f.dG_dparam * self.scale
        J[:n, n + 1:] = B
        J[n:, :n] = V.T
        return J


def tangent(J: np.ndarray, prev: np.ndarray | None, nz: int | None = None) -> np.ndarray:
    """Unit null vector of the bordered Jacobian, its z = (u0, p) part (the leading ``nz``
    entries, default ``prev.size``; the k multipliers' entries are zero on a family),
    oriented along ``prev``.  J (r x (r + 1)) has full row rank on a regular branch: the
    last column of the full Q of J^T = Q R is orthogonal to every row of J (a QR costs a
    third of the SVD: 3.6 against 11 ms at 292 states)."""
    q, _ = scipy.linalg.qr(J.T, mode="full")
    t = q[:, -1][:prev.size if nz is None else nz]
    if prev is not None and t @ prev < 0:
        t = -t
    return t / np.linalg.norm(t)


def tangent_and_start(J: np.ndarray, prev: np.ndarray | None):
    """(t, H): :func:`tangent` of the bordered Jacobian J, and H = inv([J; t^T]), the
    quasi-Newton corrector's start from J along t, from the same QR: with J^T = Q R,
    [J; t^T] = diag(R1^T, s) Q^T (s = +-1, t = s q_last), so its inverse is
    [Q1 R1^-T, s q_last]: one triangular solve instead of an LU and its inverse, once a
    point.  H is None where J borders neutral directions (t is then the truncated null
    vector, renormalised)."""
    if prev is None or J.shape[1] != prev.size:         # bordered: k neutral directions
        return tangent(J, prev), None
    q, r = scipy.linalg.qr(J.T, mode="full")
    t = q[:, -1].copy()
    s = -1.0 if t @ prev < 0 else 1.0
    t *= s
    n = J.shape[0]
    H = np.empty((n + 1, n + 1))
    # X = Q1 R1^-T  <=>  R1 X^T = Q1^T
    H[:, :n] = scipy.linalg.solve_triangular(r[:n, :n], q[:, :n].T, check_finite=False).T
    H[:, n] = t
    return t / np.linalg.norm(t), H


def _quasi_newton(prob: CorrectorProblem, z_pred: np.ndarray, t: np.ndarray, J0: np.ndarray,
                  max_iter: int, max_move: float = np.inf, H0: np.ndarray | None = None):
    """Broyden's method on F(z, lam) = [H(z) + B lam; V^T (u - u_pred); t.(z - z_pred)]
    = 0 from the predictor, started with the bordered Jacobian ``J0`` of the last point
    (B, V: its neutral directions) and updated by rank-one (good Broyden) updates of the
    inverse; every iterate costs an orbit without the variational equations.  Returns z
    with |H| / (1 + |u|) < tol, or None where it does not get there in ``max_iter``
    iterations or its residual exceeds :data:`DIVERGED` times the smallest so far (Broyden's
    residuals need not fall monotonically; then the exact Newton corrector takes over);
    with z, the number of iterations."""
    tol = prob.method.tol
    n1 = z_pred.size
    k = J0.shape[1] - n1
    if H0 is not None:
        H = H0.copy()                   # inv([J0; t^T]) already (:func:`tangent_and_start`)
    else:
        A = np.vstack([J0, np.concatenate([t, np.zeros(k)])[None, :]])
        try:
            H = np.linalg.inv(A)
        except np.linalg.LinAlgError:
            return None
    n = n1 - 1
    B, V = J0[:n, n1:], J0[n:, :n]
    x = np.concatenate([z_pred, np.zeros(k)])

    def F(x):
        z = x[:n1]
        if not z[-1] * prob.scale > 0:
            return None, np.inf
        tr = prob.plain(z)
        if not tr.ok or not np.all(np.isfinite(tr.u_end)):
            return None, np.inf
        G = tr.u_end - z[:-1]
        return (np.concatenate([G + B @ x[n1:], V @ (z[:-1] - z_pred[:-1]),
                                [t @ (z - z_pred)]]), residual_norm(G, z[:-1]))

    f, res = F(x)
    best = res
    for it in range(max_iter):
        if f is None:
            return None
        if res < tol:
            # a corrector that moved far from the predictor may have crossed over to
            # another sheet of the branch (near a fold): not accepted
            if np.linalg.norm(x[:n1] - z_pred) > max_move:
                return None
            return x[:n1], it
        dx = -H @ f
        x_new = x + dx
        f_new, res_new = F(x_new)
        if f_new is None:
            return None
        best = min(best, res_new)
        if res_new > DIVERGED * best:
            return None
        df = f_new - f
        Hdf = H @ df
        den = dx @ Hdf
        if abs(den) > 1e-300:
            H = H + np.outer(dx - Hdf, dx @ H) / den
        x, f, res = x_new, f_new, res_new
    ok = f is not None and res < tol and np.linalg.norm(x[:n1] - z_pred) <= max_move
    return (x[:n1], max_iter) if ok else None


def correct(prob: CorrectorProblem, z_pred: np.ndarray, t: np.ndarray, max_iter: int,
             k_ref: int | None = None, J0: np.ndarray | None = None,
             exact_fallback: bool = True, max_move: float = np.inf,
             z_base: np.ndarray | None = None, max_angle: float | None = None,
             between=None, H0: np.ndarray | None = None):
    """Newton on [H(z) + B lam; V^T dz = 0; t.(z - z_pred)] = 0. Returns (z, flow,
    iterations, residual) or None (why in ``prob.last_failure``: the integrator's failure,
    or GRAZING_END where an iterate's number of neutral directions differs from ``k_ref``:
    a contact of the free coordinate opens or closes, the flow is not smooth there).

    With ``J0`` (the bordered Jacobian at the last point) the cheap quasi-Newton
    corrector (:func:`_quasi_newton`) runs first; its solution is checked, and finished
    if need be, by the exact Newton iteration below, whose first flow (with the variational
    equations) is the one the point needs anyway for its multipliers and tangent.  Where
    it fails or ends farther than ``max_move`` from the predictor (Broyden's iterates can
    cross over to another sheet near a fold), the exact iteration starts from the
    predictor, or (``exact_fallback`` False) the corrector gives up at once (the caller
    halves the step: cheaper).  With ``z_base`` (the last point) and ``max_angle``: a
    quasi-Newton solution whose secant from ``z_base`` leaves the tangent ``t`` by more
    than max_angle / 2 is refused before its orbit with the variational equations is
    integrated (``prob.secant_rejected``): on an arc the tangent turns by twice the
    secant's angle, so the new tangent would turn by more than max_angle.  ``between``:
    called once after the quasi-Newton stage, before the first orbit with the variational
    equations (the continuation finishes its last point there, whose multipliers were
    computed in a thread meanwhile); ``prob``'s record of this call survives it."""
    tol = prob.method.tol
    z = z_pred.copy()
    prob.quasi_newton_iterations = None
    prob.secant_rejected = False
    if J0 is not None:
        got = _quasi_newton(prob, z_pred, t, J0, QUASI_NEWTON_ITER, max_move, H0)
        if got is not None:
            z, prob.quasi_newton_iterations = got
            if z_base is not None and max_angle is not None:
                sec = z - z_base
                c = float(sec @ t) / max(float(np.linalg.norm(sec)), 1e-300)
                if np.arccos(np.clip(c, -1.0, 1.0)) > 0.5 * max_angle:
                    prob.secant_rejected = True
                    return None
        elif not exact_fallback:
            prob.last_failure = Status.NOT_CONVERGED
            return None
    if between is not None:
        record = (prob.quasi_newton_iterations, prob.secant_rejected, prob.last_failure,
                  prob.last_orbit)
        between()
        (prob.quasi_newton_iterations, prob.secant_rejected, prob.last_failure,
         prob.last_orbit) = record
    res_prev, stalled = np.inf, 0
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
            if np.linalg.norm(z - z_pred) > EXACT_MOVE * max_move:
                return None               # crossed over to another sheet: a smaller step
            return z, f, it, res
        stalled = stalled + 1 if res > NEWTON_CONTRACTION * res_prev else 0
        if it == max_iter or stalled == NEWTON_STALLED:
            return None
        res_prev = res
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


def predictor(z: np.ndarray, t: np.ndarray, ds: float, t_prev=None, ds_prev=None) -> np.ndarray:
    """z + ds t, plus the second-order term where the last step's tangent change gives one
    (the tangent's change estimates the curvature; left out where it exceeds ds / 4)."""
    pred = z + ds * t
    if t_prev is not None:
        bend = 0.5 * ds * ds * (t - t_prev) / ds_prev
        if np.linalg.norm(bend) < 0.25 * ds:
            pred = pred + bend
    return pred


def tangent_turned(prob: CorrectorProblem, t_new: np.ndarray, t: np.ndarray,
                   max_angle: float) -> bool:
    """The new tangent turned by more than ``max_angle`` from ``t`` (counted as a rejected
    step: the step is too long for the branch's curvature)."""
    if np.arccos(np.clip(t_new @ t, -1, 1)) > max_angle:
        prob.rejected["angle"] += 1
        return True
    return False


def adapted_step(ds: float, prob: CorrectorProblem, it: int, ds_min: float,
                 ds_max: float) -> float:
    """The next step after an accepted one: x1.5 (up to ``ds_max``) where the corrector
    needed few iterations (quasi-Newton: <= QUASI_NEWTON_GROW; exact Newton: <= 2), x0.7
    where it needed many (>= QUASI_NEWTON_SHRINK; >= 5), at least ``ds_min``."""
    qn = prob.quasi_newton_iterations
    if qn is not None and it == 0:
        grow, shrink = qn <= QUASI_NEWTON_GROW, qn >= QUASI_NEWTON_SHRINK
    else:
        grow, shrink = it <= 2, it >= 5
    ds = min(ds * 1.5, ds_max) if grow else (ds * 0.7 if shrink else ds)
    return max(ds, ds_min)
