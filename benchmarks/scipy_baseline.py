"""The honest scipy baseline the project's integrator is compared against.

:func:`dense_rhs` writes the right-hand side of a :class:`~vibrogear.models.reduced.ReducedModel`
the way one would without the project: the linear part assembled ONCE per (model, param)
into a dense first-order matrix

    A = [[0, I], [-(W + P^T Kc(s) P), -(D + P^T Bc(s) P)]]      (2m x 2m, numpy)

and every contact evaluated vectorised in numpy on dense (nc, m) directions with the laws
of :func:`vibrogear.solvers.integrator.kernels.accel` (dead zones, one-sided contacts, exponents,
damping only in contact, mesh-stiffness and transmission-error harmonics, harmonic
forcing).  The contact mode is the sign of delta - gap at the evaluated state (the
compiled loop carries it as an input and switches it at located events; at any state
where the two agree the values are equal, see tests/test_scipy_baseline.py).

:func:`solve_points_scipy` integrates a list of parameter points like a sequential
sweep (each point from t = 0 for a whole number of excitation periods, seeded from the
previous end state) with ``scipy.integrate.solve_ivp(method="RK45")``.  There are NO
events in the baseline: RK45 steps straight across contact switches (the vector field
is only continuous there, so its error estimate shrinks the steps around them).  The
comparison with the compiled integrator is therefore made at equal *accuracy*: both are
measured against one tight-tolerance reference (see bench_gearbox_integrator.py).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

__all__ = ["DenseRHS", "dense_rhs", "PointResult", "solve_points_scipy", "monitored_deformation"]


class DenseRHS:
    """u' = A u + F(t) - [0; C^T f(C x - e(t), C v - e'(t))], dense numpy, counting calls."""

    def __init__(self, model, param: float):
        m = model.n_modes
        cp, ct, fo = model.coupling, model.contacts, model.forcing
        spin = model.spin_per_param * param
        K = np.diag(np.asarray(model.omega2, dtype=float))
        B = np.diag(np.asarray(model.damping, dtype=float))
        if cp.P.shape[0]:
            K = K + cp.P.T @ (cp.Kc0 + spin * cp.Kc1) @ cp.P
            B = B + cp.P.T @ (cp.Bc0 + spin * cp.Bc1) @ cp.P
        self.A = np.block([[np.zeros((m, m)), np.eye(m)], [-K, -B]])
        self.m = m
        self.W = model.excitation_frequency(param)
        H = model.n_harmonics
        self.hw = np.arange(1, H + 1) * self.W                 # harmonic circular frequencies
        self.F0 = np.array(fo.F0, dtype=float)
        self.Fcs = np.vstack([fo.Fc, fo.Fs]) if H else np.zeros((0, m))   # (2H, m)
        self.C = np.array(ct.directions, dtype=float)         # (nc, m) dense
        self.Ct = np.ascontiguousarray(self.C.T)
        self.k_hi, self.k_lo = np.array(ct.k_hi, float), np.array(ct.k_lo, float)
        self.g_hi, self.g_lo = np.array(ct.gap_hi, float), np.array(ct.gap_lo, float)
        self.p = np.array(ct.exponent, dtype=float)
        self.cdamp = np.array(ct.damping, dtype=float)
        self.kcs = np.hstack([ct.stiffness_cos, ct.stiffness_sin])     # (nc, 2H)
        self.ecs = np.hstack([ct.error_cos, ct.error_sin])             # (nc, 2H)
        # e'(t) = sum_h h W (-ec sin + es cos): the same (nc, 2H) table against [cos, sin]
        self.edcs = np.hstack([ct.error_sin * self.hw, -ct.error_cos * self.hw])
        self.calls = 0

    def _trig(self, t: float) -> np.ndarray:
        a = self.hw * t
        return np.concatenate([np.cos(a), np.sin(a)])

    def contact_forces(self, t: float, u) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(delta, delta', f) of every contact at (t, u); f = 0 inside the dead zone."""
        m = self.m
        cs = self._trig(t)
        delta = self.C @ u[:m] - self.ecs @ cs
        rate = self.C @ u[m:] - self.edcs @ cs
        mod = 1.0 + self.kcs @ cs
        s_hi = np.maximum(delta - self.g_hi, 0.0)
        s_lo = np.maximum(self.g_lo - delta, 0.0)             # 0 where g_lo = -inf
        f = mod * (self.k_hi * s_hi ** self.p - self.k_lo * s_lo ** self.p)
        f += np.where((delta > self.g_hi) | (delta < self.g_lo), self.cdamp * rate, 0.0)
        return delta, rate, f

    def __call__(self, t: float, u) -> np.ndarray:
        self.calls += 1
        m = self.m
        du = self.A @ u
        du[m:] += self.F0 + self._trig(t) @ self.Fcs
        if self.C.shape[0]:
            _, _, f = self.contact_forces(t, u)
            du[m:] -= self.Ct @ f
        return du


