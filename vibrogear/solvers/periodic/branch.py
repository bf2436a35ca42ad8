"""The objects of a continuation: the problem (a periodic orbit of a model), the method
(shooting + pseudo-arclength with its settings) and the result (branches of points, special
points, status, counters, wall time, error estimates).  The options are
:class:`~vibrogear.config.options.ContinuationOptions`; the algorithm is
:func:`vibrogear.solvers.periodic.continuation.continuation`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...config.options import IntegrationOptions
from ...models.reduced import ReducedModel
from .floquet import split_trivial, stability
from ...status import Outcome, Status

__all__ = ["PeriodicOrbitProblem", "PseudoArclength", "BranchPoint", "Branch", "SpecialPoint",
           "ContinuationResult", "stability_notes", "branch_arrays"]


@dataclass(frozen=True, eq=False)
class PeriodicOrbitProblem:
    """The period-``n_periods`` orbit of ``model`` through (``u0``, ``param``): ``u0`` is (close
    to) its state at t = 0; ``direction`` = -1 continues towards smaller parameter first."""
    model: ReducedModel
    u0: np.ndarray
    param: float
    n_periods: int = 1
    direction: int = -1

    def __post_init__(self):
        object.__setattr__(self, "u0", np.array(self.u0, dtype=float))
        if self.u0.shape != (self.model.n_states,):
            raise ValueError(f"u0 must have {self.model.n_states} entries")
        if self.direction not in (-1, 1) or self.n_periods < 1:
            raise ValueError("direction must be -1 or +1 and n_periods >= 1")


@dataclass(frozen=True)
class PseudoArclength:
    """Shooting (the orbit's residual H(u0, p) = u(T) - u0 with its exact Jacobian from the
    variational equations) + pseudo-arclength steps: Keller's corrector to ``tol`` (relative
    periodicity residual), a second-order predictor, at most ``max_angle`` radians between
    successive tangents, at most ``locate_iter`` regula-falsi steps per special point (fewer
    once successive iterates differ by less than ``locate_tol`` of the step).  The
    arclength measures the parameter divided by ``param_scale``; the options' ds, ds_min,
    ds_max are in parameter units (a step along the parameter axis moves it by ds)."""
    integration: IntegrationOptions = IntegrationOptions()
    tol: float = 1e-9
    param_scale: float = 1.0
    max_angle: float = 0.35
    locate_iter: int = 10
    locate_tol: float = 1e-5           # a special point is located when successive
    #                                    regula-falsi iterates differ by < this x the step
    quasi_newton: bool = True          # the corrector's Broyden stage (solvers/periodic/corrector.py)
    start_max_iter: int | None = None   # Newton iterations for the starting orbit
    #                                     (default: 3 x the options' max_corrector_iter)
    split_columns: bool = True          # orbits with the monodromy on two cores where it
    #                                     pays (solvers/integrator/split_flow.py; same numbers)

    def __post_init__(self):
        if not (0 < self.tol < 1 and self.param_scale > 0 and 0 < self.max_angle < np.pi
                and self.locate_iter >= 1 and (self.start_max_iter or 1) >= 1
                and 0 < self.locate_tol < 1):
            raise ValueError("PseudoArclength: need 0 < tol < 1, param_scale > 0, "
                             "0 < max_angle < pi, locate_iter >= 1, start_max_iter >= 1, "
                             "0 < locate_tol < 1")


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
    integration_error: float = 0.0      # the orbit's integrator error estimate
    liouville_det_error: float | None = None
    neutral: int = 0        # trivial multipliers 1 (orbit family of a free DOF), bordered out
    located_within: float = 0.0     # special points: parameter width of the bracket that
    #                                 holds the test function's zero (0: not a special point)

    @property
    def stable(self) -> bool:
        """Orbitally stable: the nontrivial multipliers inside the unit circle."""
        return stability(self.floquet, trivial=self.neutral)

    @property
    def max_abs_multiplier(self) -> float:
        """Largest |multiplier| among the nontrivial ones (those that decide stability)."""
        mu = np.abs(split_trivial(self.floquet, self.neutral)[0])
        return float(mu.max()) if mu.size else 0.0


@dataclass(frozen=True, eq=False)
class Branch:
    points: tuple           # BranchPoint, in order of continuation
    n_periods: int          # 1: period-1 branch, 2: period-2 branch
    status: Status          # LEFT_RANGE / REJOINED / GRAZING_END when done, else
    #                         why it stopped
    message: str
    period_scale: float     # period of the orbit = period_scale / param (n_periods excitation periods)
    counters: dict = field(default_factory=dict)
    wall_time: float = 0.0

    def array(self, name: str) -> np.ndarray:
        return np.array([getattr(p, name) for p in self.points])


@dataclass(frozen=True)
class SpecialPoint:
    label: str              # LP, PD or NS
    param: float
    branch: int             # index into ContinuationResult.branches
    index: int              # index into that branch's points


@dataclass(frozen=True, eq=False)
class ContinuationResult:
    """Branches of periodic orbits traced by shooting + pseudo-arclength continuation.

    ``branches``: the period-1 branch, then the period-2 branch of its first period doubling;
    each point has the parameter, the start state ``u0`` (n,) [model units], the Floquet
    multipliers, ``qmin`` / ``qmax`` [model length: m for a gearbox] of the monitored
    deformation over the orbit, ``impacts`` per period, ``stable``, ``label`` ("", "LP",
    "PD", "NS": fold, period doubling, Neimark-Sacker).  ``special_points``: those
    bifurcations; ``status``, ``message``, ``counters``, ``wall_time`` [s]: the solver's.

    :meth:`arrays` (the names of ``branch.npz``; M points of all branches, n states):
    ``param`` (M,) [rpm or Omega], ``period`` (M,) [model time units],
    ``u0`` (M, n) [model units], ``floquet`` (M, n) complex [1], ``stable`` (M,) bool,
    ``label`` (M,) str, ``branch`` (M,) int (index of the branch), ``n_periods`` (M,) int
    (excitation periods per orbit), ``qmin`` / ``qmax`` (M,) [model length: m],
    ``impacts`` (M,) int [1/orbit], ``residual`` (M,) [1] shooting residual, ``neutral`` (M,)
    int, ``max_abs_multiplier`` (M,) [1]."""
    branches: tuple         # Branch: the period-1 branch, then the period-2 branch of its PD
    special_points: tuple   # SpecialPoint, branch by branch in order of continuation
    status: Status
    message: str
    counters: dict
    wall_time: float

    @property
    def error_estimate(self) -> dict:
        """Worst periodicity residual, integrator error estimate and Liouville determinant
        error over all points (the last None where a contact is damped)."""
        pts = [p for b in self.branches for p in b.points]
        dets = [p.liouville_det_error for p in pts if p.liouville_det_error is not None]
        return {"max_periodicity_residual": max((p.residual for p in pts), default=None),
                "max_integration_error": max((p.integration_error for p in pts), default=None),
                "liouville_det_error": max(dets) if dets else None}

    def arrays(self) -> dict:
        """The arrays of ``branch.npz`` (see the class docstring)."""
        return branch_arrays(self.branches)

    @property
    def outcome(self) -> Outcome:
        return Outcome(self.status, self.message,
                       {k: v for k, v in self.counters.items() if isinstance(v, (int, np.integer))
                        and not isinstance(v, bool)}, self.wall_time, self.error_estimate)


def branch_arrays(branches) -> dict:
    """The arrays ``branch.npz`` holds: the points of all branches (period-1 first)
    concatenated into flat arrays (:class:`ContinuationResult` documents them)."""
    rows = [(b_i, b, p) for b_i, b in enumerate(branches) for p in b.points]
    n = rows[0][2].u0.size if rows else 0
    param = np.array([p.param for _, _, p in rows], dtype=float)
    scale = np.array([b.period_scale for _, b, _ in rows], dtype=float)
    return {
        "param": param,
        "period": scale / param if rows else np.zeros(0),
        "u0": np.array([p.u0 for _, _, p in rows]).reshape(len(rows), n),
        "floquet": np.array([p.floquet for _, _, p in rows], dtype=complex).reshape(len(rows), n),
        "stable": np.array([p.stable for _, _, p in rows], dtype=bool),
        "label": np.array([p.label for _, _, p in rows], dtype="<U2"),
        "branch": np.array([i for i, _, _ in rows], dtype=np.int64),
        "n_periods": np.array([b.n_periods for _, b, _ in rows], dtype=np.int64),
        "qmin": np.array([p.qmin for _, _, p in rows], dtype=float),
        "qmax": np.array([p.qmax for _, _, p in rows], dtype=float),
        "impacts": np.array([p.impacts for _, _, p in rows], dtype=np.int64),
        "residual": np.array([p.residual for _, _, p in rows], dtype=float),
        "neutral": np.array([p.neutral for _, _, p in rows], dtype=np.int64),
        "max_abs_multiplier": np.array([p.max_abs_multiplier for _, _, p in rows], dtype=float),
    }


def stability_notes(pts, name: str) -> str:
    """Where the branch loses stability at an NS point: the motion there leaves the
    periodic orbit for a torus (quasi-periodic), stated in the branch's message."""
    notes = []
    for k, p in enumerate(pts):
        if p.label == "NS" and 0 < k < len(pts) - 1:
            a, b = pts[k - 1].stable, pts[k + 1].stable
            if a != b:
                notes.append(f"stable orbit ends at NS {name} = {p.param:.6g} (onto a torus)")
    return "".join(f"; {n}" for n in notes)
