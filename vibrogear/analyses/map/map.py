"""Speed x load operating map of a gearbox (``vibrogear map SCENE``, section [map]).

Each load row is a sweep over the driving speed (the sweep's point solver,
:func:`~vibrogear.solvers.sequential.sweep_point.run_point`, walked exactly as
:func:`~vibrogear.solvers.sequential.sweep.sweep` walks a unit: every point starts from the end state
of the previous good point of its direction, the first of each unit from the static
equilibrium of that load at the grid's first speed, as a sweep's), so every map point is a settled sweep point with its motion
class and the rattle / contact metrics of
:mod:`vibrogear.solvers.sequential.record_metrics` (impacts per mesh period per flank,
rattle energy, contact fraction, bearing elements out of contact).
The largest mesh force of each point is added here: ``force_periods`` mesh periods more,
sampled ``force_samples`` times per period, from the point's end state, through the one
contact law (:func:`~vibrogear.solvers.integrator.contact_eval.contact_history`).

The load of row k is the scene's coupling twists times a factor s_k
(:mod:`.load_scaling`: F0(s) = F0_rest + s F0_couplings, exact, one model build).  The
work units (load row, direction, segment) are independent and run on local processes or
MPI ranks (:func:`~vibrogear.pipeline.executors.run_units`); results do not depend on the
number of workers.  Each finished point is appended to ``map.partial.jsonl``
(:class:`~vibrogear.pipeline.resume.PartialStore`: reused only with the same physics,
loads, grid, settings, options and version), which the runner deletes once ``map.npz``
exists.  With ``curves = true`` the LP / PD points of the period-1 branch are located at
every load and joined (:mod:`.curves`).
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from ...pipeline.executors import broadcast, run_units, under_mpi
from ...pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ...pipeline.resume import PartialStore, fingerprint
from ...pipeline.wall_split import WallSplit
from ...solvers.integrator.contact_eval import contact_history
from ...solvers.integrator.integrate import integrate
from ...solvers.sequential.motion import FAILED, MOTION_LEGEND
from ...solvers.sequential.record_metrics import contact_groups
from ...status import Outcome, Status
from ...solvers.sequential.sweep import assemble_result, sweep_units
from ...solvers.sequential.sweep_point import end_phase, run_point
from .load_scaling import LoadScaling, load_scaling
from ...config.options import SweepOptions
from ..study import Study, integration_options, start_state
from ...solvers.sequential.record_json import record_from_json, record_to_json

__all__ = ["OperatingMap", "run", "compute_map", "PARTIAL_NAME",
           "grid_array", "map_arrays", "METRICS_PER_MESH"]

PARTIAL_NAME = "map.partial.jsonl"
#: what the map does on one process (summary.json's serial_part)
SERIAL_PART = ("not shared among the workers: the load scaling and the resume file before "
               "the walks; stacking each load row and the summary after them")
CURVES_PART = ("; between the LP / PD curves' loads, which follow one another (a load's "
               "windows are placed around the last load's points; the windows of one load are "
               "work units, phase 'curves')")


@dataclass(frozen=True, eq=False)
class OperatingMap:
    """A computed map: ``rows[k]`` is the :class:`~vibrogear.solvers.sequential.sweep.SweepResult` of
    load k (all directions, in unit order); ``scale[k]`` its load factor, ``torque[k]``
    [N m] and ``twist[k]`` [rad]."""
    rpm: np.ndarray
    scale: np.ndarray
    torque: np.ndarray
    twist: np.ndarray
    directions: tuple
    rows: tuple
    meshes: tuple                   # metric keys of the meshes (record_metrics.contact_groups)
    bearings: tuple                 # metric keys of the bearings ("bearing_<name>")
    status_code: Status
    status_message: str
    wall_time: float
    resumed: int = 0
    workers: object = None
    curves: object = None           # BifurcationCurves or None
    study: Study | None = None
    load_kind: str = "torque"
    note: str = ""
    legend: tuple = MOTION_LEGEND   # names of the motion_class codes

    def grid(self, name: str) -> np.ndarray:
        """(directions, loads, speeds) array of a per-point quantity (see :func:`grid_array`)."""
        return grid_array(self, name)

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays of ``map.npz``, by the same names (:func:`map_arrays`)."""
        return map_arrays(self)

    def plot(self):
        """The motion class of every point over speed and load (``map_class.png``) as a
        matplotlib Figure."""
        from ...report.plots.map import plot_class_map
        return plot_class_map(self.arrays(), title=self.study.title if self.study else "")

    @property
    def outcome(self) -> Outcome:
        """The map as a whole: its rows' sweeps combined (counters summed, the largest
        error estimates), with the map's own status and wall time."""
        return Outcome.combine([r.outcome for r in self.rows], status=self.status_code,
                               message=self.status_message, wall_s=self.wall_time)


