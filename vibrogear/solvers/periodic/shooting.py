"""Shooting for periodic orbits of a harmonically forced ReducedModel.

The orbit of period T = n 2 pi / W (period-n) starting at t = 0 (phase cos(W t) = 1)
solves G(u0) = u(T; u0) - u0 = 0.  The monodromy d u(T)/d u0 comes from the
variational equations integrated with the orbit (saltation at switches), so Newton
uses the exact Jacobian of the discretised flow; its eigenvalues are the Floquet
multipliers.

Free gears (orbit families).  A DOF without restoring force that touches nothing during
the period (a free gear floating in its backlash) makes the orbit one of a family: its
rigid shift v is mapped onto itself, M v = v, and M - I is singular.  The solver borders
it out (``neutral`` below): where :func:`~.floquet.neutral_directions` finds k such
directions (in modal coordinates a DOF without restoring force is a zero-frequency mode,
so the search runs over the positions of those modes, tested on M itself: every model is
covered, and one without zero-frequency modes pays nothing), Newton solves

    [[M - I, B], [V^T, 0]] [du; lam] = [-G; 0]

(V: the neutral right null vectors, the phase condition V^T du = 0 keeps the free
coordinate where it is; B: left null vectors, which the multiplier lam absorbs; the
matrix is nonsingular when the family is k-dimensional).  A genuine orbit has lam = 0 up
to the residual; a drift along the free coordinate (no orbit at all) leaves lam and the
residual finite and Newton reports it.  The k trivial multipliers 1 are reported
(``neutral``) and left out of the stability verdict.

Why a phase condition rather than only shooting over the rattle period: where the free
gear does touch a flank during n mesh periods the orbit is isolated and n-period shooting
alone works, but where it floats (the gear held off both flanks, or a long rattle cycle
not yet resolved) the family exists for every n, so n-period shooting cannot remove the
singularity.  The bordering costs one SVD of M - I restricted to the rigid modes per
Newton step (and one full SVD where a neutral direction exists).  The continuation analysis
also picks n from the settled trajectory's stroboscopic states
(:func:`vibrogear.solvers.sequential.sweep.classify_period`, the sweep's period detection), so the
two work together.  A family ends where the free coordinate starts touching (a grazing):
the continuation stops there with GRAZING_END.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass

import numpy as np

from ...models.reduced import ReducedModel
from .floquet import (floquet_multipliers, liouville_error, neutral_directions, split_trivial,
                      stability)
from ..integrator.integrate import IntegrationOptions, Trajectory, integrate
from ...status import Outcome, Status
from ...config.options import ShootingOptions

__all__ = ["PeriodicFlow", "periodic_flow", "periodic_residual", "ShootingResult", "shoot",
           "residual_norm", "newton_step"]


@dataclass(frozen=True, eq=False)
class PeriodicFlow:
    """G = u(T) - u0 and its derivatives with respect to u0 and the parameter."""
    G: np.ndarray
    dG_du0: np.ndarray       # monodromy - I
    dG_dparam: np.ndarray    # includes the change of the period T with the parameter
    monodromy: np.ndarray
    trajectory: Trajectory
    period: float

    @property
    def ok(self) -> bool:
        return self.trajectory.ok

    def neutral(self, model: ReducedModel) -> tuple[np.ndarray, np.ndarray]:
        """(V, B) of :func:`~.floquet.neutral_directions` for this orbit (cached)."""
        got = self.__dict__.get("_neutral")
        if got is None:
            got = neutral_directions(self.monodromy, model.omega2) if self.ok else (
                np.zeros((self.G.size, 0)),) * 2
            self.__dict__["_neutral"] = got
        return got

    def multipliers(self) -> np.ndarray:
        """The Floquet multipliers of this orbit (:func:`~.floquet.floquet_multipliers`,
        computed once: an eigen-solve of the monodromy costs ~20 ms at 292 states)."""
        got = self.__dict__.get("_multipliers")
        if got is None:
            job = self.__dict__.pop("_prefetch", None)
            if job is not None:
                job[0].join()
                got = job[1][0] if job[1] else None
            if got is None:
                got = floquet_multipliers(self.monodromy)
            self.__dict__["_multipliers"] = got
        return got

    def prefetch_multipliers(self) -> None:
        """Start the eigen-solve of :meth:`multipliers` in a thread (LAPACK releases the
        GIL): the continuation runs its next quasi-Newton corrector meanwhile, whose
        orbits keep one core busy and leave the other idle."""
        if "_multipliers" in self.__dict__ or "_prefetch" in self.__dict__:
            return
        out: list = []
        job = threading.Thread(target=lambda: out.append(floquet_multipliers(self.monodromy)),
                               daemon=True)
        self.__dict__["_prefetch"] = (job, out)
        job.start()


def newton_step(flow: PeriodicFlow, model: ReducedModel) -> np.ndarray:
    """The Newton step du on G(u0) = 0, bordered by the orbit family's neutral directions
    (phase condition V^T du = 0) where there are any; raises LinAlgError if singular."""
    V, B = flow.neutral(model)
    k = V.shape[1]
    if k == 0:
        return np.linalg.solve(flow.dG_du0, -flow.G)
    n = flow.G.size
    A = np.zeros((n + k, n + k))
    A[:n, :n] = flow.dG_du0
    A[:n, n:] = B
    A[n:, :n] = V.T
    return np.linalg.solve(A, -np.concatenate([flow.G, np.zeros(k)]))[:n]


def residual_norm(G: np.ndarray, u0: np.ndarray) -> float:
    """Periodicity residual, relative to the size of the orbit's state."""
    return float(np.linalg.norm(G) / (1.0 + np.linalg.norm(u0)))


