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
from ...pipeline.executors import broadcast
from ...pipeline.wall_split import WallSplit
from ...pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ...pipeline.resume import PartialStore
from ...solvers.sequential.motion import MOTION_LEGEND
from ...solvers.sequential.sweep_point import PHASES
from .plan import CensusPlan, UnitContext, unit_kind, work_unit
from .starts import start_scales
from ..study import Study, integration_options
from ...solvers.sequential.record_json import record_from_json
from ...status import Outcome

__all__ = ["StatesResult", "run", "grid", "census_plan", "PARTIAL_NAME"]

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


def _describe(param_name, unit) -> str:
    """A unit named for the user (where an MPI rank lost it)."""
    kind, i, p = unit[0], unit[1], unit[2]
    if kind == "start":
        return f"{param_name} = {p:.6g}, starts {unit[3][0]}..{unit[3][-1]}"
    if kind == "orbit":
        return f"{param_name} = {unit[3]:.6g}, the orbit of attractor {unit[2]}"
    return f"{param_name} = {unit[3]:.6g}, a half-branch"


def _group(plan, study):
    """Rank 0's result of the census: (attractors in grid order, settled and failed per grid
    value, the records, the starts' table)."""
    by_point = plan.by_point()
    attractors, n_ok, n_failed = [], [], []
    for atts, k, f in plan.attractors:
        attractors += atts
        n_ok.append(k)
        n_failed.append(f)
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
    return attractors, n_ok, n_failed, recs, starts


#: what the census does without sharing it among the workers (summary.json's serial_part)
SERIAL_PART = ("not shared among the workers: the start states and the resume file before "
               "the units; between them, on the coordinating process while the workers go "
               "on, each grid value's grouping into attractors and the choice of the "
               "candidates for branches; after them the comparison with the sweep and the "
               "summary")


def census_plan(study, scene, *, done=None, store=None, progress=None, previous=None):
    """The census's coordinator and the context its units run in: (CensusPlan, UnitContext)
    for ``scene.states`` (``done``: starts settled before; ``previous``: this run's results
    so far, whose continuation's branches count as known)."""
    from .branches import branch_settings, known_branches, orbit_options
    cfg = scene.states
    model = study.model
    params = grid(cfg)
    opts = integration_options(scene, record=True, period_tol=cfg.period_tol, section=cfg,
                               study=study)
    scales = [start_scales(model, float(p), study.start(float(p)),
                           deformation_scale=cfg.deformation_scale,
                           velocity_scale=cfg.velocity_scale, box=cfg.box) for p in params]
    orbit_opts, shooting = orbit_options(study, scene)
    cont = None
    if cfg.branches and cfg.param_max > cfg.param_min and not model.multi_frequency:
        cont = branch_settings(study, scene)
    ctx = UnitContext(model=model, settings=SweepOptions.of(cfg), options=opts, seed=cfg.seed,
                      orbit_options=orbit_opts, shooting=shooting, continuation=cont)
    plan = CensusPlan(study, cfg, params, scales, ctx, done=done, store=store,
                      progress=progress, known=known_branches(previous), workers=cfg.workers)
    return plan, ctx


def run(study: Study, scene, ctx: RunContext, previous=None) -> AnalysisOutcome:
    from .branches import compare_with_sweep
    from .summary import states_summary

    cfg = scene.states
    params = grid(cfg)
    wall = time.perf_counter()
    split = WallSplit(SERIAL_PART)
    opts = integration_options(scene, record=True, period_tol=cfg.period_tol, section=cfg,
                               study=study)
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
        plan, unit_ctx = census_plan(
            study, scene, done=done, store=store, previous=previous,
            progress=lambda i, rec: bar.update(
                1, f"{params[i]:.4g} {study.param_unit} P{rec.period_n}"))
        coordinator = plan if ctx.root else None
        first = broadcast(plan.start() if ctx.root else None)
        split.run("census", partial(work_unit, unit_ctx), [u for u, _c in first],
                  costs=[c for _u, c in first], workers=cfg.workers, kind=unit_kind,
                  on_result=None if coordinator is None else coordinator.on_result,
                  on_done=None if coordinator is None else coordinator.on_done,
                  describe=partial(_describe, study.param_name))
    t_units = time.perf_counter() - wall
    try:
        grouped = _group(plan, study) if ctx.root else None
    except BaseException:
        broadcast(None)
        raise
    if broadcast(ctx.root and grouped is not None) is not True or not ctx.root:
        return AnalysisOutcome(summary={"status": "ok", "message": "census rank"})
    if not plan.finished():
        raise NumericalFailure("states: the census's units ended before every grid value was "
                               "grouped (an internal error: please report it)")
    attractors, n_ok, n_failed, recs, starts = grouped
    timings = {ph: float(sum(r.timings.get(ph, 0.0) for r in recs)) for ph in PHASES}
    timings["clustering"] = plan.clustering_s
    work = split.work_by_kind("census")
    timings["orbits"] = work.get("orbits", 0.0)
    timings["branches"] = work.get("branches", 0.0)
    sweep = compare_with_sweep(study, attractors, (previous or {}).get("sweep"))
    timings["census_wall"] = t_units
    timings["total_wall"] = time.perf_counter() - wall
    solves = Outcome.combine((r.outcome for r in recs), wall_s=t_units)
    info = plan.census_info()
    counters = {"starts_settled": len(recs), "starts_resumed": resumed, "rounds": info["rounds"],
                **{k: solves.counters.get(k, 0) for k in ("steps", "rhs_calls", "events")}}
    result = StatesResult(params=params, attractors=tuple(attractors),
                          n_starts=np.array(n_ok, int), n_failed=np.array(n_failed, int),
                          study=study, branches=tuple(plan.found), branch_notes=tuple(plan.notes),
                          sweep=sweep, timings=timings, counters=counters, starts=starts)
    summary = states_summary(result, cfg, opts, info)
    summary.update(split.summary())
    if store is not None and store.note:
        summary["resume"] = store.note
    return AnalysisOutcome(summary=summary, result=result, solver=solves,
                           partial_files=() if store is None else (store.path,))
