"""``vibrogear states``: every operating state at every speed (section ``[states]``).

The sweep follows one path up and one down; the continuation follows the branches it is
started on.  Neither sees a state that only a disturbance reaches.  This census does:

1. **Starts**: at each grid value, ``starts`` random initial states (:mod:`.starts`).
2. **Settling**: each start is one sweep point
   (:func:`~vibrogear.solvers.sequential.sweep_point.run_point`: transient until settled,
   record window, class with its evidence, contact metrics) with the section's sweep
   settings.  Work units are (grid value, a batch of starts), run by
   :func:`~vibrogear.pipeline.executors.run_units` on processes or MPI ranks; each settled
   start is appended to ``states.partial.jsonl`` as it arrives (the one resume rule of
   :mod:`~vibrogear.pipeline.resume`; the start count, batch, early stop, clustering and
   branch settings are not part of the signature: a run with more starts reuses the ones
   done).  With ``basin_tol`` the starts run in rounds of ``batch`` per grid value and a
   value stops once every basin's 95 % interval is narrower than ``basin_tol``.
3. **Attractors**: the settled motions of each grid value grouped, with basin fractions and
   Wilson intervals (:mod:`.cluster`).
4. **Orbits and branches** (:mod:`.branches`): each periodic attractor shot (Newton on
   the period map: its exact extrema and Floquet multipliers), then, with ``branches``, a
   continuation both ways from each one that no branch found so far passes through; each
   attractor compared with the sweep of this run or of ``sweep.npz`` in the output folder.
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np

from ...config.options import SweepOptions
from ...pipeline.executors import broadcast, effective_workers, run_units, unit_size
from ...pipeline.wall_split import WallSplit
from ...pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ...pipeline.resume import PartialStore
from ...solvers.sequential.motion import MOTION_LEGEND
from ...solvers.sequential.sweep_point import PHASES, run_point
from .cluster import cluster_point, interval_widths
from .starts import draw_start, start_scales
from ..study import Study, integration_options
from ...solvers.sequential.record_json import record_from_json, record_to_json
from ...status import Outcome

__all__ = ["StatesResult", "run", "census", "grid", "PARTIAL_NAME"]

PARTIAL_NAME = "states.partial.jsonl"
#: settings that do not change a settled start (left out of the resume signature)
_NOT_IN_SIGNATURE = ("workers", "starts", "batch", "basin_tol", "cluster_tol", "stat_tol",
                     "branches", "branch_max_points", "n_points", "directions", "segments")


@dataclass(frozen=True, eq=False)
class StatesResult:
    """The census: every attractor found from random starts at every grid value.

    P grid values, A attractors (all grid values), B branch points.

    Fields:

    - ``params``: (P,) [rpm or Omega] the grid.
    - ``attractors``: (A,) Attractor, grouped by grid value: ``param``, ``motion_class``
      (code into ``legend``), ``period_n``, ``qmin`` / ``qmax`` [m for a gearbox] of the
      monitored deformation, ``fraction`` [1] of the settled starts that reach it (its basin)
      with ``ci`` (Wilson 95 % interval), ``count`` (starts), ``stable`` (Floquet; None: not
      shot), ``max_multiplier`` [1], ``metrics`` ({mesh: {"impacts" [1/period], "rattle" [J
      per period]}}), ``seen_by_sweep``.
    - ``n_starts``: (P,) starts settled without failure; ``n_failed``: (P,) failed.
    - ``study``: the :class:`~vibrogear.analyses.study.Study`.
    - ``branches``: branches continued from attractors; ``branch_notes``: how each ended.
    - ``sweep``: the sweep's arrays it was compared with (None: no sweep).
    - ``timings``: {phase: s}; ``counters``: integrator counters.
    - ``starts``: per settled start: ``point``, ``index``, ``wall_s`` [s], ``attractor``.
    - ``legend``: names of the motion-class codes.

    :meth:`arrays`: the arrays of ``states.npz`` by the same names (``attractor_param``,
    ``attractor_qmin`` [m], ``basin_fraction`` [1], ``basin_ci_lo`` / ``_hi``, ...;
    :mod:`vibrogear.report.writers.states` lists them all); :meth:`plot`: the danger map."""
    params: np.ndarray                 # (P,)
    attractors: tuple                  # states_cluster.Attractor, grouped by grid value
    n_starts: np.ndarray               # (P,) starts settled without failure
    n_failed: np.ndarray               # (P,) starts whose integration failed
    study: Study
    branches: tuple = ()               # Branch objects continued from attractors
    branch_notes: tuple = ()           # per attractor continued: where and how it ended
    sweep: dict | None = None          # the sweep's arrays it was compared with
    timings: dict = field(default_factory=dict)
    counters: dict = field(default_factory=dict)
    #: per settled start: grid index, start index, wall seconds, attractor index (-1: failed)
    starts: dict = field(default_factory=dict)
    #: names of the motion-class codes of the attractors (the sweep's)
    legend: tuple = MOTION_LEGEND

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays of ``states.npz``, by the same names (see the class docstring)."""
        from .summary import states_arrays
        return states_arrays(self)

    def plot(self):
        """The danger map (``states.png``) as a matplotlib Figure: every attractor by speed,
        marker area its basin, the sweep's path and the branches."""
        from ...report.writers.states import figure
        return figure(self)