def grid_array(m: OperatingMap, name: str) -> np.ndarray:
    """``name`` on the (direction, load, speed) grid: a SweepResult attribute (``qmax``,
    ``period_n``, ``motion_class``, ``status``, ``point_wall``, ...) or a metric key
    (``rattle_G1``, ``max_force_G1``, ...); NaN (or -1 for integers) where absent."""
    D, L, S = len(m.directions), m.scale.size, m.rpm.size
    first = getattr(m.rows[0], name, None) if m.rows else None
    if first is None:
        first = m.rows[0].metrics.get(name) if m.rows else None
    integer = first is not None and np.asarray(first).dtype.kind in "iu"
    out = np.full((D, L, S), -1 if integer else np.nan, dtype=np.int64 if integer else float)
    for k, row in enumerate(m.rows):
        vals = getattr(row, name, None)
        if vals is None:
            vals = row.metrics.get(name)
        if vals is None:
            continue
        for j, d in enumerate(m.directions):
            sel = row.direction == d
            out[j, k, row.index[sel]] = np.asarray(vals)[sel]
    return out


# ---------------------------------------------------------------- work units

def _max_mesh_force(model, param, u, meshes, periods, samples, options, force_unit):
    """{max_force_<mesh>: largest |force| [N]} over ``periods`` mesh periods from ``u``
    (NaN where that integration fails: :func:`_mesh_force_run` also returns it)."""
    return _mesh_force_run(model, param, u, meshes, periods, samples, options, force_unit)[0]


def _mesh_force_run(model, param, u, meshes, periods, samples, options, force_unit,
                    t0: float = 0.0):
    """(:func:`_max_mesh_force`'s dict, the integration's result); ``t0``: the model time of
    ``u`` (the forcing's phase: 0 unless the model is multi-frequency)."""
    T = model.excitation_period(param)
    t = t0 + np.arange(1, periods * samples + 1) * (T / samples)
    tr = integrate(model, param, u, t0, t0 + periods * T, t_eval=t, options=options)
    if not tr.ok:
        return {f"max_force_{k}": np.nan for k in meshes}, tr
    force = contact_history(model, param, tr.t, tr.u)[2]
    return {f"max_force_{k}": float(np.max(np.abs(force[idx[0]])) * force_unit)
            for k, idx in meshes.items()}, tr


def _describe_unit(unit) -> str:
    """A unit as a lost-rank message names it: load row, direction, speed range, points."""
    row, scale, direction, indices, rpm, _p_first, _done = unit
    return (f"load row {row} (scale {scale:.6g}), {direction} over {rpm[0]:.6g} .. "
            f"{rpm[-1]:.6g} rpm (points {indices[0]}..{indices[-1]})")


