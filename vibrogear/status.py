"""One status enumeration for every solver, with one table of messages.

Every solver result (integration, shooting, static equilibrium, sweep, continuation)
carries a :class:`Status` and a message that starts from :data:`MESSAGES`, and shows the
same face, :class:`Outcome`, through its ``outcome`` property: status, message, counters,
wall time and error estimate, of one shape everywhere, for scripts and post-processing
that take any result.  An analysis that runs several solves (the runs of a run-up, the
sweeps of a map, the starts of a census, the backbones of ``nnm``) hands the runner one
outcome, :meth:`Outcome.combine` of its solves': counters summed in one place, not by hand.
The compiled
integrator loop returns plain negative integers (numba has no enums); they are the values
of the integrator members below and become a :class:`Status` in one place,
:func:`from_code`.  The integers are also what ``sweep.npz`` stores per point, so the files
keep their meaning: 0 ok, < 0 integrator failure (see the table), > 0 a failure of the
solver above the integrator.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

__all__ = ["Status", "MESSAGES", "from_code", "SUCCESS", "Outcome"]


class Status(IntEnum):
    OK = 0
    # ---- integrator (values used inside the compiled loop, solvers/integrator/dopri.py)
    MAX_STEPS = -1
    NONFINITE = -2
    CHATTERING = -3
    STEP_TOO_SMALL = -4
    GRAZING = -5
    DIVERGED = -6               # checked after the loop (solvers/integrator/trust.py)
    INACCURATE = -7
    BAD_PARAMETER = -10
    # ---- solvers above the integrator
    PARTIAL = 1                 # a sweep: some points failed (the others are kept)
    STOPPED_BY_CALLBACK = 2
    NOT_CONVERGED = 3           # Newton: iteration limit reached
    SINGULAR = 4                # Newton: singular Jacobian
    LINE_SEARCH_FAILED = 5
    LEFT_RANGE = 6              # continuation: the branch left the parameter range (done)
    REJOINED = 7                # continuation: period-n branch rejoined the period-1 branch
    MAX_POINTS = 8
    DS_TOO_SMALL = 9            # continuation: step below ds_min
    NO_START = 10               # continuation: no starting orbit
    SWITCH_FAILED = 11          # continuation: could not switch onto the period-2 branch
    GRAZING_END = 12            # continuation: the branch ends at a grazing contact

    @property
    def message(self) -> str:
        return MESSAGES[self]

    @property
    def success(self) -> bool:
        """The solver finished its job (a continuation that left its range has)."""
        return self in SUCCESS

    @property
    def text(self) -> str:
        """The short name written to files (``"ok"``, ``"max_steps"``, ...)."""
        return self.name.lower()


MESSAGES = {
    Status.OK: "ok",
    Status.MAX_STEPS: "maximum number of steps reached",
    Status.NONFINITE: "non-finite state (the solution blew up)",
    Status.CHATTERING: "too many events without progress (chattering / Zeno behaviour at a "
                       "contact)",
    Status.STEP_TOO_SMALL: "step size underflow",
    Status.GRAZING: "grazing switch with a jumping vector field: saltation undefined",
    Status.DIVERGED: "diverged (the state left its physical bounds)",
    Status.INACCURATE: "inaccurate (the error estimate or the contact events show the "
                       "tolerance is too loose for this model)",
    Status.BAD_PARAMETER: "excitation frequency must be finite and > 0",
    Status.PARTIAL: "some points failed",
    Status.STOPPED_BY_CALLBACK: "stopped by the callback",
    Status.NOT_CONVERGED: "maximum Newton iterations reached",
    Status.SINGULAR: "singular Jacobian",
    Status.LINE_SEARCH_FAILED: "Newton line search failed",
    Status.LEFT_RANGE: "left the parameter range",
    Status.REJOINED: "rejoined the period-1 branch",
    Status.MAX_POINTS: "maximum number of points reached",
    Status.DS_TOO_SMALL: "step size below ds_min",
    Status.NO_START: "no starting orbit",
    Status.SWITCH_FAILED: "could not switch onto the period-2 branch",
    Status.GRAZING_END: "the branch ends at a grazing contact (a contact starts or stops "
                        "touching: the flow is not differentiable there)",
}

SUCCESS = frozenset({Status.OK, Status.LEFT_RANGE, Status.REJOINED, Status.GRAZING_END})


@dataclass(frozen=True)
class Outcome:
    """The one face of a solver result (its ``outcome`` property).

    ``counters``: {name: int} (steps, rhs calls, iterations, flows, ... as the solver has
    them); ``error_estimate``: {name: float or None} (None: not available for this run);
    ``wall_s``: the solver's wall time."""
    status: Status
    message: str
    counters: dict
    wall_s: float
    error_estimate: dict

    def __post_init__(self):
        object.__setattr__(self, "status", Status(self.status))
        object.__setattr__(self, "counters", {str(k): int(v) for k, v in self.counters.items()})
        object.__setattr__(self, "error_estimate", {
            str(k): (None if v is None or not math.isfinite(float(v)) else float(v))
            for k, v in self.error_estimate.items()})
        object.__setattr__(self, "wall_s", float(self.wall_s))

    @property
    def ok(self) -> bool:
        return self.status.success

    @classmethod
    def combine(cls, outcomes, *, status: Status | None = None, message: str | None = None,
                wall_s: float | None = None) -> "Outcome":
        """One outcome of several solves.

        ``counters``: each name summed over the solves; ``error_estimate``: each name's
        largest value (None where no solve has one); ``wall_s``: the solves' wall times
        summed, unless given (the analysis's own clock, where the solves ran side by side).
        ``status`` / ``message``, unless given: :attr:`Status.OK` where every solve
        succeeded (none at all included); the solves' one status where all failed alike;
        else :attr:`Status.PARTIAL`, "k of n solves failed", with the first failure's
        message."""
        outs = list(outcomes)
        counters: dict = {}
        errors: dict = {}
        for o in outs:
            for k, v in o.counters.items():
                counters[k] = counters.get(k, 0) + v
            for k, v in o.error_estimate.items():
                old = errors.get(k)
                errors[k] = v if old is None else old if v is None else max(old, v)
        failed = [o for o in outs if not o.ok]
        if status is None:
            if not failed:
                status, text = Status.OK, MESSAGES[Status.OK]
            elif len(failed) == len(outs) and len({o.status for o in failed}) == 1:
                status, text = failed[0].status, failed[0].message
            else:
                status = Status.PARTIAL
                text = (f"{len(failed)} of {len(outs)} solves failed; the first: "
                        f"{failed[0].message}")
            message = text if message is None else message
        return cls(status, MESSAGES[Status(status)] if message is None else message, counters,
                   sum(o.wall_s for o in outs) if wall_s is None else wall_s, errors)


def from_code(code: int) -> Status:
    """The :class:`Status` of an integer code (from the compiled loop or a file)."""
    try:
        return Status(int(code))
    except ValueError:
        raise ValueError(f"unknown solver status code {code!r}") from None
