"""Time integration of a ReducedModel: the Python face of the compiled DOPRI5 loop."""
from __future__ import annotations

import math

import time
import weakref
from dataclasses import dataclass

import numpy as np

from ...config.options import IntegrationOptions   # defined once, with the [integration] rules
from ...models.reduced import ReducedModel
from .dopri import JAC_AUTO, JAC_BLAS, JAC_LOOPS, LoopResult, dopri_loop, loop_inputs
from .kernels import model_arrays
from ...status import Outcome, Status, from_code
from .trust import assess

__all__ = ["IntegrationOptions", "Trajectory", "integrate"]


@dataclass(frozen=True, eq=False)
class Trajectory:
    t: np.ndarray               # requested output times
    u: np.ndarray               # (len(t), n) states there (dense output)
    t_end: float
    u_end: np.ndarray
    status: Status              # OK, or an integrator failure (see message)
    message: str
    steps: int
    rejected: int
    rhs_calls: int
    events: int
    event_times: np.ndarray
    event_contacts: np.ndarray
    event_modes: np.ndarray
    monitor_min: float          # extrema of the monitored contact deformation after record_from
    monitor_max: float
    monitor_losses: int         # contact losses of the monitored contact after record_from
    final_modes: np.ndarray
    f_end: np.ndarray           # u' at t_end
    monodromy: np.ndarray | None = None   # d u_end / d u0
    dparam: np.ndarray | None = None      # d u_end / d param at fixed t_end
    #: with ``integrate(..., columns=(c0, c1))``: those columns of [monodromy | dparam] only
    #: (monodromy and dparam are then None)
    tangent_columns: np.ndarray | None = None
    wall_time: float = 0.0
    #: sum over the accepted steps of the RMS norm of the embedded 4th-order local error
    #: estimate (state units): a bound-like estimate of the global error of the embedded
    #: solution when errors do not grow along the flow (the 5th-order solution that is
    #: propagated is usually more accurate); 0 for an empty run
    error_estimate: float = 0.0
    #: error_estimate / the solution's size (RMS of the larger of start and end state); the
    #: run is INACCURATE above ``options.max_error`` (solvers/integrator/trust.py); NaN where the loop
    #: failed
    relative_error: float = float("nan")
    #: the step size the controller proposes after t_end: ``first_step`` of a run that
    #: continues this one
    h_next: float = float("nan")
    #: d delta / dt of the switching contact at each logged event (event_contacts): at a
    #: contact onset, the approach speed (the state the integrator located the switch at)
    event_rates: np.ndarray | None = None

    @property
    def counts(self) -> np.ndarray:
        """(steps, rejected, rhs calls, events): what a caller that integrates in pieces
        adds up (``counters += tr.counts``)."""
        return np.array([self.steps, self.rejected, self.rhs_calls, self.events], np.int64)

    @property
    def next_first_step(self) -> float | None:
        """``h_next`` as the ``first_step`` of a run that continues this one (None: the
        default start, where the run gave no usable step)."""
        h = self.h_next
        return float(h) if math.isfinite(h) and h > 0 else None

    @property
    def ok(self) -> bool:
        return self.status == Status.OK

    @property
    def outcome(self) -> Outcome:
        return Outcome(self.status, self.message, {
            "steps": self.steps, "rejected": self.rejected, "rhs_calls": self.rhs_calls,
            "events": self.events}, self.wall_time, {
            "accumulated_local_error": self.error_estimate,
            "relative_error": self.relative_error})


_JACOBIAN = {"auto": JAC_AUTO, "loops": JAC_LOOPS, "blas": JAC_BLAS}
_W2_MAX: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _initial_step(model: ReducedModel, param: float, span: float, rtol: float) -> float:
    """A step well below the fastest time scale (modal, contact, excitation)."""
    w2 = _W2_MAX.get(model)
    if w2 is None:
        ct = model.contacts
        k_contact = 0.0
        if ct.count:
            k = np.maximum(np.abs(ct.k_hi), np.abs(ct.k_lo)) * np.sum(ct.directions ** 2, axis=1)
            k_contact = float(np.max(k))
        w2 = _W2_MAX[model] = float(np.max(model.omega2, initial=0.0)) + k_contact
    w_max = np.sqrt(max(w2, model.excitation_frequency(param) ** 2, 1e-30))
    return min(span, 0.1 * rtol ** 0.2 / w_max)


