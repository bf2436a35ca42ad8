"""Periodic orbits of the impact pair, exact: Newton on the exact flow's period map
(:mod:`.impact_exact`) with its exact monodromy; the orbit's extrema and Floquet multipliers.

Nothing here imports :mod:`vibrogear.solvers` (see the package docstring).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .impact_exact import FlowResult, ImpactParams, exact_dense, exact_flow
from .pwl_region import linear_periodic_state

__all__ = ["PeriodicOrbit", "periodic_orbit"]


# --------------------------------------------------------------------------
# periodic orbits
# --------------------------------------------------------------------------
@dataclass
class PeriodicOrbit:
    u0: np.ndarray
    period: float
    n_periods: int
    monodromy: np.ndarray
    floquet: np.ndarray
    residual: float
    iterations: int
    converged: bool
    flow: FlowResult
    q_min: float
    q_max: float

    @property
    def contact_sides(self) -> set:
        """Subset of {+1, -1}: the contact regions the orbit enters."""
        return {r for r in self.flow.regions_visited if r != 0}

    @property
    def stable(self) -> bool:
        return bool(np.max(np.abs(self.floquet)) < 1.0)


def _orbit_extrema(p, Omega, flow, n=4000):
    ts = np.linspace(flow.t0, flow.t1, n)
    ts = np.union1d(ts, flow.switch_times)
    u = exact_dense(p, Omega, None, flow.t0, ts, flow=flow)
    return float(u[:, 0].min()), float(u[:, 0].max())


def periodic_orbit(p: ImpactParams, Omega: float, u0_guess=None, *, n_periods: int = 1,
                   t0: float = 0.0, tol: float = 1e-13, max_iter: int = 60) -> PeriodicOrbit:
    """Periodic orbit of period T = 2 pi n / Omega by damped Newton on u(T; u0) - u0.

    The Jacobian is the exact monodromy minus identity.  Default initial guess:
    the linear-limit (no contact) periodic state.  ``tol`` applies to
    max|u(T) - u0| relative to max(1, |u0|).
    """
    T = 2.0 * np.pi * n_periods / Omega
    u = (linear_periodic_state(p.zeta, p.kappa, p.f_m, p.f_p, Omega, t0) if u0_guess is None
         else np.array(u0_guess, dtype=float))

    def resid(u):
        fl = exact_flow(p, Omega, u, t0, t0 + T, stm=True)
        return fl.u_end - u, fl

    F, fl = resid(u)
    nF = np.max(np.abs(F))
    it = 0
    converged = nF <= tol * max(1.0, np.max(np.abs(u)))
    while not converged and it < max_iter:
        it += 1
        J = fl.stm - np.eye(2)
        try:
            du = np.linalg.solve(J, -F)
        except np.linalg.LinAlgError:
            break
        lam = 1.0
        while True:
            un = u + lam * du
            Fn, fln = resid(un)
            nFn = np.max(np.abs(Fn))
            if nFn < nF or lam < 1e-6:
                break
            lam *= 0.5
        u, F, fl, nF = un, Fn, fln, nFn
        converged = nF <= tol * max(1.0, np.max(np.abs(u)))
    if converged:  # one extra polishing step (cheap, quadratic convergence)
        J = fl.stm - np.eye(2)
        un = u + np.linalg.solve(J, -F)
        Fn, fln = resid(un)
        if np.max(np.abs(Fn)) <= nF:
            u, F, fl, nF = un, Fn, fln, np.max(np.abs(Fn))
    qmin, qmax = _orbit_extrema(p, Omega, fl)
    return PeriodicOrbit(u0=u, period=T, n_periods=n_periods, monodromy=fl.stm,
                         floquet=np.linalg.eigvals(fl.stm), residual=float(nF), iterations=it,
                         converged=bool(converged), flow=fl, q_min=qmin, q_max=qmax)
