"""Sequential continuation (brute-force bifurcation diagram, the paper's Fig. 2).

The work is split into independent *units* (direction, segment): the parameter values
of each direction ("up": as given, "down": reversed) are cut into ``segments``
contiguous pieces; every unit starts from ``u0`` (or zeros) at its first point and walks
its points in order, each point starting from the end state of the previous good point
of the same unit.  Units never depend on each other, so they run in parallel (local
processes or MPI ranks, :mod:`vibrogear.pipeline.executors`) and the results do not
depend on the number of workers.

Each point (:mod:`.sweep_point`) integrates a transient that stops when the stroboscopic
map has converged or the statistics have settled (at most ``transient_periods +
extra_transient_periods`` periods), then ``record_periods`` periods that are recorded:
stroboscopic (Poincare) samples of the full state and of the monitored deformation
delta_mon = c_mon . x - e_mon(t), its extrema (located on the dense output), the contact
losses of the monitored contact, the contact events.  The motion class with its evidence
(period-n, else the largest Lyapunov exponent with its interval) and the rattle / contact
metrics per contact group come from them (:mod:`.motion`, :mod:`.lyapunov`).

Each point starts at phase 0 (t = 0, cos(W t) = 1) and integrates whole periods: its end
state seeds the next point (a multi-frequency model's lies n periods into its forcing, and
the next point continues from there: ``sweep_point.end_phase``).  A failed point keeps NaN
values and its status and message; the unit goes on from its last good state."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import cached_property, partial

import numpy as np

from ...config.options import SweepOptions
from ...models.reduced import ReducedModel
from ...pipeline.executors import broadcast, is_root, run_units, under_mpi
from ..integrator.integrate import IntegrationOptions
from .motion import (MOTION_LEGEND, classify_period, count_clusters, monitored_deformation,
                     monitored_name)
from .strob_evidence import spectral_evidence
from ...status import Outcome, Status
from .sweep_point import PHASES, PointRecord, end_phase, run_point

__all__ = ["PointRecord", "SweepResult", "sweep", "sweep_units", "classify_period",
           "count_clusters", "monitored_deformation", "assemble_result", "MOTION_LEGEND"]

DIRECTIONS = ("up", "down")


@dataclass(frozen=True, eq=False)
class SweepResult:
    """All points of a sweep in unit order (up units first, then down; each unit in
    walk order), whatever order the workers finished them in.

    N points (grid values x directions), R recorded excitation periods, n states.  Lengths
    are in the model's length unit (``ReducedModel.length_unit``: m for a gearbox,
    nondimensional for the impact pair), times in model time units (``time_unit_s`` seconds
    each: 1 s for a gearbox).  NaN marks a failed point (``status != 0``).

    Fields:

    - ``param``: (N,) the parameter of each point (driving-shaft speed in rpm for a gearbox,
      Omega for the impact pair; ``param_name``).
    - ``direction``: (N,) str, ``"up"`` / ``"down"``: the sweep direction.
    - ``index``: (N,) int, the point's index into the parameter grid.
    - ``qmin``, ``qmax``: (N,) [model length, m] minimum and maximum of the monitored contact
      deformation over the record window.
    - ``poincare``: (N, R) [model length, m] the monitored deformation once per excitation
      period (stroboscopic, Poincare samples).
    - ``period_n``: (N,) int, the period in excitation periods (0: not periodic).
    - ``impacts``: (N,) [1/period] contact losses of the monitored contact per excitation period.
    - ``defect``: (N,) [1] periodicity defect of a periodic point (NaN: not periodic).
    - ``clusters``: (N,) int, clusters of the Poincare samples.
    - ``status``: (N,) int, 0 ok, else the integrator's failure code; ``message``: (N,) str.
    - ``u_end``: (N, n) [model units] the state at the end of each point (seeds the next).
    - ``steps``, ``rejected``, ``rhs_calls``, ``events``: int counters of the integrator.
    - ``wall_time``: [s] of this call; ``point_wall``: (N,) [s] per point.
    - ``rtol``, ``atol``, ``period_tol``: [1], [model units], [1] the tolerances used.
    - ``motion_class``: (N,) int code into ``motion_legend`` (periodic, quasi-periodic,
      chaotic, ...); ``lyapunov``: (N,) [1/model time] largest Lyapunov exponent (NaN: not
      computed), ``lyapunov_ci``: (N, 2) its 95 % interval.
    - ``transient_used``: (N,) [periods] transient integrated; ``settled_by``: (N,) str,
      ``"map"`` / ``"statistics"`` / ``"budget"``.
    - ``metrics``: {name: (N,)} per contact group: ``period_n_<g>``, ``motion_class_<g>``,
      ``impacts_drive_<mesh>`` / ``impacts_back_<mesh>`` [1/period],
      ``impact_velocity_rms_<mesh>`` / ``_max_`` [model length/s, m/s],
      ``contact_fraction_<mesh>`` [1], ``rattle_<mesh>`` [J per period, model units for the
      impact pair], ``unloaded_<bearing>`` [1]; each with an ``_err`` companion (batch means).
    - ``timings``: {phase: s} wall time by phase, summed over the points.

    :meth:`arrays` gives the arrays of ``sweep.npz`` (NaN replaced by 0, ``ok`` flags)."""
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
    motion_class: np.ndarray | None = None    # (N,) int, index into MOTION_LEGEND
    lyapunov: np.ndarray | None = None        # (N,) largest exponent (NaN: not computed)
    lyapunov_ci: np.ndarray | None = None     # (N, 2) its 95 % interval
    transient_used: np.ndarray | None = None  # (N,) transient periods integrated
    settled_by: np.ndarray | None = None      # (N,) "map" / "statistics" / "budget"
    metrics: dict = field(default_factory=dict)   # {name: (N,)} per-group classes, metrics
    #: {phase: wall seconds summed over the points} (sweep_point.PHASES; resumed points
    #: count as recorded)
    timings: dict = field(default_factory=dict)
    #: the monitored contact's name (the key of ``hysteresis_<name>`` in sweep.npz; "" when
    #: unknown)
    monitored: str = ""
    #: (N,) the model time (the forcing's phase) of each ``u_end``: zeros unless the model is
    #: multi-frequency (``ReducedModel.phase_time``; None: all 0)
    u_end_t: np.ndarray | None = None

    @property
    def ok(self) -> np.ndarray:
        return self.status == 0

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays ``sweep.npz`` holds, by the same names (NaN/inf replaced by 0; failed
        points flagged by ``ok = False`` and ``status < 0``; :mod:`vibrogear.report.sweep_files`
        describes them)."""
        ok = self.status == 0
        return dict(**self._class_arrays(),
            param=_finite(self.param), direction=np.asarray(self.direction, dtype="<U4"),
            qmin=_finite(self.qmin), qmax=_finite(self.qmax),
            poincare=_finite(self.poincare), period_n=np.asarray(self.period_n, np.int64),
            impacts=_finite(self.impacts), index=np.asarray(self.index, np.int64),
            status=np.asarray(self.status, np.int64), ok=ok,
            defect=_finite(self.defect), clusters=np.asarray(self.clusters, np.int64),
            u_end=_finite(self.u_end), point_wall=_finite(self.point_wall),
            message=np.asarray(self.message, dtype=str) if self.message else np.zeros(0, "<U1"),
            rtol=np.asarray(self.rtol, np.float64), atol=np.asarray(self.atol, np.float64),
            period_tol=np.asarray(self.period_tol, np.float64),
            param_name=np.asarray(self.param_name),
        )

    def _class_arrays(self) -> dict:
        """Motion class, evidence and metrics (absent on results made before them)."""
        N = self.param.size
        if self.motion_class is None:
            return {}
        out = dict(motion_class=np.asarray(self.motion_class, np.int64),
                   motion_class_legend=np.asarray(self.motion_legend),
                   lyapunov=_finite(self.lyapunov), lyapunov_ok=np.isfinite(self.lyapunov),
                   lyapunov_ci=_finite(np.asarray(self.lyapunov_ci).reshape(N, 2)),
                   transient_used=np.asarray(self.transient_used, np.int64),
                   settled_by=np.asarray(self.settled_by, dtype="<U10"))
        for k, v in self.metrics.items():
            v = np.asarray(v)
            out[k] = v if v.dtype.kind == "i" else _finite(v)
        out.update(self.spectral)
        out.update(self.hysteresis_arrays())
        return out

    def hysteresis_arrays(self) -> dict:
        """``hysteresis_<monitored>``: per point, how far qmax up and qmax down at its speed
        differ beyond their batch-means errors, max(|qmax up - qmax down| - (qmax_err up +
        qmax_err down), 0) (the same value on the up and the down point; 0 where either failed
        or the sweep ran one way; without ``qmax_err`` the plain difference).  The error term
        keeps a record that samples a slow beat differently up and down (meshes exciting at
        their own frequencies, a common period longer than the record) from reading as two
        coexisting states."""
        key = getattr(self, "monitored", "") or "monitored"
        param = np.asarray(self.param, float)
        d = np.asarray(self.direction, str)
        q = np.asarray(self.qmax, float)
        err = np.asarray((self.metrics or {}).get("qmax_err", np.zeros(param.size)), float)
        err = np.where(np.isfinite(err), err, 0.0)
        ok = (np.asarray(self.status) == 0) & np.isfinite(q)
        h = np.zeros(param.size)
        if np.any(d == "up") and np.any(d == "down"):
            for k in range(param.size):
                other = np.flatnonzero((param == param[k]) & (d != d[k]) & ok)
                if ok[k] and other.size:
                    o = other[0]
                    h[k] = max(abs(q[k] - q[o]) - (err[k] + err[o]), 0.0)
        return {f"hysteresis_{key}": h}

    @property
    def motion_legend(self) -> tuple[str, ...]:
        """Names of the ``motion_class`` codes."""
        return MOTION_LEGEND

    @property
    def error_estimate(self) -> dict:
        """Integrator tolerances and the worst periodicity defect of the periodic points."""
        d = self.defect[np.isfinite(self.defect)]
        return {"rtol": self.rtol, "atol": self.atol, "period_tol": self.period_tol,
                "max_periodicity_defect": float(d.max()) if d.size else None,
                "failed_points": int(np.sum(self.status != 0))}

    @cached_property
    def spectral(self) -> dict:
        """The spectral evidence of each point's class (:func:`.strob_evidence.spectral_evidence`:
        ``base_f2_order``, ``strob_flatness``, ``strob_peak_fraction``), computed once per
        result for the summary, the files and the figures."""
        return spectral_evidence(self) if self.motion_class is not None else {}

    @property
    def outcome(self) -> Outcome:
        """The sweep as a whole (``status`` holds each point's)."""
        e = self.error_estimate
        return Outcome(self.status_code, self.status_message, {
            "points": self.param.size, "failed_points": e["failed_points"],
            "steps": self.steps, "rejected": self.rejected, "rhs_calls": self.rhs_calls,
            "events": self.events}, self.wall_time,
            {k: e[k] for k in ("rtol", "atol", "period_tol", "max_periodicity_defect")})


