"""Sequential continuation (brute-force bifurcation diagram, the paper's Fig. 2).

The work is split into independent *units* (direction, segment): the parameter values
of each direction ("up": as given, "down": reversed) are cut into ``segments``
contiguous pieces; every unit starts from ``u0`` (or zeros) at its first point and walks
its points in order, each point starting from the end state of the previous good point
of the same unit.  Units never depend on each other, so they run in parallel (local
processes or MPI ranks, :mod:`vibrogear.pipeline.executors`) and the results do not
depend on the number of workers.  Each point integrates ``transient_periods``
excitation periods that are dropped (plus up to ``extra_transient_periods`` more while
the motion is not yet periodic) and then ``record_periods`` periods that are recorded:

* stroboscopic (Poincare) samples of the full state at t = (N_tr + k) T, k = 1..R, and
  of the monitored deformation delta_mon = c_mon . x - e_mon(t) at the same instants;
* the extrema of delta_mon over the record window (located on the dense output);
* the contact losses of the monitored contact (mesh interruptions), per period.

Each point starts at t = 0 where the excitation phase is cos(W t) = 1; since a whole
number of periods is integrated, the end state is again at phase 0 and seeds the next
point directly.  The motion is classified as period-n for the smallest n <= max_period
with |P_{k+n} - P_k| <= period_tol * scale for every recorded k (scales: the largest
sampled |x| for the displacements, the largest |x'| for the velocities), else 0 (not
periodic: quasi-periodic or chaotic).  A cheap chaos indicator is the number of distinct
Poincare clusters.  A failed point keeps NaN values and its integrator status and
message; the unit goes on from its last good state.  Solvers never print.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import partial

import numpy as np

from ..models.reduced import ReducedModel
from ..pipeline.executors import broadcast, is_root, run_units, under_mpi
from .contact_eval import contact_kinematics
from ..config.options import SweepOptions
from .integrate import IntegrationOptions, integrate
from .status import Status

__all__ = ["PointRecord", "SweepResult", "sweep", "sweep_units", "classify_period",
           "count_clusters", "monitored_deformation", "assemble_result"]

DIRECTIONS = ("up", "down")


@dataclass(frozen=True, eq=False)
class PointRecord:
    """One finished point of a sweep (what the callback receives and resuming needs)."""
    direction: str
    index: int                   # index into the ``params`` array given to :func:`sweep`
    param: float
    qmin: float                  # extrema of the monitored deformation (NaN if failed)
    qmax: float
    poincare: np.ndarray         # (R,) monitored deformation at the period multiples
    period_n: int                # 1..max_period, 0 = not periodic (or failed)
    impacts: float               # contact losses of the monitored contact per period
    defect: float                # max_k |P_{k+n} - P_k| / scale (periodic points), else NaN
    clusters: int                # distinct Poincare clusters (0 if failed)
    status: int                  # Status: OK, or the integrator's failure (< 0)
    message: str
    u_end: np.ndarray            # (n,) state at the end (phase 0): seeds the next point
    steps: int = 0
    rejected: int = 0
    rhs_calls: int = 0
    events: int = 0
    wall_time: float = 0.0
    states: np.ndarray | None = None   # (R, n) Poincare samples of the full state (optional)

    @property
    def ok(self) -> bool:
        return self.status == 0


@dataclass(frozen=True, eq=False)
class SweepResult:
    """All points of a sweep in unit order (up units first, then down; each unit in
    walk order), whatever order the workers finished them in."""
    param: np.ndarray            # (N,)
    direction: np.ndarray        # (N,) "up" / "down"
    index: np.ndarray            # (N,) index into the parameter grid
    qmin: np.ndarray             # (N,) NaN where failed
    qmax: np.ndarray
    poincare: np.ndarray         # (N, R)
    period_n: np.ndarray         # (N,) int, 0 = not periodic
    impacts: np.ndarray          # (N,) contact losses per excitation period
    defect: np.ndarray           # (N,) periodicity defect (NaN: not periodic / failed)
    clusters: np.ndarray         # (N,) int
    status: np.ndarray           # (N,) int, 0 ok
    message: tuple[str, ...]
    u_end: np.ndarray            # (N, n)
    steps: int
    rejected: int
    rhs_calls: int
    events: int
    wall_time: float             # of this call (resumed points cost nothing)
    point_wall: np.ndarray       # (N,) wall time per point as recorded
    rtol: float
    atol: float
    period_tol: float
    param_name: str = "param"
    status_code: Status = Status.OK   # OK, PARTIAL (some points failed), STOPPED_BY_CALLBACK
    status_message: str = "ok"
    states: np.ndarray | None = None   # (N, R, n) when kept
    records: tuple = field(default=(), repr=False)

    @property
    def ok(self) -> np.ndarray:
        return self.status == 0

    @property
    def error_estimate(self) -> dict:
        """Integrator tolerances and the worst periodicity defect of the periodic points."""
        d = self.defect[np.isfinite(self.defect)]
        return {"rtol": self.rtol, "atol": self.atol, "period_tol": self.period_tol,
                "max_periodicity_defect": float(d.max()) if d.size else None,
                "failed_points": int(np.sum(self.status != 0))}


# ---------------------------------------------------------------- analysis helpers

def monitored_deformation(model: ReducedModel, param: float, t, states) -> np.ndarray:
    """delta_mon = c_mon . x - e_mon(t) at times ``t`` for states (len(t), 2m)."""
    if model.contacts.count == 0:
        return np.atleast_2d(states)[:, 0].copy()
    return contact_kinematics(model, param, t, states, rows=[model.monitor])[0][0]


def _scaled(samples: np.ndarray, split: int | None) -> np.ndarray:
    """Samples divided by block scales (largest |value| in each block; tiny floor)."""
    s = np.asarray(samples, dtype=float)
    if s.ndim == 1:
        s = s[:, None]
    blocks = [slice(0, s.shape[1])] if not split else [slice(0, split), slice(split, None)]
    out = np.empty_like(s)
    for b in blocks:
        sc = float(np.max(np.abs(s[:, b]), initial=0.0))
        out[:, b] = s[:, b] / (sc if sc > 1e-300 else 1.0)
    return out


def classify_period(samples, max_period: int, period_tol: float, *,
                    split: int | None = None) -> tuple[int, float]:
    """(n, defect): smallest n <= max_period with max_k |P_{k+n} - P_k| <= period_tol.

    ``samples`` (R,) or (R, n) stroboscopic samples; ``split``: index where the velocity
    block starts (the two blocks are scaled separately).  Differences are measured in
    units of each block's largest |value|.  Returns (0, nan) when no n qualifies or the
    samples are not finite.
    """
    s = np.asarray(samples, dtype=float)
    if s.ndim == 1:
        s = s[:, None]
    if s.shape[0] < 2 or not np.all(np.isfinite(s)):
        return 0, math.nan
    z = _scaled(s, split)
    defects = {}
    for n in range(1, min(int(max_period), s.shape[0] - 1) + 1):
        defects[n] = float(np.max(np.abs(z[n:] - z[:-n])))
        if defects[n] > period_tol:
            continue
        # a genuine period-n cycle is resolved from every shorter divisor cycle; a slowly
        # decaying transient can pass at n > 1 by aliasing while n = 1 nearly passes
        if all(defects[d] > 10.0 * period_tol for d in range(1, n) if n % d == 0):
            return n, defects[n]
    return 0, math.nan


def count_clusters(samples, rel_tol: float = 1e-3, *, split: int | None = None) -> int:
    """Number of distinct Poincare clusters (greedy, inf-norm radius ``rel_tol`` in scaled
    units).  Period-n motion gives n; quasi-periodic or chaotic motion gives many."""
    s = np.asarray(samples, dtype=float)
    if s.ndim == 1:
        s = s[:, None]
    if s.shape[0] == 0 or not np.all(np.isfinite(s)):
        return 0
    z = _scaled(s, split)
    centres: list[np.ndarray] = []
    for p in z:
        if not any(float(np.max(np.abs(p - c))) <= rel_tol for c in centres):
            centres.append(p)
    return len(centres)


# ---------------------------------------------------------------- one point

def _failed(direction, index, param, R, status, message, u_seed, traj=None, wall=0.0):
    nan = math.nan
    return PointRecord(direction, int(index), float(param), nan, nan, np.full(R, nan), 0,
                       nan, nan, 0, int(status), message, np.array(u_seed, dtype=float),
                       steps=traj.steps if traj else 0, rejected=traj.rejected if traj else 0,
                       rhs_calls=traj.rhs_calls if traj else 0,
                       events=traj.events if traj else 0, wall_time=wall)


def _run_point(model, param, u_seed, direction, index, *, transient_periods, record_periods,
               max_period, period_tol, cluster_tol, options, keep_states,
               extra_transient_periods=0) -> PointRecord:
    """Integrate the transient, record; while the motion is not yet periodic and the
    extra-transient budget lasts, drop the record as transient too and record again."""
    wall = time.perf_counter()
    R = int(record_periods)
    if not (math.isfinite(param) and model.excitation_frequency(param) > 0):
        return _failed(direction, index, param, R, Status.BAD_PARAMETER,
                       Status.BAD_PARAMETER.message, u_seed)
    T = model.excitation_period(param)
    seed = np.array(u_seed, dtype=float)
    tp = int(transient_periods)
    budget = int(extra_transient_periods)
    counts = np.zeros(4, dtype=np.int64)   # steps, rejected, rhs calls, events
    while True:
        t_rec = tp * T
        t1 = (tp + R) * T
        t_eval = (tp + np.arange(1, R + 1)) * T
        t_eval[-1] = t1
        tr = integrate(model, param, seed, 0.0, t1, t_eval=t_eval, options=options,
                       record_from=t_rec)
        counts += (tr.steps, tr.rejected, tr.rhs_calls, tr.events)
        if not tr.ok:
            return _failed(direction, index, param, R, tr.status, tr.message, u_seed, tr,
                           time.perf_counter() - wall)
        states = tr.u
        has_monitor = model.contacts.count > 0   # else the extrema come from the samples only
        ok = (np.all(np.isfinite(states)) and np.all(np.isfinite(tr.u_end))
              and (not has_monitor or (math.isfinite(tr.monitor_min)
                                       and math.isfinite(tr.monitor_max))))
        if not ok:
            return _failed(direction, index, param, R, Status.NONFINITE,
                           "non-finite state or monitor values",
                           u_seed, tr, time.perf_counter() - wall)
        m = model.n_modes
        n, defect = classify_period(states, max_period, period_tol, split=m)
        if n > 0 or budget <= 0:
            break
        # not periodic yet: the recorded window becomes transient, integrate on
        seed = tr.u_end.copy()
        tp = min(max(int(transient_periods), R), budget)
        budget -= tp + R
    delta = monitored_deformation(model, param, t_eval, states)
    clusters = count_clusters(states, cluster_tol, split=m)
    qmin = min(tr.monitor_min, float(delta.min())) if has_monitor else float(delta.min())
    qmax = max(tr.monitor_max, float(delta.max())) if has_monitor else float(delta.max())
    return PointRecord(direction, int(index), float(param), qmin, qmax, delta, int(n),
                       tr.monitor_losses / R, defect, clusters, 0, "ok", tr.u_end.copy(),
                       steps=int(counts[0]), rejected=int(counts[1]), rhs_calls=int(counts[2]),
                       events=int(counts[3]), wall_time=time.perf_counter() - wall,
                       states=states.copy() if keep_states else None)


# ---------------------------------------------------------------- the sweep

def sweep_units(n_params: int, directions=DIRECTIONS, segments: int = 1) -> list:
    """[(direction, indices in walk order)]: each direction's walk cut into ``segments``
    contiguous pieces (at most one point each when segments > n_params)."""
    out = []
    for d in directions:
        order = np.arange(n_params) if d == "up" else np.arange(n_params - 1, -1, -1)
        for piece in np.array_split(order, max(1, min(int(segments), n_params))):
            out.append((d, tuple(int(i) for i in piece)))
    return out


def _walk_unit(model, kw, unit, emit) -> int:
    """Walk one unit (direction, indices, params, seed, done): each new point goes to
    ``emit``; done points are skipped and their end states seed the next point."""
    direction, indices, params, seed, done = unit
    seed = np.array(seed, dtype=float)
    new = 0
    for i, p in zip(indices, params):
        rec = done.get(i)
        if rec is None:
            rec = _run_point(model, float(p), seed, direction, i, **kw)
            emit(rec)
            new += 1
        if rec.ok:
            seed = np.array(rec.u_end, dtype=float)
    return new


def sweep(model: ReducedModel, params, *, directions=DIRECTIONS, transient_periods: int = 200,
          record_periods: int = 32, max_period: int = 8, period_tol: float = 1e-5,
          options: IntegrationOptions = IntegrationOptions(), u0=None, callback=None,
          done=None, cluster_tol: float = 1e-3, keep_states: bool = False,
          extra_transient_periods: int = 0, segments: int = 1,
          workers: int | None = None) -> SweepResult:
    """Sequential continuation of ``model`` over ``params`` in independent units (see the
    module docstring), run by :func:`~vibrogear.pipeline.executors.run_units`.

    ``segments``: pieces per direction (each starts again from ``u0``).  ``workers``:
    local processes (None: min(units, cores); 1: in this process); under ``mpirun``
    with several ranks the units go to the ranks instead, every rank must call
    :func:`sweep` with the same arguments and gets the same result.
    ``callback(record)`` is called in this process (rank 0) after each newly computed
    point, as it arrives; returning ``False`` stops the sweep.  ``done``:
    {(direction, index): PointRecord} of points already finished (e.g. read back from
    a partial file): they are not recomputed, and their end states seed the next point
    exactly as in an uninterrupted run.  Results do not depend on ``workers``.
    """
    wall = time.perf_counter()
    params = np.asarray(params, dtype=float).ravel()
    if params.size == 0:
        raise ValueError("sweep: params must not be empty")
    directions = tuple(directions)
    # the settings' rules, defined once with the [sweep] section (ConfigError: a ValueError)
    SweepOptions(transient_periods=int(transient_periods), record_periods=int(record_periods),
                 extra_transient_periods=int(extra_transient_periods), directions=directions,
                 max_period=int(max_period), period_tol=float(period_tol),
                 segments=int(segments), workers=None if workers is None else int(workers))
    n_states = model.n_states
    seed = np.zeros(n_states) if u0 is None else np.array(u0, dtype=float)
    if seed.shape != (n_states,):
        raise ValueError(f"sweep: u0 must have {n_states} entries")
    done = dict(done or {})
    kw = dict(transient_periods=int(transient_periods), record_periods=int(record_periods),
              max_period=int(max_period), period_tol=float(period_tol),
              cluster_tol=float(cluster_tol), options=options, keep_states=keep_states,
              extra_transient_periods=int(extra_transient_periods))
    layout = sweep_units(params.size, directions, int(segments))
    units = [(d, idx, params[list(idx)], seed, {i: done[(d, i)] for i in idx if (d, i) in done})
             for d, idx in layout]
    todo = [u for u in units if len(u[4]) < len(u[1])]
    new: dict = {}
    stopped = False

    def on_result(_k, rec):
        nonlocal stopped
        new[(rec.direction, rec.index)] = rec
        if callback is not None and callback(rec) is False:
            stopped = True
            return False
        return None

    run_units(partial(_walk_unit, model, kw), todo, workers=workers, on_result=on_result)
    if under_mpi() and not is_root():
        return broadcast(None)                  # rank 0's result, identical everywhere
    records = [r for d, idx in layout for i in idx
               for r in (done.get((d, i)) or new.get((d, i)),) if r is not None]
    failed = sum(1 for r in records if not r.ok)
    if stopped:
        code = Status.STOPPED_BY_CALLBACK
        msg = f"{code.message} after {len(records)} points"
    elif failed:
        code, msg = Status.PARTIAL, f"{failed} of {len(records)} points failed"
    else:
        code, msg = Status.OK, Status.OK.message
    result = assemble_result(records, n_states=n_states, record_periods=int(record_periods),
                             options=options, period_tol=period_tol,
                             param_name=model.param_name, status_code=code,
                             status_message=msg, wall_time=time.perf_counter() - wall)
    return broadcast(result)


def assemble_result(records, *, n_states: int, record_periods: int, options, period_tol,
                    param_name="param", status_code=Status.OK, status_message="ok",
                    wall_time=0.0) -> SweepResult:
    """Stack point records into a :class:`SweepResult` (also used after reading files)."""
    recs = tuple(records)
    N, R = len(recs), int(record_periods)
    f = lambda name: np.array([getattr(r, name) for r in recs], dtype=float)  # noqa: E731
    i = lambda name: np.array([getattr(r, name) for r in recs], dtype=np.int64)  # noqa: E731
    poinc = np.full((N, R), np.nan)
    u_end = np.zeros((N, n_states))
    for k, r in enumerate(recs):
        p = np.asarray(r.poincare, dtype=float)
        poinc[k, :min(R, p.size)] = p[:R]
        u_end[k] = r.u_end
    states = None
    if N and all(r.states is not None for r in recs):
        states = np.stack([r.states for r in recs])
    return SweepResult(
        param=f("param"), direction=np.array([r.direction for r in recs], dtype="<U4"),
        index=i("index"), qmin=f("qmin"), qmax=f("qmax"), poincare=poinc,
        period_n=i("period_n"), impacts=f("impacts"), defect=f("defect"),
        clusters=i("clusters"), status=i("status"), message=tuple(r.message for r in recs),
        u_end=u_end, steps=int(sum(r.steps for r in recs)),
        rejected=int(sum(r.rejected for r in recs)),
        rhs_calls=int(sum(r.rhs_calls for r in recs)),
        events=int(sum(r.events for r in recs)), wall_time=float(wall_time),
        point_wall=f("wall_time"), rtol=float(options.rtol), atol=float(options.atol),
        period_tol=float(period_tol), param_name=param_name, status_code=Status(status_code),
        status_message=status_message, states=states, records=recs)
