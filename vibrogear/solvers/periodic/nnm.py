"""Nonlinear normal modes by shooting and pseudo-arclength continuation (Peeters, Viguie,
Kerschen et al. 2009): the backbone of one linear mode of the conservative system.

The problem and its bordering are in :mod:`.nnm_problem`; the corrector (quasi-Newton on
orbits alone, then Newton on orbits with the variational equations) is the forced
continuation's, :func:`~.corrector.correct`, with its tangent (:func:`~.corrector.tangent`).
The branch starts on the linear mode at ``energy_min`` (x = x_s + a phi, velocities zero,
E = omega^2 a^2 / 2 above the static state: exact while no contact switches) and is walked
towards growing energy.  Steps are relative: the arclength of a step is ``ds`` times the
orbit's distance |u0 - u_s| from the static state, so the points are spaced evenly in log
amplitude where the backbone is straight; ``ds`` grows (x 1.5, up to ``ds_max``) after easy
correctors and halves after failed ones.  The branch ends when the energy leaves
[energy_min, energy_max] (LEFT_RANGE), after ``max_points`` or where the step falls below
``ds_min``.

Per point: energy, frequency, the monitored contact's extrema, the Floquet multipliers with
the trivial ones (2 + 2 per neutral free coordinate, nearest 1) split off and reported, and
stability from the others: an orbit of a conservative system is at best neutrally stable,
so it is stable when every nontrivial multiplier lies on the unit circle within
``stability_tol`` and unstable when one lies outside.  Labels: where the energy turns along
the branch (a tongue's fold), ``IR p:q`` when the ratio of another linear mode's frequency
to the NNM's lies within ``rational_tol`` of a small rational p/q (p, q <= ``rational_max``:
an internal resonance; of several, the lowest order p + q), else ``LP``.
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Callable

import numpy as np

from ...config.options import NnmMethod
from ...pipeline.executors import blas_threads
from ...status import Outcome, Status
from .branch import PseudoArclength
from .corrector import (QUASI_NEWTON_MOVE, adapted_step, correct, predictor, tangent,
                        tangent_turned)
from .floquet import liouville_error, split_trivial
from .nnm_problem import NnmCorrectorProblem, energy, energy_gradient, phase_vector
from .special_points import switch_counts

__all__ = ["NnmMethod", "NnmPoint", "NnmBranch", "nnm_branch", "rational_near"]


@dataclass(frozen=True, eq=False)
class NnmPoint:
    omega: float                # circular frequency (model time units)
    energy: float               # above the static state (model units)
    u0: np.ndarray
    qmin: float                 # extrema of the monitored contact's deformation
    qmax: float
    floquet: np.ndarray         # nontrivial multipliers
    trivial: np.ndarray         # trivial multipliers (2 + 2 per neutral free coordinate)
    residual: float
    iterations: int
    integration_error: float
    liouville_det_error: float | None
    neutral: int                # bordered directions: 1 (phase) + neutral free coordinates
    tangent: np.ndarray
    stability_tol: float
    label: str = ""

    @property
    def period(self) -> float:
        return 2 * np.pi / self.omega

    def excursion(self, delta_static: float) -> float:
        """The monitored deformation's largest excursion from ``delta_static``."""
        return max(abs(self.qmax - delta_static), abs(self.qmin - delta_static))

    @property
    def amplitude(self) -> float:
        """max |delta| over the orbit of the monitored contact's deformation."""
        return max(abs(self.qmin), abs(self.qmax))

    @property
    def max_abs_multiplier(self) -> float:
        return float(np.max(np.abs(self.floquet))) if self.floquet.size else 1.0

    @property
    def stable(self) -> bool:
        """Every nontrivial multiplier on the unit circle (within ``stability_tol``)."""
        return self.max_abs_multiplier <= 1.0 + self.stability_tol


@dataclass(frozen=True, eq=False)
class NnmBranch:
    points: tuple
    mode: int                   # index of the start mode among the elastic modes
    omega_linear: float         # its linear circular frequency
    status: Status
    message: str
    counters: dict = field(default_factory=dict)
    wall_time: float = 0.0

    def array(self, name: str) -> np.ndarray:
        return np.array([getattr(p, name) for p in self.points])

    @property
    def outcome(self) -> Outcome:
        return Outcome(self.status, self.message,
                       {k: v for k, v in self.counters.items() if isinstance(v, (int, np.integer))
                        and not isinstance(v, bool)}, self.wall_time, self.error_estimate)

    @property
    def error_estimate(self) -> dict:
        dets = [p.liouville_det_error for p in self.points if p.liouville_det_error is not None]
        return {"max_periodicity_residual": max((p.residual for p in self.points), default=None),
                "max_integration_error": max((p.integration_error for p in self.points),
                                             default=None),
                "liouville_det_error": max(dets) if dets else None}


def rational_near(ratio: float, max_order: int, tol: float) -> Fraction | None:
    """The small rational p/q (p, q <= max_order) nearest ``ratio`` within the relative
    ``tol``, else None."""
    best = None
    for q in range(1, max_order + 1):
        for p in range(1, max_order + 1):
            r = Fraction(p, q)
            err = abs(ratio - float(r)) / float(r)
            if err <= tol and (best is None or err < best[0]):
                best = (err, r)
    return None if best is None else best[1]