def _finite(a, fill=0.0) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    return np.where(np.isfinite(a), a, fill)


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


def _describe_unit(param_name: str, unit) -> str:
    """A unit as a lost-rank message names it: direction, parameter range, point indices."""
    direction, indices, params, _seed, _done = unit
    return (f"{direction} walk over {param_name} = {params[0]:.6g} .. {params[-1]:.6g} "
            f"(points {indices[0]}..{indices[-1]})")


def _walk_unit(model, settings, kw, unit, emit) -> int:
    """Walk one unit (direction, indices, params, seed, done): each new point goes to
    ``emit``; done points are skipped and their end states seed the next point."""
    direction, indices, params, seed, done = unit
    seed = np.array(seed, dtype=float)
    new = phase = 0
    for i, p in zip(indices, params):
        rec = done.get(i)
        if rec is None:
            rec = run_point(model, float(p), seed, direction, i, settings, phase0=phase, **kw)
            emit(rec)
            new += 1
        if rec.ok:
            seed = np.array(rec.u_end, dtype=float)
            phase = end_phase(model, rec)
    return new


def sweep(model: ReducedModel, params, settings: SweepOptions | None = None, *,
          options: IntegrationOptions = IntegrationOptions(), u0=None, callback=None,
          done=None, cluster_tol: float = 1e-3, keep_states: bool = False,
          settle: bool = True, split=None) -> SweepResult:
    """Sequential continuation of ``model`` over ``params`` in independent units (see the
    module docstring), run by :func:`~vibrogear.pipeline.executors.run_units`.

    ``settings`` (:class:`~vibrogear.config.options.SweepOptions`, default its defaults):
    ``lyapunov``: the largest Lyapunov exponent of points without a period (their class
    evidence); ``shoot``: Newton on the period map from such a point's settled state
    before it is called quasi-periodic or chaotic (:mod:`.sweep_point`);
    ``second_tolerance``: the record window again at rtol / 10 from the same settled
    state, the change of each statistic (extrema, contact metrics) in
    ``metrics["<name>_tol_err"]``.  ``settle``: stop a transient whose statistics have
    settled (a transient always stops once the stroboscopic map has converged).

    ``segments``: pieces per direction (each starts again from ``u0``).  ``workers``:
    local processes (None: min(units, cores); 1: in this process); under ``mpirun``
    with several ranks the units go to the ranks instead, every rank must call
    :func:`sweep` with the same arguments and gets the same result.
    ``callback(record)`` is called in this process (rank 0) after each newly computed
    point, as it arrives; returning ``False`` stops the sweep.  ``done``:
    {(direction, index): PointRecord} of points already finished (e.g. read back from
    a partial file): they are not recomputed, and their end states seed the next point
    exactly as in an uninterrupted run.  Results do not depend on ``workers``.
    ``split``: a :class:`~vibrogear.pipeline.wall_split.WallSplit` that times the units.
    """
    wall = time.perf_counter()
    params = np.asarray(params, dtype=float).ravel()
    if params.size == 0:
        raise ValueError("sweep: params must not be empty")
    settings = SweepOptions() if settings is None else settings
    n_states = model.n_states
    seed = np.zeros(n_states) if u0 is None else np.array(u0, dtype=float)
    if seed.shape != (n_states,):
        raise ValueError(f"sweep: u0 must have {n_states} entries")
    done = dict(done or {})
    kw = dict(options=options, cluster_tol=float(cluster_tol), keep_states=keep_states,
              settle=bool(settle))
    layout = sweep_units(params.size, settings.directions, settings.segments)
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

    # a unit's cost: its points still to compute (a resumed sweep's part-done units are
    # shorter; the longest go first, the short ones fill the end)
    run = run_units if split is None else partial(split.run, "walks")
    run(partial(_walk_unit, model, settings, kw), todo, workers=settings.workers,
        on_result=on_result, costs=[len(u[1]) - len(u[4]) for u in todo],
        describe=partial(_describe_unit, model.param_name))
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
    result = assemble_result(records, n_states=n_states, record_periods=settings.record_periods,
                             options=options, period_tol=settings.period_tol,
                             param_name=model.param_name, status_code=code,
                             status_message=msg, wall_time=time.perf_counter() - wall,
                             monitored=monitored_key(model))
    return broadcast(result)