def integrate(model: ReducedModel, param: float, u0, t0: float, t1: float, *,
              t_eval=None, options: IntegrationOptions = IntegrationOptions(),
              variational: bool = False, record_from: float | None = None,
              jacobian: str = "auto", columns: tuple[int, int] | None = None,
              first_step: float | None = None) -> Trajectory:
    """Integrate u' = f(t, u; param) from (t0, u0) to t1.

    ``t_eval``: sorted times for dense output.  ``variational``: also integrate the
    monodromy d u / d u0 and the parameter sensitivity d u / d param (with saltation at
    switches).  ``record_from``: start of the window in which the extrema and contact
    losses of the monitored contact are recorded (default t0).  ``jacobian``: how the
    variational equations apply the Jacobian, "auto" (BLAS from
    :data:`~vibrogear.solvers.integrator.variational.BLAS_MIN_WORK` on), "blas" or "loops" (the same
    products up to round-off).  ``columns`` = (c0, c1): with ``variational``, integrate
    only the columns [c0, c1) of the tangent [d u / d u0 | d u / d param] (n + 1 columns),
    returned in ``tangent_columns``: the state and its steps do not depend on which
    columns ride along (:mod:`.split_flow` shares them between two processes).
    ``first_step``: the first trial step (e.g. ``h_next`` of the run this one continues;
    default a step well below the model's fastest time scale, from which the controller
    grows it over the first steps).
    """
    wall = time.perf_counter()
    if jacobian not in _JACOBIAN:
        raise ValueError(f"jacobian must be one of {sorted(_JACOBIAN)}, not {jacobian!r}")
    u0 = np.ascontiguousarray(u0, dtype=float)
    if u0.shape != (model.n_states,):
        raise ValueError(f"u0 must have {model.n_states} entries")
    if not t1 > t0:
        raise ValueError("t1 must be greater than t0")
    if first_step is not None and not (np.isfinite(first_step) and first_step > 0):
        raise ValueError(f"first_step must be finite and > 0, not {first_step!r}")
    n = model.n_states
    c0, c1 = (0, n + 1) if columns is None else (int(columns[0]), int(columns[1]))
    if not 0 <= c0 < c1 <= n + 1:
        raise ValueError(f"columns must satisfy 0 <= c0 < c1 <= {n + 1}, not {columns}")
    t_eval = np.ascontiguousarray(np.zeros(0) if t_eval is None else t_eval, dtype=float)
    if t_eval.size and (np.any(np.diff(t_eval) < 0) or t_eval[0] < t0 or t_eval[-1] > t1):
        raise ValueError("t_eval must be sorted and inside [t0, t1]")
    arrs, Om, spin, dOm, dspin = model_arrays(model, param)
    span = t1 - t0
    hmax = span
    if Om > 0:
        hmax = min(span, options.max_step_periods * 2 * np.pi / Om)
    h0 = min(_initial_step(model, param, span, options.rtol) if first_step is None
             else float(first_step), hmax, span)
    mon = model.monitor if model.contacts.count else -1
    rec = t0 if record_from is None else float(record_from)
    fin, iin = loop_inputs(Om=Om, dOm=dOm, dspin=dspin, t0=t0, t1=t1, rtol=options.rtol,
                           atol=options.atol, h0=h0, hmax=hmax, rec_t0=rec,
                           max_steps=options.max_steps, max_events=options.max_events_per_step,
                           variational=variational, mon=mon, ev_cap=options.event_log,
                           jacobian=_JACOBIAN[jacobian], col0=c0, col1=c1)
    res = LoopResult._make(dopri_loop(arrs, u0, t_eval, fin, iin))
    code, t_end, y, Phi, u_eval, cnt = res.status, res.t, res.y, res.Phi, res.u_eval, res.counters
    status = from_code(code)
    message = status.message + (f" at t = {t_end:.6g}" if status else "")
    rel = float("nan")
    if status == Status.OK and not np.all(np.isfinite(y)):
        status = Status.NONFINITE
        message = status.message
    elif status == Status.OK:
        status, message, rel = assess(model, param, u0, y, u_eval, t0, t1, float(res.err_sum),
                                      int(cnt[3]), (float(res.mon_min), float(res.mon_max)),
                                      options)
    nev = int(cnt[3])
    keep = min(nev, options.event_log)
    whole = variational and columns is None
    return Trajectory(
        t=t_eval, u=u_eval, t_end=float(t_end), u_end=y, status=status, message=message,
        steps=int(cnt[0]), rejected=int(cnt[1]), rhs_calls=int(cnt[2]), events=nev,
        event_times=res.ev_t[:keep], event_contacts=res.ev_j[:keep],
        event_modes=res.ev_m[:keep], monitor_min=float(res.mon_min),
        monitor_max=float(res.mon_max), monitor_losses=int(cnt[4]),
        final_modes=res.mode, f_end=res.f_end,
        monodromy=Phi[:, :n].copy() if whole else None,
        dparam=Phi[:, n].copy() if whole else None,
        tangent_columns=Phi if variational and not whole else None,
        wall_time=time.perf_counter() - wall, error_estimate=float(res.err_sum),
        relative_error=rel, h_next=float(res.h_next), event_rates=res.ev_r[:keep],
    )