def dense_rhs(model, param: float) -> DenseRHS:
    """f(t, u) of ``model`` at ``param`` with its dense linear part built once (see module doc)."""
    return DenseRHS(model, param)


def monitored_deformation(model, param: float, t, x) -> np.ndarray:
    """delta_mon(t) = c_mon . x(t) - e_mon(t) for times t (k,) and displacements x (k, m)."""
    ct, j = model.contacts, model.monitor
    hw = np.arange(1, model.n_harmonics + 1) * model.excitation_frequency(param)
    a = np.outer(np.asarray(t, dtype=float), hw)
    return x @ ct.directions[j] - np.cos(a) @ ct.error_cos[j] - np.sin(a) @ ct.error_sin[j]


@dataclass(frozen=True, eq=False)
class PointResult:
    param: float
    wall_time: float       # s: RHS build + solve_ivp + extrema extraction
    cpu_time: float        # s: the same in process CPU time (robust on a loaded machine)
    solve_time: float      # s: solve_ivp alone
    rhs_calls: int
    steps: int             # accepted steps (interpolant segments)
    monitor_min: float     # extrema of the monitored deformation over the record window
    monitor_max: float
    u_end: np.ndarray
    status: int
    message: str

    @property
    def ok(self) -> bool:
        return self.status == 0


def _grid_extremum(t, q, k, sign, model, param, sol) -> float:
    """Refine a grid extremum sign*q[k] by the vertex of the parabola through its neighbours
    (evaluated on the dense output again, kept only if it improves the sample)."""
    if k == 0 or k == len(q) - 1:
        return float(q[k])
    q0, q1, q2 = q[k - 1], q[k], q[k + 1]
    den = q0 - 2.0 * q1 + q2
    if den == 0.0:
        return float(q1)
    dt = t[k + 1] - t[k]
    tv = t[k] + 0.5 * dt * (q0 - q2) / den
    qv = monitored_deformation(model, param, [tv], sol.sol(tv)[:model.n_modes][None, :])[0]
    return float(qv) if sign * qv > sign * q1 else float(q1)


def solve_points_scipy(model, params, u0, *, periods: int, rtol: float, atol: float,
                       record_from: int, samples_per_period: int = 200,
                       max_step_periods: float = np.inf) -> list[PointResult]:
    """Integrate each param for ``periods`` excitation periods (t = 0 .. periods T) with
    scipy RK45, the first from ``u0`` and each next one from the previous end state.

    ``record_from``: first recorded period; the extrema of the monitored contact
    deformation are taken over [record_from T, periods T] from the dense output sampled
    ``samples_per_period`` times per period, each extremum refined by a parabola through
    the samples around it.  A failed point (status != 0) keeps NaN extrema and the next
    point starts from the last good state.
    """
    if not 0 <= record_from < periods:
        raise ValueError("need 0 <= record_from < periods")
    seed = np.array(u0, dtype=float)
    out = []
    for param in np.atleast_1d(np.asarray(params, dtype=float)):
        wall, cpu = time.perf_counter(), time.process_time()
        f = dense_rhs(model, float(param))
        T = model.excitation_period(float(param))
        t1 = periods * T
        solve = time.perf_counter()
        sol = solve_ivp(f, (0.0, t1), seed, method="RK45", rtol=rtol, atol=atol,
                        dense_output=True, max_step=max_step_periods * T)
        solve = time.perf_counter() - solve
        qmin = qmax = np.nan
        if sol.status == 0:
            n_rec = periods - record_from
            t = np.linspace(record_from * T, t1, n_rec * samples_per_period + 1)
            q = monitored_deformation(model, float(param), t, sol.sol(t)[:model.n_modes].T)
            qmin = _grid_extremum(t, q, int(np.argmin(q)), -1.0, model, float(param), sol)
            qmax = _grid_extremum(t, q, int(np.argmax(q)), 1.0, model, float(param), sol)
            seed = sol.y[:, -1].copy()
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        out.append(PointResult(param=float(param), wall_time=wall, cpu_time=cpu,
                               solve_time=solve, rhs_calls=int(sol.nfev), steps=len(sol.t) - 1,
                               monitor_min=float(qmin), monitor_max=float(qmax),
                               u_end=sol.y[:, -1].copy(), status=int(sol.status),
                               message=sol.message))
    return out
