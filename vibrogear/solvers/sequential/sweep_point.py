"""One point of a sweep: a transient that stops when settled, a record window, the motion
class with its evidence (period, Lyapunov exponent) and the contact metrics.

Every integration starts at phase 0 (t = 0, cos(W t) = 1) and covers whole excitation
periods T, so its end state is again at phase 0; a multi-frequency model (sampled per base
period of a forcing whose common period is longer) starts each integration where the last
left the forcing instead (``ReducedModel.phase_time``), and its end state's time is
``PointRecord.u_end_t``.

* **Transient** in blocks of max(max_period + 2, 8) periods, at most ``transient_periods +
  extra_transient_periods`` (the budget).  It stops after a block when

  - the stroboscopic map has converged: the last max_period + 2 samples have a period
    n <= max_period within ``period_tol`` (:func:`~.motion.classify_period`), or
  - the statistics have settled (``settle``): with windows of W = ``settle_window``
    (default max(record_periods, ``SETTLE_WINDOW``)) periods, the mean and the standard deviation of the monitored
    deformation (8 samples per period) over the last two windows differ by at most
    ``SETTLE_TOL`` of its range, and over the last three windows the distance of the
    stroboscopic samples from the nearest period (:func:`~.motion.best_defect`) has not
    shrunk below ``NO_CONTRACTION`` of the previous window's, twice (a decaying
    transient shrinks it, an attractor does not).

  ``transient_used`` is the number of periods integrated; ``settled_by`` says why it
  stopped ("map", "statistics" or "budget").
* **Record** of ``record_periods`` periods in chunks of min(:data:`~.lyapunov.CHUNK`,
  record_periods // 8) periods (at least 1; one integrator call each, the blocks of the
  exponent's interval): stroboscopic samples, extrema of the monitored deformation (located
  by the integrator), located contact events.
* **Class** (:mod:`~.motion`): period-n from the record's stroboscopic samples, at the
  engineering resolution (every mesh deformation and force within ``resolution_rel`` of
  its range over the record, or 1 nm / 1 N; the record's dense samples give the ranges) or
  within ``period_tol`` on the full state; where there is none and ``lyapunov`` is on, the
  largest Lyapunov exponent over the record window (:mod:`~.lyapunov`: each record chunk is
  the reference trajectory, one perturbed trajectory per chunk) decides chaotic /
  quasi-periodic / not settled; where its lower bound is above 0, the same estimate is
  repeated on the record integrated again at rtol / 10: chaotic only where that lower bound
  is above 0 too and the two 95 % intervals overlap (an exponent that moves with the
  tolerance is integration noise; the change between the two is reported as the estimate's
  floor).  Under
  a multi-frequency forcing (no common period within the limit) a point that is not
  chaotic is "multi-frequency forced".  Per contact group, the period again on the
  group's own quantities.
* **Orbit check** (``shoot``, :mod:`~.orbit_check`): a point without a period (or periodic
  at the resolution only, its transient budget used up) is first shot from its settled
  state (periods 1 and 2).  A stable orbit makes it periodic
  (``settled_by = "shooting"``; the record is taken again on the orbit); an unstable one
  is reported beside the class (``orbit_*`` metrics), which the exponent then decides.
* **Metrics** (:func:`~.record_metrics.metrics_with_errors`): impacts, approach speeds at onset
  (the switching function's rate where the integrator located the onset),
  contact fractions, rattle energy and power, unloaded rolling elements, each with a
  batch-means error over blocks of the record window; the largest force of each mesh
  (``max_force_<mesh>`` [N], from the record's dense samples) without one.
* **Second tolerance** (``second_tolerance``): the record window again at rtol / 10 (atol /
  10) from the same settled state; the change of the extrema and of each metric is its
  tolerance error (``<name>_tol_err`` in the metrics).  On a periodic or quasi-periodic
  point it estimates the integration error.  On a chaotic point the two records would
  diverge and differ by sampling alone, as much as the batch-means error says: it is not
  run there (``_tol_err`` NaN, ``tol_err_measured`` = 0).
* **Timings**: the wall time of each phase (:data:`PHASES`) in ``PointRecord.timings``.
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ...config.options import IntegrationOptions, SweepOptions
from ..integrator.integrate import integrate
from .lyapunov import CHUNK, initial_direction, state_scale
from .orbit_check import check_orbit, near_periods
from .point_evidence import (group_periods, lyapunov_exponent, perturbation,
                             record_contact_metrics, resolution_metrics, resolution_test)
from .record_window import record_extrema, record_window
from .motion import (CHAOTIC, FAILED, best_defect, classify_period, count_clusters,
                     monitored_deformation, motion_class, period_defect)
from .record_metrics import contact_groups
from ...status import Outcome, Status

__all__ = ["PointRecord", "run_point", "end_phase", "failed_point", "SETTLE_TOL", "NO_CONTRACTION",
           "SETTLE_WINDOW", "PHASES"]

#: the phases of a point whose wall time :attr:`PointRecord.timings` reports
PHASES = ("transient", "record", "lyapunov", "orbit_check", "metrics", "second_tolerance")

#: settled statistics: mean and std of two windows within this fraction of the range
SETTLE_TOL = 0.1
#: ... and the distance from the nearest period not below this fraction of the last one
NO_CONTRACTION = 0.95
#: shortest window of the statistics test (periods)
SETTLE_WINDOW = 32
_S_TRANSIENT = 8      # dense samples per period for the transient's statistics


@dataclass(frozen=True, eq=False)
class PointRecord:
    """One finished point of a sweep (what the callback receives and resuming needs)."""
    direction: str
    index: int                   # index into the ``params`` array given to the sweep
    param: float
    qmin: float                  # extrema of the monitored deformation (NaN if failed)
    qmax: float
    poincare: np.ndarray         # (R,) monitored deformation at the period multiples
    period_n: int                # 1..max_period, 0 = not periodic (or failed)
    impacts: float               # contact losses of the monitored contact per base period
    defect: float                # max_k |P_{k+n} - P_k| / scale (periodic points), else NaN
    clusters: int                # distinct Poincare clusters (0 if failed)
    status: int                  # Status: OK, or the integrator's failure (< 0)
    message: str
    u_end: np.ndarray            # (n,) state at the end: seeds the next point
    steps: int = 0
    rejected: int = 0
    rhs_calls: int = 0
    events: int = 0
    wall_time: float = 0.0
    states: np.ndarray | None = None   # (R, n) Poincare samples of the full state (optional)
    motion_class: int = FAILED         # motion.MOTION_LEGEND index
    lyapunov: float = math.nan         # largest Lyapunov exponent (1 / model time unit;
    #: metrics lyapunov_per_s [1/s], lyapunov_per_period [per excitation period])
    lyapunov_ci: tuple = (math.nan, math.nan)   # its 95 % interval
    transient_used: int = 0            # transient periods integrated
    settled_by: str = ""               # "map", "statistics", "budget"
    metrics: dict = field(default_factory=dict)  # per-group classes and contact metrics
    #: wall seconds by phase (PHASES): where the point's time went
    timings: dict = field(default_factory=dict)
    #: the model time (the forcing's phase) of ``u_end``: 0 unless the model is
    #: multi-frequency (``ReducedModel.phase_time``); an integration that continues the
    #: point at its speed starts from it
    u_end_t: float = 0.0

    @property
    def ok(self) -> bool:
        return self.status == 0

    @property
    def outcome(self) -> Outcome:
        """The point's solve as an :class:`~vibrogear.status.Outcome` (integrator counters;
        the point's evidence is in its fields), for :meth:`Outcome.combine`."""
        return Outcome(self.status, self.message, {
            "steps": self.steps, "rejected": self.rejected, "rhs_calls": self.rhs_calls,
            "events": self.events}, self.wall_time, {})


