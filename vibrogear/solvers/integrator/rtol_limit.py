"""The loosest rtol a model can use, found by measurement.

Why a measurement: the error controller of an explicit method keeps a model's fastest
modes stable only by shrinking the step.  At a loose tolerance those modes carry noise of
the tolerance's size; whether the contacts feel it depends on how stiff the contacts are,
how near the motion runs to a gap and how far the fastest master mode lies above the
excitation, which no closed form captures for a non-smooth gearbox.  So
:func:`loosest_rtol` integrates a short window (``periods`` excitation periods from the
given start state, by default the static equilibrium at the lowest speed of the scene)
at a ladder of tolerances, from tight to loose, against a reference at
:data:`REFERENCE_RTOL`, and keeps the loosest rung at which

* the run passes every check of :func:`vibrogear.solvers.integrator.trust.assess` (its status is OK);
* the monitored contact's extrema differ from the reference's by at most ``accuracy``
  times the reference's range (plus the reference's own size where the range is tiny);
* the contact events number the reference's, within 10 % + 2.

The ladder stops at the first rung that fails (a tolerance looser than a failing one is
not tried).  The result says which rung failed and why, so a message can name both the
tolerance that failed and the one that would do.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

from ...config.options import IntegrationOptions
from ...models.reduced import ReducedModel
from .integrate import integrate

__all__ = ["RtolLimit", "loosest_rtol", "LADDER", "REFERENCE_RTOL"]

#: the tolerances tried, tight to loose
LADDER = (1e-8, 1e-7, 1e-6, 1e-5, 3e-5, 1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 1e-1)
REFERENCE_RTOL = 1e-10


@dataclass(frozen=True)
class RtolLimit:
    """``rtol``: the loosest rung that passed (None: not even the tightest);
    ``failed_rtol``/``reason``: the first rung that failed (None: all passed)."""
    rtol: float | None
    param: float
    periods: int
    failed_rtol: float | None
    reason: str
    wall_s: float

    def describe(self, param_name: str = "param") -> str:
        at = f"{periods_text(self.periods)} from the start state at {param_name} = {self.param:g}"
        if self.rtol is None:
            return f"no rtol down to {LADDER[0]:g} is accurate ({self.reason}; {at})"
        tail = "" if self.failed_rtol is None else \
            f"; {self.failed_rtol:g} is not ({self.reason})"
        return f"rtol <= {self.rtol:g} is accurate for this model{tail} ({at})"


def periods_text(n: int) -> str:
    return f"{n} excitation period" + ("s" if n != 1 else "")


def _run(model, param, u0, T, periods, rtol, base, atol_per_rtol):
    opts = IntegrationOptions(**{**base, "rtol": rtol, "atol": atol_per_rtol * rtol})
    return integrate(model, param, u0, 0.0, periods * T, options=opts)


def loosest_rtol(model: ReducedModel, param: float, u0, *, periods: int = 20,
                 accuracy: float = 1e-2, up_to: float = LADDER[-1],
                 options: IntegrationOptions = IntegrationOptions()) -> RtolLimit:
    """Measure the loosest rtol of :data:`LADDER` below ``up_to``, and ``up_to`` itself as
    the last rung, that stays accurate over ``periods`` excitation periods from ``u0`` at
    ``param`` (see the module doc); atol / rtol on every rung is that of ``options``."""
    wall = time.perf_counter()
    base = {k: getattr(options, k) for k in ("max_steps", "max_events_per_step",
                                             "max_step_periods", "event_log", "max_error",
                                             "max_deformation", "max_events_per_period")}
    T = model.excitation_period(param)
    per = options.atol / options.rtol        # every rung keeps the ratio asked for
    ref = _run(model, param, u0, T, periods, REFERENCE_RTOL, base, per)
    if not ref.ok:
        return RtolLimit(None, param, periods, REFERENCE_RTOL, f"reference: {ref.message}",
                         time.perf_counter() - wall)
    lo, hi = ref.monitor_min, ref.monitor_max
    spread = max(hi - lo, 1e-3 * max(abs(lo), abs(hi)), 1e-300)
    best, failed, reason = None, None, ""
    for rtol in [r for r in LADDER if r < up_to] + [up_to]:   # the rtol asked for last
        tr = _run(model, param, u0, T, periods, rtol, base, per)
        err = max(abs(tr.monitor_min - lo), abs(tr.monitor_max - hi)) / spread
        if not tr.ok:
            failed, reason = rtol, tr.status.text
        elif not err <= accuracy:
            failed, reason = rtol, (f"monitored extrema off by {err:.2g} of their range, "
                                    f"more than {accuracy:g}")
        elif abs(tr.events - ref.events) > 0.1 * ref.events + 2:
            failed, reason = rtol, f"{tr.events} contact events against {ref.events}"
        if failed is not None:
            break
        best = rtol
    return RtolLimit(best, param, periods, failed, reason, time.perf_counter() - wall)