def grid(cfg) -> np.ndarray:
    lo, hi = float(cfg.param_min), float(cfg.param_max)
    return np.array([lo]) if cfg.n_points == 1 else np.linspace(lo, hi, cfg.n_points)


def _compact(rec):
    """A settled start as kept: the cycle (last n stroboscopic states) of a periodic one,
    no states otherwise."""
    n = int(rec.period_n)
    st = rec.states
    keep = np.array(st[-n:], dtype=float) if (n > 0 and st is not None) else None
    return dataclasses.replace(rec, states=keep)


def _settle_unit(model, settings, options, seed, unit, emit) -> int:
    """Settle the starts of one unit (grid index, value, start indices, scales)."""
    i, p, ks, scales = unit
    for k in ks:
        u = draw_start(scales, model, seed, i, k)
        rec = run_point(model, float(p), u, "start", int(k), settings, options=options,
                        keep_states=True)
        emit((int(i), _compact(rec)))
    return len(ks)


def _describe(param_name, unit) -> str:
    i, p, ks, _ = unit
    return f"{param_name} = {p:.6g}, starts {ks[0]}..{ks[-1]}"


def census(model, params, cfg, *, options, scales, store=None, done=None, progress=None,
           root: bool = True, split=None) -> tuple[dict, dict]:
    """Settle the starts of every grid value (module docstring, steps 1-2); returns
    ({grid index: [PointRecord]}, {"rounds", "new", "stopped_early"}).  ``done``: {(i, k):
    record} already settled (resumed); ``split``: a :class:`~vibrogear.pipeline.wall_split.WallSplit`
    that times the units.  Collective under MPI: every rank calls it."""
    settings = SweepOptions.of(cfg)
    done = dict(done or {})
    P = len(params)
    round_size = cfg.batch if cfg.basin_tol is not None else cfg.starts
    active = list(range(P))
    upto, rounds, new, early = 0, 0, 0, []
    while active:
        upto = min(upto + round_size, cfg.starts)
        units = None
        if root:
            todo = {i: [k for k in range(upto) if (i, k) not in done] for i in active}
            n_todo = sum(len(v) for v in todo.values())
            w = effective_workers(n_todo, cfg.workers)
            # at most `batch` starts a unit; smaller where the workers would otherwise
            # run out of units before the end (the last units leave the others idle)
            size = cfg.batch if w == 1 else unit_size(n_todo, w, cfg.batch)
            units = []
            for i in active:
                for a in range(0, len(todo[i]), size):
                    units.append((i, float(params[i]), tuple(todo[i][a:a + size]),
                                  scales[i]))
        units = broadcast(units)

        def on_result(_u, item):
            i, rec = item
            done[(i, int(rec.index))] = rec
            if store is not None:
                store.append({"point": i, **record_to_json(rec)})
            if progress is not None:
                progress(i, rec)

        if units:
            run = run_units if split is None else partial(split.run, "census")
            run(partial(_settle_unit, model, settings, options, cfg.seed), units,
                workers=cfg.workers, on_result=on_result, costs=[len(u[2]) for u in units],
                describe=partial(_describe, model.param_name))
            new += sum(len(u[2]) for u in units)
        rounds += 1
        still = None
        if root:
            still = []
            for i in active:
                if upto >= cfg.starts:
                    continue
                recs = [done[(i, k)] for k in range(upto) if (i, k) in done]
                atts, _, _ = cluster_point(recs, i, params[i], n_modes=model.n_modes,
                                           cluster_tol=cfg.cluster_tol, stat_tol=cfg.stat_tol)
                if interval_widths(atts) < cfg.basin_tol:
                    early.append(i)
                else:
                    still.append(i)
        active = broadcast(still)
    by_point = {i: [r for (j, _k), r in sorted(done.items()) if j == i] for i in range(P)}
    return by_point, {"rounds": rounds, "new": new, "stopped_early": early}