class _Stop(Exception):
    pass


def _point(prob, z, f, t, it, res, method, k) -> NnmPoint:
    tr = f.trajectory
    mu = f.multipliers()
    keep, trivial = split_trivial(mu, 2 * k)
    om = float(z[-1] * prob.scale)
    return NnmPoint(omega=om, energy=0.0, u0=z[:-1].copy(), qmin=tr.monitor_min,
                    qmax=tr.monitor_max, floquet=keep, trivial=trivial, residual=res,
                    iterations=it, integration_error=tr.error_estimate,
                    liouville_det_error=liouville_error(prob.model, om, f.period, mu),
                    neutral=k, tangent=t.copy(), stability_tol=method.stability_tol)


def _with(p: NnmPoint, **kw) -> NnmPoint:
    return dataclasses.replace(p, **kw)


def nnm_branch(model, u_static: np.ndarray, omega0: float, phi: np.ndarray, method: NnmMethod,
               *, rigid: np.ndarray | None = None, mode: int = 0,
               other_omegas: np.ndarray = np.zeros(0),
               callback: Callable[[NnmPoint], bool | None] | None = None) -> NnmBranch:
    """The backbone of the linear mode (``omega0``, unit ``phi``) of the conservative
    ``model`` (:func:`~.nnm_problem.conservative_model`) about its static state
    ``u_static``; ``rigid``: the free coordinates' basis (m x r); ``other_omegas``: the
    other modes' linear frequencies (internal-resonance labels).  ``callback(point)``
    returning False stops the branch (STOPPED_BY_CALLBACK)."""
    with blas_threads(1):
        return _branch(model, np.asarray(u_static, float), float(omega0),
                       np.asarray(phi, float), method, rigid, mode, np.asarray(other_omegas),
                       callback)


def _branch(model, us, omega0, phi, method, rigid, mode, others, callback) -> NnmBranch:
    wall = time.perf_counter()
    m = model.n_modes
    rigid = np.zeros((m, 0)) if rigid is None else rigid
    phi = phi / np.linalg.norm(phi)
    e_s = energy(model, us)
    a0 = np.sqrt(2 * method.energy_min) / omega0
    u_start = us.copy()
    u_start[:m] += a0 * phi
    # arclength metric: a relative frequency change counts like the start orbit's size
    scale = omega0 / max(a0, 1e-300)
    pa = PseudoArclength(integration=method.integration, tol=method.tol, param_scale=scale,
                         max_angle=method.max_angle, quasi_newton=method.quasi_newton,
                         split_columns=False)
    prob = NnmCorrectorProblem(model, pa, phase_vector(model, phi, method.phase), rigid)
    pts: list[NnmPoint] = []
    counters = lambda: {"flows": prob.flows, "plain_flows": prob.plain_flows,   # noqa: E731
                        "rhs_calls": prob.rhs_calls, "rejected_angle": prob.rejected["angle"],
                        "rejected_corrector": prob.rejected["corrector"]}

    def emit(p):
        pts.append(p)
        if callback is not None and callback(p) is False:
            raise _Stop

    z0 = np.concatenate([u_start, [omega0 / scale]])
    t0 = np.zeros_like(z0)
    t0[:m] = phi
    t0 /= np.linalg.norm(t0)
    _set_tol(prob, z0, us, method)
    got = correct(prob, z0, t0, 3 * method.max_corrector_iter)
    if got is None:
        why = prob.last_failure.message if prob.last_failure else "Newton did not converge"
        return NnmBranch((), mode, omega0, Status.NO_START, f"{Status.NO_START.message}: "
                         f"{why}", counters(), time.perf_counter() - wall)
    status, message = Status.LEFT_RANGE, ""
    try:
        status, message = _walk(prob, got, t0, us, e_s, method, others, emit, pts)
    except _Stop:
        status, message = Status.STOPPED_BY_CALLBACK, f"after {len(pts)} points"
    msg = status.message + (f": {message}" if message else "")
    return NnmBranch(tuple(pts), mode, omega0, status, msg, counters(),
                     time.perf_counter() - wall)


def _set_tol(prob, z, us, method) -> None:
    """The corrector's tolerance on |u(T) - u0| / (1 + |u0|) (:func:`~.shooting.residual_norm`)
    that holds the residual to ``method.tol`` times the orbit's size |u0 - u_s| (a gearbox's
    states are ~1e-5: a residual relative to 1 + |u0| alone would be far too loose), but
    no tighter than the integration can deliver (10 rtol |u0| + atol: a small orbit about a
    large static state)."""
    u = z[:-1]
    opts = method.integration
    size, big = float(np.linalg.norm(u - us)), float(np.linalg.norm(u))
    tol = max(method.tol * size, 10 * opts.rtol * big + opts.atol) / (1.0 + big)
    prob.method = dataclasses.replace(prob.method, tol=min(max(tol, 1e-15), 0.5))