def _walk(model, scaling: LoadScaling, settings, kw, extra, unit, emit) -> int:
    """One unit (row, scale, direction, indices, params, first speed, done): the points of
    one direction (piece) of one load row, each new one emitted as (row, record)."""
    row, scale, direction, indices, params, p_first, done = unit
    m = scaling.model_at(model, scale)
    seed = start_state(m, p_first, strict=False)
    new = phase = 0
    for i, p in zip(indices, params):
        rec = done.get(i)
        if rec is None:
            rec = run_point(m, float(p), seed, direction, i, settings, phase0=phase, **kw)
            if rec.ok:
                force, tr = _mesh_force_run(m, float(p), rec.u_end, **extra, t0=rec.u_end_t)
                rec = dataclasses.replace(rec, metrics={**rec.metrics, **force})
                if not tr.ok:
                    # the motion settled but its largest mesh force is unknown: the point
                    # is not ok (a NaN force would be written as 0 N beside status 0)
                    rec = dataclasses.replace(
                        rec, status=int(tr.status), message=f"largest mesh force "
                        f"({extra['periods']} mesh periods from the settled state): "
                        f"{tr.message}")
            emit((row, rec))
            new += 1
        if rec.ok or rec.motion_class != FAILED:      # the motion settled: its end seeds
            seed = np.array(rec.u_end, dtype=float)
            phase = end_phase(m, rec)
    return new


def compute_map(study: Study, scaling: LoadScaling, rpm, scales, settings, options, *,
                out=None, root: bool = True, callback=None, force_periods: int = 4,
                force_samples: int = 128, split=None) -> OperatingMap:
    """The map of ``study`` over ``rpm`` x load factors ``scales`` with the sweep settings
    ``settings`` (:class:`~vibrogear.config.options.SweepOptions`) and integrator
    ``options``.  ``out``: folder of the partial file (None: not resumable);
    ``callback(row, record)`` after each new point; ``split``: a
    :class:`~vibrogear.pipeline.wall_split.WallSplit` that times the units."""
    wall = time.perf_counter()
    rpm = np.asarray(rpm, dtype=float).ravel()
    scales = np.asarray(scales, dtype=float).ravel()
    model = study.model
    groups = contact_groups(model)
    meshes = {k: idx for k, (kind, idx) in groups.items() if kind == "mesh"}
    bearings = tuple(k for k, (kind, _) in groups.items() if kind != "mesh")
    kw = dict(options=options, cluster_tol=1e-3, keep_states=False, settle=True)
    extra = dict(meshes=meshes, periods=int(force_periods), samples=int(force_samples),
                 options=options, force_unit=study.force_unit_n)
    store, done, note = None, {}, ""
    if out is not None and root:
        sig = {"analysis": "map", "physics": study.physics,
               "loads": fingerprint((scaling.f0_rest, scaling.f0_couplings)),
               "scales": [repr(float(s)) for s in scales],
               "grid": [repr(float(p)) for p in rpm],
               "settings": {k: v for k, v in dataclasses.asdict(settings).items()
                            if k != "workers"},
               "force": [int(force_periods), int(force_samples)], "options": options}
        store = PartialStore(Path(out) / PARTIAL_NAME, sig)
        note = store.note
        for item in store.items:
            done[(int(item["row"]), item["direction"], int(item["index"]))] = \
                record_from_json(item)
    directions = tuple(settings.directions)
    units = []
    for k, s in enumerate(scales):
        for d, idx in sweep_units(rpm.size, directions, settings.segments):
            mine = {i: done[(k, d, i)] for i in idx if (k, d, i) in done}
            if len(mine) < len(idx):
                units.append((k, float(s), d, idx, rpm[list(idx)], float(rpm[0]), mine))
    new: dict = {}

    def on_result(_u, item):
        row, rec = item
        new[(row, rec.direction, rec.index)] = rec
        if store is not None:
            store.append({"row": int(row), **record_to_json(rec)})
        if callback is not None:
            callback(row, rec)

    # a unit's cost: its points still to compute (the longest go first)
    run = run_units if split is None else partial(split.run, "walks")
    run(partial(_walk, model, scaling, settings, kw, extra), units, workers=settings.workers,
        on_result=on_result, costs=[len(u[3]) - len(u[6]) for u in units],
        describe=_describe_unit)
    if under_mpi() and not root:
        return broadcast(None)
    records = {**done, **new}
    rows = []
    for k in range(scales.size):
        recs = [records[(k, d, i)] for d, idx in sweep_units(rpm.size, directions, 1)
                for i in idx if (k, d, i) in records]
        rows.append(assemble_result(recs, n_states=model.n_states,
                                    record_periods=settings.record_periods, options=options,
                                    period_tol=settings.period_tol,
                                    param_name=model.param_name))
    failed = sum(int(np.sum(r.status != 0)) for r in rows)
    total = sum(r.param.size for r in rows)
    code, msg = ((Status.PARTIAL, f"{failed} of {total} points failed") if failed
                 else (Status.OK, Status.OK.message))
    result = OperatingMap(rpm=rpm, scale=scales, torque=scaling.torque(scales),
                          twist=scaling.twist(scales), directions=directions, rows=tuple(rows),
                          meshes=tuple(meshes), bearings=bearings, status_code=code,
                          status_message=msg, wall_time=time.perf_counter() - wall,
                          resumed=len(done), workers=settings.workers, study=study, note=note)
    return broadcast(result) if under_mpi() else result