def _group(by_point, params, model, cfg, study):
    """Rank 0's grouping of the settled starts: (attractors, settled and failed per grid
    value, the records, the starts' table, its wall seconds)."""
    t0 = time.perf_counter()
    attractors, n_ok, n_failed = [], [], []
    for i, p in enumerate(params):
        atts, k, f = cluster_point(by_point[i], i, p, n_modes=model.n_modes,
                                   cluster_tol=cfg.cluster_tol, stat_tol=cfg.stat_tol)
        attractors += atts
        n_ok.append(k)
        n_failed.append(f)
    t_cluster = time.perf_counter() - t0
    if sum(n_ok) == 0:
        first = next((r for recs in by_point.values() for r in recs), None)
        raise NumericalFailure("states: every start failed" + (
            f"; first: {study.param_name} = {first.param:g}: {first.message}" if first else ""))
    recs = [r for v in by_point.values() for r in v]
    which = {(a.point, k): j for j, a in enumerate(attractors) for k in a.members}
    starts = {"point": np.array([i for i, v in by_point.items() for _ in v], int),
              "index": np.array([r.index for v in by_point.values() for r in v], int),
              "wall_s": np.array([r.wall_time for v in by_point.values() for r in v], float)}
    starts["attractor"] = np.array([which.get((i, k), -1) for i, k in
                                    zip(starts["point"], starts["index"])], int)
    return attractors, n_ok, n_failed, recs, starts, t_cluster


#: what the census does without sharing it among the workers (summary.json's serial_part)
SERIAL_PART = ("not shared among the workers: the start states and the resume file before "
               "the census; the grouping into attractors, the choice of each wave of branches, "
               "the comparison with the sweep and the summary after it")


def run(study: Study, scene, ctx: RunContext, previous=None) -> AnalysisOutcome:
    from .branches import compare_with_sweep, continue_branches, refine_orbits
    from .summary import states_summary

    cfg = scene.states
    model = study.model
    params = grid(cfg)
    wall = time.perf_counter()
    split = WallSplit(SERIAL_PART)
    opts = integration_options(scene, record=True, period_tol=cfg.period_tol, section=cfg,
                               study=study)
    scales = [start_scales(model, float(p), study.start(float(p)),
                           deformation_scale=cfg.deformation_scale,
                           velocity_scale=cfg.velocity_scale, box=cfg.box) for p in params]
    store, done = None, {}
    if ctx.writes:
        settings = {k: v for k, v in dataclasses.asdict(cfg).items()
                    if k not in _NOT_IN_SIGNATURE}
        store = PartialStore(Path(ctx.out) / PARTIAL_NAME, {
            "analysis": "states", "physics": study.physics,
            "grid": [repr(float(p)) for p in params], "settings": settings, "options": opts})
        for item in store.items:
            i = int(item["point"])
            if i < len(params):
                done[(i, int(item["index"]))] = record_from_json(item)
        done = {key: r for key, r in done.items() if key[1] < cfg.starts}
    resumed = len(done)
    with ctx.progress(len(params) * cfg.starts - resumed, "states") as bar:
        by_point, info = census(
            model, params, cfg, options=opts, scales=scales, store=store, done=done,
            root=ctx.root, split=split, progress=lambda i, rec: bar.update(
                1, f"{params[i]:.4g} {study.param_unit} P{rec.period_n}"))
    t_census = time.perf_counter() - wall
    try:
        grouped = _group(by_point, params, model, cfg, study) if ctx.root else None
    except BaseException:
        broadcast(None)         # the other ranks leave (they wait for the orbits' units)
        raise
    if broadcast(ctx.root and grouped is not None) is not True:
        return AnalysisOutcome(summary={"status": "ok", "message": "census rank"})
    attractors, n_ok, n_failed, recs, starts, t_cluster = grouped or ([], [], [], [], {}, 0.0)
    timings = {ph: float(sum(r.timings.get(ph, 0.0) for r in recs)) for ph in PHASES}
    timings["clustering"] = t_cluster
    t0 = time.perf_counter()
    refine_orbits(study, scene, attractors, workers=cfg.workers, split=split, root=ctx.root)
    timings["orbits"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    branches, notes = (), ()
    if cfg.branches:
        branches, notes = continue_branches(study, scene, attractors, previous or {},
                                            workers=cfg.workers, split=split, root=ctx.root)
    timings["branches"] = time.perf_counter() - t0
    if not ctx.root:            # rank 0 compares and reports
        return AnalysisOutcome(summary={"status": "ok", "message": "census rank"})
    sweep = compare_with_sweep(study, attractors, (previous or {}).get("sweep"))
    timings["census_wall"] = t_census
    timings["total_wall"] = time.perf_counter() - wall
    solves = Outcome.combine((r.outcome for r in recs), wall_s=t_census)
    counters = {"starts_settled": len(recs), "starts_resumed": resumed, "rounds": info["rounds"],
                **{k: solves.counters.get(k, 0) for k in ("steps", "rhs_calls", "events")}}
    result = StatesResult(params=params, attractors=tuple(attractors),
                          n_starts=np.array(n_ok, int), n_failed=np.array(n_failed, int),
                          study=study, branches=tuple(branches), branch_notes=tuple(notes),
                          sweep=sweep, timings=timings, counters=counters, starts=starts)
    summary = states_summary(result, cfg, opts, info)
    summary.update(split.summary())
    if store is not None and store.note:
        summary["resume"] = store.note
    return AnalysisOutcome(summary=summary, result=result, solver=solves,
                           partial_files=() if store is None else (store.path,))