def _orient(t, grad_e, n):
    """The tangent pointing towards growing energy."""
    return -t if float(grad_e @ t[:n]) < 0 else t


def _walk(prob, got, t_hint, us, e_s, method, others, emit, pts):
    model = prob.model
    n = us.size
    z, f, it, res = got
    J = prob.jac(f)
    k = prob.neutral(f)
    t = tangent(J, t_hint)
    t = _orient(t, energy_gradient(model, z[:-1]), n)
    e_prev = energy(model, z[:-1]) - e_s
    emit(_with(_point(prob, z, f, t, it, res, method, k), energy=e_prev))
    h = method.ds                     # relative step
    t_prev = ds_prev = None
    qn_failed = 0
    de_prev = float(energy_gradient(model, z[:-1])[:n] @ t[:n])
    while True:
        if len(pts) >= method.max_points:
            return Status.MAX_POINTS, ""
        size = max(float(np.linalg.norm(z[:-1] - us)), 1e-300)
        ds = h * size
        pred = predictor(z, t, ds, t_prev, ds_prev)
        prob.last_failure = None
        _set_tol(prob, z, us, method)
        got = correct(prob, pred, t, method.max_corrector_iter, k,
                      J if method.quasi_newton else None,
                      exact_fallback=qn_failed > 0 or h <= 2 * method.ds_min,
                      max_move=QUASI_NEWTON_MOVE * ds, z_base=z,
                      max_angle=method.max_angle if h > method.ds_min else None)
        qn_failed = qn_failed + 1 if got is None and not prob.secant_rejected else 0
        if got is not None:
            z_new, f_new, it, res = got
            J_new = prob.jac(f_new)
            t_new = tangent(J_new, t)
            if h > method.ds_min and tangent_turned(prob, t_new, t, method.max_angle):
                got = None
        else:
            prob.rejected["angle" if prob.secant_rejected else "corrector"] += 1
        jumped = False
        if got is None:
            h *= 0.5
            if h >= method.ds_min:
                continue
            # the steps collapse where a contact interval appears or vanishes (a grazing:
            # the flow is not differentiable there); step over it with exact Newton
            got = _jump(prob, z, t, k, size, method)
            if got is None:
                why = prob.last_failure.message if prob.last_failure else "corrector failed"
                return Status.DS_TOO_SMALL, (f"at omega = {z[-1] * prob.scale:.6g} ({why})")
            z_new, f_new, it, res, h = got
            J_new = prob.jac(f_new)
            t_new = tangent(J_new, t)
            jumped = True
        k_new = prob.neutral(f_new)
        e_new = energy(model, z_new[:-1]) - e_s
        de_new = float(energy_gradient(model, z_new[:-1])[:n] @ t_new[:n])
        point = _point(prob, z_new, f_new, t_new, it, res, method, k_new)
        label = ""
        if np.sign(de_new) != np.sign(de_prev) and de_prev != 0:
            label = _fold_label(point.omega, others, method)
        elif jumped:
            label = "GR" if np.any(switch_counts(model, f_new.trajectory) != switch_counts(
                model, f.trajectory)) else "J"
        emit(_with(point, energy=e_new, label=label))
        t_prev, ds_prev = t, h * size
        h = adapted_step(h, prob, it, method.ds_min, method.ds_max)
        z, f, t, J, k, de_prev = z_new, f_new, t_new, J_new, k_new, de_new
        if e_new > method.energy_max:
            return Status.LEFT_RANGE, f"energy {e_new:.6g} above energy_max"
        if (method.excursion_max is not None
                and point.excursion(method.delta_static) > method.excursion_max):
            return Status.LEFT_RANGE, "excursion above amplitude_max"
        if e_new < method.energy_min * (1 - 1e-9):
            return Status.LEFT_RANGE, f"energy {e_new:.6g} below energy_min (the branch turned)"


#: relative steps tried, in this order, to step over a grazing (x the method's ds)
JUMP_STEPS = (1.0, 0.3, 3.0, 0.1)


def _jump(prob, z, t, k, size, method):
    """(z, flow, iterations, residual, h) of the first exact-Newton corrector that
    converges from a step of h = ds x JUMP_STEPS along the tangent, or None."""
    for c in JUMP_STEPS:
        h = c * method.ds
        got = correct(prob, z + h * size * t, t, 3 * method.max_corrector_iter, k)
        if got is not None and got[0][-1] > 0:
            return (*got, h)
    return None


def _fold_label(omega, others, method) -> str:
    """``IR p:q`` (another mode's linear frequency / omega near p/q) or ``LP``."""
    best = None
    for w in np.asarray(others, float):
        r = rational_near(w / omega, method.rational_max, method.rational_tol)
        if r is not None:
            # the lowest order p + q first (the strongest coupling), then the nearest
            key = (r.numerator + r.denominator, abs(w / omega - float(r)) / float(r))
            if best is None or key < best[0]:
                best = (key, r)
    if best is None:
        return "LP"
    return f"IR {best[1].numerator}:{best[1].denominator}"