def failed_point(direction, index, param, R, status, message, u_seed, counts=None,
                 wall=0.0, used=0) -> PointRecord:
    nan = math.nan
    c = np.zeros(4, np.int64) if counts is None else counts
    return PointRecord(direction, int(index), float(param), nan, nan, np.full(R, nan), 0,
                       nan, nan, 0, int(status), message, np.array(u_seed, dtype=float),
                       steps=int(c[0]), rejected=int(c[1]), rhs_calls=int(c[2]),
                       events=int(c[3]), wall_time=wall, transient_used=int(used))


class _Clock:
    """Wall time by phase: :meth:`lap` books the time since the last lap to a phase."""

    def __init__(self, start: float):
        self.last, self.laps = start, {}

    def lap(self, phase: str) -> None:
        now = time.perf_counter()
        self.laps[phase] = self.laps.get(phase, 0.0) + now - self.last
        self.last = now


def _settled(dense, strob, W: int, max_period: int) -> bool:
    """The statistics test of the module docstring on the last three windows of W
    periods: the last two have equal statistics, and neither step between the three
    shrank the distance from the nearest period."""
    S = _S_TRANSIENT
    a, b = dense[-2 * S * W: -S * W], dense[-S * W:]
    rng = float(np.ptp(np.concatenate([a, b])))
    if not rng > 0:
        return False
    if abs(a.mean() - b.mean()) > SETTLE_TOL * rng or abs(a.std() - b.std()) > SETTLE_TOL * rng:
        return False
    d = [best_defect(strob[len(strob) - (k + 1) * W - 1: len(strob) - k * W], max_period)
         for k in (2, 1, 0)]
    return bool(d[1] >= NO_CONTRACTION * d[0] and d[2] >= NO_CONTRACTION * d[1])