def periodic_flow(model: ReducedModel, param: float, u0, *, n_periods: int = 1,
                  options: IntegrationOptions = IntegrationOptions(),
                  split=None, first_step: float | None = None) -> PeriodicFlow:
    """G, its derivatives and the monodromy over ``n_periods`` excitation periods;
    ``split``: a :class:`~.split_flow.ColumnSplit` of ``model`` (the variational
    equations on two cores); ``first_step``: the integrator's first trial step."""
    u0 = np.asarray(u0, dtype=float)
    T = n_periods * model.excitation_period(param)
    if split is not None:
        tr = split.integrate(param, u0, T, options, first_step)
    else:
        tr = integrate(model, param, u0, 0.0, T, options=options, variational=True,
                       first_step=first_step)
    n = u0.size
    dT_dp = -T / param if param != 0 else 0.0
    if model.omega_per_param == 0.0:
        dT_dp = 0.0
    dG_dp = tr.dparam + tr.f_end * dT_dp
    return PeriodicFlow(G=tr.u_end - u0, dG_du0=tr.monodromy - np.eye(n), dG_dparam=dG_dp,
                        monodromy=tr.monodromy, trajectory=tr, period=T)


def periodic_residual(model: ReducedModel, param: float, u0, *, n_periods: int = 1,
                      options: IntegrationOptions = IntegrationOptions(),
                      first_step: float | None = None) -> Trajectory:
    """The orbit without the variational equations (G = ``u_end - u0``): what a
    quasi-Newton corrector needs, at a small fraction of :func:`periodic_flow`'s cost
    (measured on the two-stage gearbox, 292 states: 2 ms against 0.39 s)."""
    T = n_periods * model.excitation_period(param)
    return integrate(model, param, np.asarray(u0, dtype=float), 0.0, T, options=options,
                     first_step=first_step)


