"""Static equilibrium of a ReducedModel under its mean load (the paper's start state).

Solves W x + P^T Kc P x + sum_j c_j f_j(c_j . x - e_j(0)) = F0 (velocities zero, mean
mesh stiffness, transmission error at t = 0 left out: e is the dynamic excitation)
by a semi-smooth Newton method with backtracking; bounded iterations.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..models.contact_law import evaluate_set
from ..models.reduced import ReducedModel
from ..status import Outcome, Status

__all__ = ["StaticResult", "static_equilibrium", "static_forces"]


@dataclass(frozen=True, eq=False)
class StaticResult:
    x: np.ndarray
    u0: np.ndarray          # [x, 0]
    residual: float         # |force residual| / (1 + |F0|): the error estimate
    iterations: int
    message: str
    status: Status = Status.OK      # OK or NOT_CONVERGED
    wall_time: float = 0.0

    @property
    def converged(self) -> bool:
        return self.status == Status.OK

    @property
    def counters(self) -> dict:
        return {"iterations": self.iterations}

    @property
    def error_estimate(self) -> dict:
        return {"relative_force_residual": self.residual}

    @property
    def outcome(self) -> Outcome:
        return Outcome(self.status, self.message, self.counters, self.wall_time,
                       self.error_estimate)


def static_forces(model: ReducedModel, x: np.ndarray, param: float, mu: float = 0.0):
    """(r, J) at rest at the positions x: the residual r = F0 - (restoring forces + mu x)
    and its negative Jacobian J = d(restoring forces)/dx + mu I (contacts through the one
    contact law, at zero velocity)."""
    ct, cp = model.contacts, model.coupling
    spin = model.spin_per_param * param
    Kc = cp.Kc0 + spin * cp.Kc1
    r = model.forcing.F0 - (model.omega2 + mu) * x
    J = np.diag(model.omega2 + mu).astype(float)
    if cp.P.shape[0]:
        r -= cp.P.T @ (Kc @ (cp.P @ x))
        J += cp.P.T @ Kc @ cp.P
    if ct.count:
        law = evaluate_set(ct, ct.directions @ x)     # at rest: no damping force
        r -= ct.directions.T @ law.force
        J += ct.directions.T @ (law.stiffness[:, None] * ct.directions)
    return r, J


def _newton(model, x, param, mu, tol, max_iter, scale):
    r, J = static_forces(model, x, param, mu)
    res = np.linalg.norm(r) / scale
    it = 0
    while res > tol and it < max_iter:
        it += 1
        try:
            dx = np.linalg.solve(J, r)
        except np.linalg.LinAlgError:
            dx = np.linalg.lstsq(J, r, rcond=None)[0]
        lam = 1.0
        for _ in range(30):
            r2, J2 = static_forces(model, x + lam * dx, param, mu)
            res2 = np.linalg.norm(r2) / scale
            if res2 < res or res2 <= tol:
                break
            lam *= 0.5
        x, r, J, res = x + lam * dx, r2, J2, res2
        if not np.all(np.isfinite(x)):
            break
    return x, res, it


def static_equilibrium(model: ReducedModel, param: float = 0.0, *, x0=None, tol: float = 1e-12,
                       max_iter: int = 100) -> StaticResult:
    """Newton from ``x0``; where the tangent stiffness is singular (a dead zone, a free
    gear) a homotopy adds a vanishing artificial stiffness mu I, mu -> 0."""
    wall = time.perf_counter()
    m = model.n_modes
    x = np.zeros(m) if x0 is None else np.array(x0, dtype=float)
    scale = 1.0 + np.linalg.norm(model.forcing.F0)
    ct = model.contacts
    k_ref = max(float(np.max(model.omega2, initial=0.0)),
                float(np.max(np.concatenate([ct.k_hi, ct.k_lo]), initial=0.0)), 1e-30)
    its = 0
    x, res, it = _newton(model, x, param, 0.0, tol, max_iter, scale)
    its += it
    if not (res <= tol and np.all(np.isfinite(x))):
        x = np.zeros(m) if x0 is None else np.array(x0, dtype=float)
        for mu in [k_ref * 10.0 ** -k for k in range(0, 13)] + [0.0]:
            x, res, it = _newton(model, x, param, mu, tol if mu == 0 else 1e-10, max_iter, scale)
            its += it
    ok = bool(res <= tol and np.all(np.isfinite(x)))
    return StaticResult(x=x, u0=np.concatenate([x, np.zeros(m)]),
                        residual=float(res), iterations=its,
                        message="converged" if ok else "no static equilibrium found "
                        "(unloaded free body or load beyond every contact)",
                        status=Status.OK if ok else Status.NOT_CONVERGED,
                        wall_time=time.perf_counter() - wall)
