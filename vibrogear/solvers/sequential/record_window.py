"""The record window of a sweep point (:mod:`.sweep_point`): ``R`` excitation periods in
chunks (one integrator call each, the blocks of the Lyapunov exponent's interval), the
stroboscopic states, the monitored contact's extrema and losses, the contact events with the
approach speed at each onset, and the largest force of each mesh, from the dense output at
:data:`FORCE_SAMPLES` times per period (interpolated: the trajectory is the same as without;
a force peak between two samples is under-read by at most ~(pi / FORCE_SAMPLES)^2 / 2 = 0.5 %
of a smooth peak, more for an impact shorter than a sample step)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..integrator.integrate import integrate
from ...status import Status
from ...models.contact_law import evaluate
from ..integrator.contact_eval import contact_kinematics
from .motion import monitored_deformation, monitored_quantities

__all__ = ["RecordWindow", "record_window", "record_extrema", "onset_speeds", "dense_per_period",
           "FORCE_SAMPLES"]

#: dense samples per excitation period at which the mesh forces' peaks are read (at least)
FORCE_SAMPLES = 32


def dense_per_period(period_multiple: int) -> int:
    """Dense samples per excitation period that give the ranges of the monitored
    quantities (:func:`~.motion.monitored_quantities`): 16 per base period, at most 256
    (a long common period is sampled at many phases over the record instead)."""
    return int(min(16 * max(1, int(period_multiple)), 256))


def _force_peaks(model, param, t, u, rows) -> np.ndarray:
    """max |force| over the samples (t, u) of each contact in ``rows`` (model units)."""
    delta, ddot, mu = contact_kinematics(model, param, t, u, rows)
    ct, col = model.contacts, (rows, None)
    f = evaluate(delta, ddot, k_hi=ct.k_hi[col], k_lo=ct.k_lo[col], gap_hi=ct.gap_hi[col],
                 gap_lo=ct.gap_lo[col], exponent=ct.exponent[col], damping=ct.damping[col],
                 modulation=mu).force
    return np.max(np.abs(f), axis=1)


def onset_speeds(tr, rows) -> list:
    """|delta'| of contact ``rows`` at each contact onset of trajectory ``tr``, NaN at the
    other events: the switching function's rate in the state the integrator located the
    switch at (``Trajectory.event_rates``; it used to be found by a second, short
    integration from the dense sample before each onset: 7 % of a two-stage sweep point)."""
    return [abs(float(r)) if md != 0 and int(j) in rows else math.nan
            for j, md, r in zip(tr.event_contacts, tr.event_modes, tr.event_rates)]


@dataclass(frozen=True, eq=False)
class RecordWindow:
    """A record window: its chunks (start state, period-end states, time offset), all
    period-end states, the end state, monitor extrema and losses, the contact events with
    the onset speeds."""
    chunks: list
    states: np.ndarray
    end: np.ndarray
    qmin: float
    qmax: float
    losses: int
    lost_events: bool
    events: tuple
    speeds: np.ndarray
    #: {name: (min, max)} of each monitored quantity over the record's dense samples
    ranges: dict = None
    #: (chunks,) largest and smallest monitored deformation of each chunk
    chunk_max: np.ndarray = None
    chunk_min: np.ndarray = None
    peak_force: dict = None      # {mesh contact row: largest |force| (model units)}
    #: (R,) the model time (the forcing's phase) of each period end in ``states``: zeros
    #: unless the model is multi-frequency (``ReducedModel.phase_time``)
    strob_t: np.ndarray = None

    def phase_times(self) -> np.ndarray:
        return np.zeros(len(self.states)) if self.strob_t is None else self.strob_t


def record_window(model, param, seed, R, T, chunk, groups, options, counts, has_monitor,
                  start: int = 0):
    """The record window of R periods in chunks (module docstring): a :class:`RecordWindow`,
    or (status, message) where the integration failed.  Each chunk starts afresh (with the
    step the last one proposed it costs ~2 % fewer steps, but a chaotic point's record is
    then another stretch of its attractor: the sweep's goldens and statistics tests were
    reviewed on these).  ``start``: the excitation periods integrated before the record
    from the point's start (the forcing's phase: ``ReducedModel.phase_time``); each chunk is
    ``(start state, period-end states, time from the record's start, phase time)``."""
    mesh_rows = {int(idx[0]) for kind, idx in groups.values() if kind == "mesh"}
    rows = np.array(sorted(mesh_rows), dtype=int)
    peaks = np.zeros(rows.size)
    chunks, states, ev_t, ev_j, ev_m, speeds = [], [], [], [], [], []
    qmin, qmax, losses, lost_events = math.inf, -math.inf, 0, False
    seed = np.array(seed, dtype=float)
    # the ranges of the monitored quantities and the mesh forces' peaks on one dense grid
    S = max(dense_per_period(model.period_multiple), FORCE_SAMPLES if rows.size else 1)
    ranges: dict = {}
    cmax, cmin = [], []
    t0 = 0.0
    while t0 < R * T * (1 - 1e-12):
        k = min(chunk, R - int(round(t0 / T)))
        ends_t = np.arange(1, k + 1) * T
        ends_t[-1] = k * T
        t_eval = (np.arange(k)[:, None] * T + np.arange(1, S + 1)[None, :] * (T / S)).ravel()
        t_eval[S - 1::S] = ends_t              # the period ends exactly as without samples
        t_s = model.phase_time(start + int(round(t0 / T)), param)
        t_eval = t_s + t_eval
        tr = integrate(model, param, seed, t_s, t_s + k * T, t_eval=t_eval, options=options)
        counts += tr.counts
        if not tr.ok:
            return tr.status, tr.message
        if not (np.all(np.isfinite(tr.u)) and np.all(np.isfinite(tr.u_end))
                and (not has_monitor or (math.isfinite(tr.monitor_min)
                                         and math.isfinite(tr.monitor_max)))):
            return Status.NONFINITE, "non-finite state or monitor values"
        ends = tr.u[S - 1::S]
        for name, (v, _kind) in monitored_quantities(model, param, t_eval, tr.u).items():
            lo, hi = ranges.get(name, (math.inf, -math.inf))
            ranges[name] = (min(lo, float(v.min())), max(hi, float(v.max())))
        cmax.append(tr.monitor_max if has_monitor else math.nan)
        cmin.append(tr.monitor_min if has_monitor else math.nan)
        if rows.size:
            peaks = np.maximum(peaks, _force_peaks(model, param, tr.t, tr.u, rows))
        chunks.append((seed.copy(), ends, t0, t_s))
        states.append(ends)
        qmin, qmax = min(qmin, tr.monitor_min), max(qmax, tr.monitor_max)
        losses += tr.monitor_losses
        lost_events |= tr.events > tr.event_times.size
        speeds += onset_speeds(tr, mesh_rows)
        ev_t += [t0 + (te - t_s) for te in tr.event_times]
        ev_j += [int(j) for j in tr.event_contacts]
        ev_m += [int(md) for md in tr.event_modes]
        seed = tr.u_end.copy()
        t0 += k * T
    return RecordWindow(chunks, np.concatenate(states), seed, qmin, qmax, losses, lost_events,
                   (np.array(ev_t), np.array(ev_j, int), np.array(ev_m, int)),
                   np.array(speeds), ranges, np.array(cmax), np.array(cmin),
                   dict(zip(rows.tolist(), peaks.tolist())),
                   np.array([model.phase_time(start + k, param) for k in range(1, R + 1)]))


def record_extrema(model, param, rec: RecordWindow, has_monitor) -> tuple[float, float]:
    """(min, max) of the monitored deformation over a record: the integrator's located
    extrema and the stroboscopic samples (the samples alone without a monitored contact)."""
    delta = monitored_deformation(model, param, rec.phase_times(), rec.states)
    if not has_monitor:
        return float(delta.min()), float(delta.max())
    return min(rec.qmin, float(delta.min())), max(rec.qmax, float(delta.max()))