@dataclass(frozen=True, eq=False)
class ShootingResult:
    u0: np.ndarray
    residual: float              # periodicity residual |u(T) - u0| / (1 + |u0|)
    iterations: int
    floquet: np.ndarray          # complex Floquet multipliers
    monodromy: np.ndarray
    period: float
    n_periods: int
    status: Status               # OK, NOT_CONVERGED, SINGULAR, LINE_SEARCH_FAILED or the
    message: str                 # integrator's failure
    wall_time: float
    monitor_min: float
    monitor_max: float
    impacts: int                 # contact losses of the monitored contact per orbit
    rhs_calls: int
    flows: int = 0               # orbits integrated (with the variational equations)
    integration_error: float = 0.0       # the last orbit's integrator error estimate
    liouville_det_error: float | None = None   # det M against Liouville's formula
    neutral: int = 0             # trivial multipliers 1: dimension of the orbit family
    #                              (a free gear touching nothing), bordered out by Newton

    @property
    def converged(self) -> bool:
        return self.status == Status.OK

    @property
    def stable(self) -> bool:
        """Orbitally stable: the nontrivial multipliers inside the unit circle."""
        return stability(self.floquet, trivial=self.neutral)

    @property
    def trivial_multipliers(self) -> np.ndarray:
        return split_trivial(self.floquet, self.neutral)[1]

    @property
    def counters(self) -> dict:
        return {"iterations": self.iterations, "flows": self.flows, "rhs_calls": self.rhs_calls}

    @property
    def error_estimate(self) -> dict:
        """Periodicity residual, the integrator's error estimate over the orbit and the
        monodromy's determinant against Liouville's formula (None with contact damping)."""
        return {"periodicity_residual": self.residual,
                "integration_error": self.integration_error,
                "liouville_det_error": self.liouville_det_error}

    @property
    def outcome(self) -> Outcome:
        return Outcome(self.status, self.message, self.counters, self.wall_time,
                       self.error_estimate)


def shoot(model: ReducedModel, param: float, u0_guess, *, n_periods: int = 1,
          options: IntegrationOptions = IntegrationOptions(),
          shooting: ShootingOptions = ShootingOptions(tol=1e-10),
          split=None) -> ShootingResult:
    """Newton on u(T; u0) - u0 with backtracking, bordered by the neutral directions of
    an orbit family (see the module docstring); bounded iterations.  ``split``: a
    :class:`~..integrator.split_flow.ColumnSplit` of ``model`` (the monodromy on two
    cores)."""
    wall = time.perf_counter()
    tol, max_iter = shooting.tol, shooting.max_iter
    u = np.array(u0_guess, dtype=float)
    n = u.size
    calls, flows = 0, 1
    flow = periodic_flow(model, param, u, n_periods=n_periods, options=options,
                         split=split)
    calls += flow.trajectory.rhs_calls
    it = 0
    status = Status.NOT_CONVERGED
    message = status.message
    res = residual_norm(flow.G, u) if flow.ok else np.inf
    while True:
        if not flow.ok:
            status, message = flow.trajectory.status, flow.trajectory.message
            break
        if res < tol:
            status, message = Status.OK, "converged"
            break
        if it >= max_iter:
            break
        it += 1
        try:
            du = newton_step(flow, model)
        except np.linalg.LinAlgError:
            status = Status.SINGULAR
            message = "singular shooting Jacobian (a multiplier 1 that is not a rigid shift)"
            break
        lam = 1.0
        accepted = False
        for _ in range(8):
            trial = u + lam * du
            f2 = periodic_flow(model, param, trial, n_periods=n_periods, options=options,
                               split=split)
            calls += f2.trajectory.rhs_calls
            flows += 1
            r2 = residual_norm(f2.G, trial) if f2.ok else np.inf
            if r2 < res or r2 < tol:
                u, flow, res, accepted = trial, f2, r2, True
                break
            lam *= 0.5
        if not accepted:
            status = Status.LINE_SEARCH_FAILED
            message = status.message
            break
    tr = flow.trajectory
    floq = floquet_multipliers(flow.monodromy) if flow.ok else np.full(n, np.nan + 0j)
    return ShootingResult(
        u0=u, residual=res, iterations=it, floquet=floq,
        monodromy=flow.monodromy, period=flow.period, n_periods=n_periods, status=status,
        message=message, wall_time=time.perf_counter() - wall,
        monitor_min=tr.monitor_min, monitor_max=tr.monitor_max, impacts=tr.monitor_losses,
        rhs_calls=calls, flows=flows, integration_error=tr.error_estimate,
        liouville_det_error=liouville_error(model, param, flow.period, floq) if flow.ok else None,
        neutral=flow.neutral(model)[0].shape[1] if flow.ok else 0,
    )