# ---------------------------------------------------------------- the verb

def run(study: Study, scene, ctx: RunContext) -> AnalysisOutcome:
    cfg = scene.map
    if study.gearbox is None:
        raise NumericalFailure("map: needs a gearbox scene")
    split = WallSplit(SERIAL_PART + (CURVES_PART if cfg.curves else ""))
    scaling = load_scaling(study.gearbox, scene.gearbox)
    values = cfg.load_values()
    scales = (scaling.scale_of_twist(values) if cfg.load_kind == "twist"
              else scaling.scale_of_torque(values))
    rpm = cfg.speeds()
    opts = integration_options(scene, record=True, period_tol=cfg.period_tol, section=cfg,
                                study=study)
    total = len(cfg.directions) * rpm.size * scales.size
    with ctx.progress(total, "map") as bar:
        res = compute_map(study, scaling, rpm, scales, SweepOptions.of(cfg), opts, out=ctx.out,
                          root=ctx.root, split=split, force_periods=cfg.force_periods,
                          force_samples=cfg.force_samples,
                          callback=lambda k, rec: bar.update(
                              1, f"{scaling.torque(scales[k]):.4g} N m "
                                 f"({scaling.twist(scales[k]):.4g} rad) {rec.param:.4g} rpm "
                                 f"P{rec.period_n}"))
    failed = sum(int(np.sum(r.status != 0)) for r in res.rows)
    if failed == sum(r.param.size for r in res.rows):
        raise NumericalFailure(f"map: all {failed} points failed; first: "
                               f"{res.rows[0].message[0]}")
    curves = None
    if cfg.curves:              # collective under MPI: every rank computes windows
        from .curves import curves_for_map
        curves = curves_for_map(study, scene, scaling, scales, split=split)
        res = dataclasses.replace(res, curves=curves)
    res = dataclasses.replace(res, load_kind=cfg.load_kind)
    summary = map_summary(res, scaling)
    if curves is not None:
        summary["curves"] = curves.summary()
    if res.note:
        summary["resume"] = res.note
    summary.update(split.summary())
    return AnalysisOutcome(summary=summary, result=res, solver=res.outcome,
                           partial_files=(ctx.out / PARTIAL_NAME,) if ctx.writes else ())