def monitored_key(model: ReducedModel) -> str:
    """The monitored contact's name as the per-contact arrays spell it (``x0`` without
    contacts)."""
    return monitored_name(model).removeprefix("delta_")


def assemble_result(records, *, n_states: int, record_periods: int, options, period_tol,
                    param_name="param", status_code=Status.OK, status_message="ok",
                    wall_time=0.0, monitored: str = "") -> SweepResult:
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
    keys = sorted({k for r in recs for k in r.metrics})
    metrics = {k: np.array([r.metrics.get(k, math.nan) for r in recs], dtype=float)
               for k in keys}
    for k in keys:                      # classes and periods stay integers (-1: absent)
        if k.startswith(("period_n_", "motion_class_")):
            metrics[k] = np.where(np.isfinite(metrics[k]), metrics[k], -1).astype(np.int64)
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
        status_message=status_message, states=states, records=recs,
        motion_class=i("motion_class"), lyapunov=f("lyapunov"),
        lyapunov_ci=np.array([r.lyapunov_ci for r in recs], dtype=float).reshape(N, 2),
        transient_used=i("transient_used"),
        settled_by=np.array([r.settled_by for r in recs], dtype="<U10"), metrics=metrics,
        timings={k: float(sum(r.timings.get(k, 0.0) for r in recs)) for k in PHASES},
        u_end_t=np.array([r.u_end_t for r in recs], dtype=float),
        monitored=str(monitored))