def end_phase(model, rec: PointRecord) -> int:
    """The excitation periods the forcing has run at ``rec``'s end state (0 unless the model
    is multi-frequency).  Every forcing frequency is a fixed multiple of the speed, so the
    forcing's phase after n periods is the same at every speed: a sweep's next point, at
    another speed, continues it from n (``run_point``'s ``phase0``) instead of jumping the
    slower meshes' phase back to 0."""
    if not model.multi_frequency:
        return 0
    return int(round(rec.u_end_t / model.excitation_period(rec.param)))


def run_point(model, param, u_seed, direction, index, settings: SweepOptions, *,
              options: IntegrationOptions, cluster_tol: float = 1e-3, keep_states: bool = False,
              settle: bool = True, phase0: int = 0) -> PointRecord:
    """One sweep point (module docstring) with ``settings`` (:class:`SweepOptions`).
    ``phase0``: the excitation periods the forcing has run before ``u_seed`` (a sweep's
    previous point: :func:`end_phase`); only a multi-frequency model reads it."""
    wall = time.perf_counter()
    clock = _Clock(wall)
    max_period, period_tol = settings.max_period, settings.period_tol
    R = settings.record_periods
    counts = np.zeros(4, dtype=np.int64)   # steps, rejected, rhs calls, events
    if not (math.isfinite(param) and model.excitation_frequency(param) > 0):
        return failed_point(direction, index, param, R, Status.BAD_PARAMETER,
                            Status.BAD_PARAMETER.message, u_seed)
    T = model.excitation_period(param)
    m = model.n_modes
    has_monitor = model.contacts.count > 0
    seed = np.array(u_seed, dtype=float)

    def fail(st, msg, used):
        return failed_point(direction, index, param, R, st, msg, u_seed, counts,
                            time.perf_counter() - wall, used)

    # ---- transient, stopped when settled
    budget = settings.transient_periods + settings.extra_transient_periods
    block = max(int(max_period) + 2, 8)
    W = settings.settle_window or max(R, SETTLE_WINDOW)
    strob, dense = [seed], []
    used, settled_by = 0, "budget"
    while used < budget:
        k = min(block, budget - used)
        t_s = model.phase_time(phase0 + used, param)     # the forcing carried on (0: periodic)
        t_eval = np.arange(1, k * _S_TRANSIENT + 1) * (T / _S_TRANSIENT)
        t_eval[-1] = k * T
        t_eval = t_s + t_eval
        tr = integrate(model, param, seed, t_s, t_s + k * T, t_eval=t_eval, options=options)
        counts += tr.counts
        used += k
        if not tr.ok or not np.all(np.isfinite(tr.u_end)):
            return fail(tr.status or Status.NONFINITE, tr.message, used)
        seed = tr.u_end.copy()
        strob.extend(tr.u[_S_TRANSIENT - 1::_S_TRANSIENT])
        dense.append(monitored_deformation(model, param, t_eval, tr.u))
        L = int(max_period) + 2
        if len(strob) >= L and classify_period(np.array(strob[-L:]), max_period, period_tol,
                                               split=m)[0] > 0:
            settled_by = "map"
            break
        if settle and used >= 3 * W and _settled(np.concatenate(dense), np.array(strob), W,
                                                  int(max_period)):
            settled_by = "statistics"
            break

    clock.lap("transient")
    # ---- record in chunks
    u_rec = seed.copy()
    groups = contact_groups(model)
    chunk = max(1, min(CHUNK, R // 8))       # >= 8 blocks for the exponent's interval
    rec = record_window(model, param, u_rec, R, T, chunk, groups, options, counts, has_monitor,
                        start=phase0 + used)
    if isinstance(rec, tuple):
        return fail(*rec, used)
    chunks, states, seed, losses = rec.chunks, rec.states, rec.end, rec.losses
    clock.lap("record")

    # ---- class and evidence: a period at the engineering resolution, else within
    # period_tol on the full state
    n_res, res_defect, res_samples, res = resolution_test(model, param, states, rec, settings)
    if n_res > 1 and settled_by == "budget":
        # a free vibration still decaying at a rational multiple of the excitation
        # frequency repeats after n > 1 periods within the resolution: a period n > 1 needs
        # a settled transient (its distance from a period no longer shrinking)
        n_res = 0
    n, defect = classify_period(states, max_period, period_tol, split=m)
    strict = n > 0
    if n_res > 0:
        n, defect = n_res, period_defect(states, n_res, split=m)
    lam, ci, floor = math.nan, (math.nan, math.nan), math.nan
    chaos_floor = 0.0
    msg = "ok"
    P = model.period_multiple
    if n == 0 and settings.lyapunov and len(chunks) >= 2:
        scale = state_scale(np.vstack([u_rec, states]), m)
        # start along the last step of the stroboscopic map: the slowest direction
        v0 = initial_direction(strob[-1] - strob[-2] if len(strob) > 1 else None, scale,
                               u_rec.size, index)
        lam, ci, msg = lyapunov_exponent(model, param, chunks, v0, options, T, chunk, counts)
        if math.isfinite(ci[0]) and ci[0] > 0.0:
            # the same estimate on the same record at rtol / 10 (module docstring)
            fine = dataclasses.replace(options, rtol=options.rtol / 10, atol=options.atol / 10)
            rec_f = record_window(model, param, u_rec, R, T, chunk, groups, fine, counts,
                                  has_monitor, start=phase0 + used)
            lam_f, ci_f = math.nan, (math.nan, math.nan)
            if not isinstance(rec_f, tuple):
                # the same perturbation: the integration noise against it is ten times
                # smaller, so an exponent that is the noise's growth falls, the motion's holds
                lam_f, ci_f, _ = lyapunov_exponent(model, param, rec_f.chunks, v0, fine, T,
                                                   chunk, counts, d0=perturbation(options))
            floor = abs(lam_f - lam) if math.isfinite(lam_f) else math.inf
            # chaotic where the tighter integration reproduces a positive lower bound and
            # the same exponent: the two 95 % intervals overlap (a chaotic record at
            # rtol / 10 is another stretch of the attractor: its change is sampling spread,
            # reported as the floor, not a bar the bound must clear; an exponent that falls
            # with the tolerance is the integrator's noise growing, not the motion's: the
            # FVA gearbox at 10 % load and 543 rpm, kv 1.001, reads +0.47 per period with
            # the perturbation 3.9e-3 at rtol 3.9e-4, +0.08 [-0.08, +0.23] with the same
            # perturbation at rtol 3.9e-5 and -0.01 at 3.9e-6, where the two-stage gearbox's
            # chaos at 2000 rpm reads +0.30, +0.43 and +0.48)
            same = math.isfinite(lam_f) and abs(lam_f - lam) <= (
                (ci[1] - ci[0]) + (ci_f[1] - ci_f[0])) / 2
            chaos_floor = 0.0 if math.isfinite(ci_f[0]) and ci_f[0] > 0.0 and same \
                else math.inf
    clock.lap("lyapunov")
    orbit = None
    # shot too: a point periodic at the resolution whose transient ran out of budget (its
    # record still drifts within the resolution; on the orbit its extrema are exact); no
    # orbit to shoot where the samples are per mesh period of a multi-frequency forcing
    unsettled = n == 0 or (not strict and settled_by == "budget")
    near = near_periods(states) if unsettled and settings.shoot and \
        not model.multi_frequency else ()
    if near and motion_class(n, ci, budget_used=settled_by == "budget",
                             floor=chaos_floor) != CHAOTIC:
        # a slow transient or an attractor without a period? (orbit_check.py; a positive
        # exponent has already shown chaos)
        orbit = check_orbit(model, param, seed, period_tol=period_tol, options=options,
                            periods=near, drift=states)
        counts[2] += orbit.rhs_calls
        if orbit.stable:
            again = record_window(model, param, orbit.u0, R, T, chunk, groups, options, counts,
                            has_monitor)
            if not isinstance(again, tuple):
                n2, d2 = classify_period(again.states, max_period, period_tol, split=m)
                r2 = resolution_test(model, param, again.states, again, settings)
                if r2[0] > 0:
                    n2, d2 = r2[0], period_defect(again.states, r2[0], split=m)
                if n2 > 0:
                    u_rec, rec, n, defect, settled_by = orbit.u0.copy(), again, n2, d2, "shooting"
                    chunks, states, seed, losses = rec.chunks, rec.states, rec.end, rec.losses
                    n_res, res_defect, res_samples, res = r2
                    lam, ci = math.nan, (math.nan, math.nan)   # periodic: multipliers instead
                    floor, chaos_floor = math.nan, 0.0
    clock.lap("orbit_check")
    budget_used = settled_by == "budget"
    mf = model.multi_frequency
    cls = motion_class(n, ci, budget_used=budget_used, floor=chaos_floor, period_multiple=P,
                       multi_frequency=mf)
    metrics = group_periods(model, param, T, states, groups, max_period, period_tol,
                             (res_samples, res), t=rec.phase_times()) if has_monitor else {}
    for key in list(metrics):
        gn = metrics[key]
        metrics[key.replace("period_n_", "motion_class_")] = motion_class(
            gn, ci, budget_used=budget_used, floor=chaos_floor, period_multiple=P,
            multi_frequency=mf) if gn > 0 else cls
    if has_monitor:
        metrics.update(record_contact_metrics(model, param, u_rec, rec, groups, R, T, n))
        if rec.lost_events:
            msg = "event log full: raise [integration] event_log for the contact metrics"
            metrics = {k: (math.nan if not k.startswith(("period_n", "motion_class")) else v)
                       for k, v in metrics.items()}
    if orbit is not None:
        metrics.update(orbit.as_metrics())
    metrics.update(resolution_metrics(model, T, n_res, res_defect, res, rec, lam, ci, floor))
    clock.lap("metrics")
    if settings.second_tolerance and cls == CHAOTIC:
        # two records of a chaotic motion diverge whatever the tolerance: their difference
        # is a sampling difference, of the size of the batch-means errors (_err), and says
        # nothing about the tolerance; not measured (NaN), flagged
        metrics.update({f"{k}_tol_err": math.nan for k in ("qmin", "qmax")})
        metrics.update({f"{k}_tol_err": math.nan for k in list(metrics)
                        if not k.endswith("_err") and f"{k}_err" in metrics})
        metrics["tol_err_measured"] = 0.0
    elif settings.second_tolerance:
        # the record window again at rtol / 10 from the same settled state: the change of
        # each statistic is its tolerance error
        fine = dataclasses.replace(options, rtol=options.rtol / 10, atol=options.atol / 10)
        rec2 = record_window(model, param, u_rec, R, T, chunk, groups, fine, counts, has_monitor,
                             start=phase0 + used)
        tol_err = {k: math.nan for k in ("qmin", "qmax")}
        if not isinstance(rec2, tuple):
            e1 = record_extrema(model, param, rec, has_monitor)
            e2 = record_extrema(model, param, rec2, has_monitor)
            tol_err["qmin"], tol_err["qmax"] = abs(e2[0] - e1[0]), abs(e2[1] - e1[1])
            if has_monitor:
                m2 = record_contact_metrics(model, param, u_rec, rec2, groups, R, T, n)
                tol_err.update({k: abs(v - metrics[k]) for k, v in m2.items()
                                if not k.endswith("_err") and k in metrics})
        metrics.update({f"{k}_tol_err": float(v) for k, v in tol_err.items()})
        metrics["tol_err_measured"] = 1.0
    clock.lap("second_tolerance")
    delta = monitored_deformation(model, param, rec.phase_times(), states)
    qmin, qmax = record_extrema(model, param, rec, has_monitor)
    return PointRecord(direction, int(index), float(param), qmin, qmax, delta, int(n),
                       losses / (R * model.period_multiple), defect, count_clusters(states, cluster_tol, split=m), 0,
                       msg, seed.copy(), steps=int(counts[0]), rejected=int(counts[1]),
                       rhs_calls=int(counts[2]), events=int(counts[3]),
                       wall_time=time.perf_counter() - wall,
                       states=states.copy() if keep_states else None, motion_class=int(cls),
                       lyapunov=float(lam), lyapunov_ci=tuple(float(c) for c in ci),
                       transient_used=int(used), settled_by=settled_by, metrics=metrics,
                       timings=clock.laps,
                       u_end_t=model.phase_time(phase0 + used + R, param))