def map_summary(res: OperatingMap, scaling: LoadScaling) -> dict:
    """Grid, loads (both units), classes, cost per point, error estimates."""
    walls = np.concatenate([r.point_wall for r in res.rows]) if res.rows else np.zeros(0)
    new_walls = walls[np.isfinite(walls)]
    classes = np.concatenate([r.motion_class for r in res.rows])
    names = [MOTION_LEGEND[int(c)] for c in classes]
    rhs = res.outcome.counters.get("rhs_calls", 0)     # the rows' sweeps combined
    n = int(walls.size)
    solver = float(np.sum(new_walls))
    return {           # status, message, error estimate: the runner's spine (res.outcome)
        "speeds_rpm": [float(res.rpm[0]), float(res.rpm[-1]), int(res.rpm.size)],
        "loads": {"given_as": res.load_kind, "torque_N_m": [float(x) for x in res.torque],
                  "twist_rad": [float(x) for x in res.twist], "scale": [float(x) for x in res.scale],
                  "nominal_torque_N_m": scaling.torque_nominal,
                  "nominal_twist_rad": scaling.twist_nominal, "motor_coupling": scaling.motor,
                  "torque": "carried by the static state at the motor coupling (the load "
                            "path's), affine in the scale: T(0) + s (T(1) - T(0))",
                  "torque_at_zero_scale_N_m": scaling.torque_zero,
                  "torque_law_error_rel": scaling.torque_law_error_rel},
        "directions": list(res.directions), "points": n, "resumed_points": res.resumed,
        "failed_points": int(sum(int(np.sum(r.status != 0)) for r in res.rows)),
        "motion_classes": {c: names.count(c) for c in MOTION_LEGEND if c in names},
        "cost": {"point_wall_s_sum": solver,
                 "point_wall_s_mean": solver / max(n, 1),
                 "point_wall_s_max": float(new_walls.max()) if new_walls.size else None,
                 "rhs_calls_per_point": rhs / max(n, 1),
                 "workers": res.workers,
                 "points_per_second": (n - res.resumed) / res.wall_time
                 if res.wall_time > 0 else None},
    }


#: the per-mesh metrics of map.npz (``<metric>_<mesh>``)
METRICS_PER_MESH = ("impacts_drive", "impacts_back", "rattle", "contact_fraction", "max_force")


def _finite(a, fill=0.0):
    a = np.asarray(a, dtype=float)
    return np.where(np.isfinite(a), a, fill)


def map_arrays(res) -> dict:
    """The arrays of ``map.npz`` (NaN replaced) as a plain dict (their names and units:
    :mod:`vibrogear.report.writers.map`)."""
    g = res.grid
    status = g("status")
    out = dict(rpm=np.asarray(res.rpm, float), torque=np.asarray(res.torque, float),
               twist=np.asarray(res.twist, float), load_scale=np.asarray(res.scale, float),
               direction=np.asarray(res.directions, dtype="<U4"),
               load_given_as=np.asarray(res.load_kind),
               motion_class=g("motion_class"), motion_class_legend=np.asarray(res.legend),
               period_n=g("period_n"), qmin=_finite(g("qmin")), qmax=_finite(g("qmax")),
               status=status, ok=status == 0, wall_time=_finite(g("point_wall")))
    for m in res.meshes:
        for k in METRICS_PER_MESH:
            out[f"{k}_{m}"] = _finite(g(f"{k}_{m}"))
        out[f"impacts_{m}"] = out[f"impacts_drive_{m}"] + out[f"impacts_back_{m}"]
    for b in res.bearings:
        out[f"unloaded_{b}"] = _finite(g(f"unloaded_{b}"))
    curves = res.curves.curves if res.curves is not None else ()
    out["curve_label"] = np.asarray([c.label for c in curves], dtype="<U2")
    out["curve_start"] = np.concatenate([[0], np.cumsum([c.rpm.size for c in curves])]).astype(int)
    for key in ("rpm", "torque", "twist"):
        out[f"curve_{key}"] = (np.concatenate([getattr(c, key) for c in curves]) if curves
                               else np.zeros(0))
    return out
