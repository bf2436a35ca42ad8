"""Sequential continuation over the study's parameter (paper Fig. 2), resumable.

Written once for every model.  The grid runs from ``param_min`` to ``param_max`` in the
scene's parameter (Omega, or the driving speed in rpm); every unit starts from the static
equilibrium at the first grid value.  Each finished point is appended to
``sweep.partial.jsonl`` as it arrives (:class:`~vibrogear.pipeline.resume.PartialStore`:
reused only when the model's physics, the grid, the sweep settings, the integrator options
and the package version are all the same, else set aside); the runner deletes it once the
report has written ``sweep.npz``.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext, is_root_process
from ...pipeline.resume import PartialStore, fingerprint
from ...pipeline.wall_split import WallSplit
from ...solvers.sequential.motion import CHAOTIC, MOTION_LEGEND, QUASI_PERIODIC
from ...status import Status
from ...solvers.sequential.record_json import json_number as _num, record_from_json, record_to_json
from ...solvers.sequential.sweep import SweepResult, sweep
from ...config.options import SweepOptions
from ..study import Study, integration_options

__all__ = ["SweepStudyResult", "run", "resumable_sweep", "jumps", "PARTIAL_NAME", "motion_summary"]

PARTIAL_NAME = "sweep.partial.jsonl"
#: what the sweep does on one process (summary.json's serial_part)
SERIAL_PART = ("not shared among the workers: the static start and the resume file before "
               "the walks; stacking the points, their spectral evidence and the summary after "
               "them")
#: sweep settings that do not change the results (left out of the resume signature)
_NOT_IN_SIGNATURE = ("workers", "callback", "done")


@dataclass(frozen=True, eq=False)
class SweepStudyResult:
    """A sweep: sequential continuation up and down in the parameter (the bifurcation diagram).

    - ``sweep``: the :class:`~vibrogear.solvers.sequential.sweep.SweepResult`, every point's
      fields with their shapes and units (``help(SweepResult)``): ``param`` (N,) [rpm or
      Omega], ``direction`` (N,), ``qmin`` / ``qmax`` (N,) [m for a gearbox] of the monitored
      mesh deformation, ``poincare`` (N, R) [m], ``period_n`` (N,), ``impacts`` (N,)
      [1/period], ``motion_class`` (N,), ``lyapunov`` (N,) [1/s], ``metrics`` (rattle,
      contact fractions per mesh), ``status`` (N,) (0 ok).
    - ``study``: the :class:`~vibrogear.analyses.study.Study` (model, parameter, monitored
      mesh: ``study.monitor.scale`` converts m to its display unit, um).

    :meth:`arrays`: the arrays of ``sweep.npz`` by the same names (lengths in m; NaN
    replaced by 0 with ``ok`` flags); :meth:`plot`: the bifurcation diagram."""
    sweep: SweepResult
    study: Study

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays of ``sweep.npz``, by the same names
        (:meth:`~vibrogear.solvers.sequential.sweep.SweepResult.arrays`)."""
        return self.sweep.arrays()

    def plot(self, branches=None, *, per_contact_rows: bool = False):
        """The bifurcation diagram (``bifurcation.png``) as a matplotlib Figure: Poincare
        samples, minima and maxima up and down in display units, the motion-class band, the
        impacts and rattle per mesh; ``branches``: a continuation's result
        (``run.results["continuation"]``) to overlay; ``per_contact_rows``: a class row per
        contact group (the scene's ``[figures] motion_rows_per_contact``)."""
        from ...report.plots.bifurcation import sweep_figure
        return sweep_figure(self, branches, per_contact_rows=per_contact_rows)


def jumps(param, q, rel: float = 0.15, res=None, err=None, level: float = 0.05) -> list[float]:
    """Midpoints between successive sweep points whose q differs by > rel * range, by more
    than ``level`` of the larger |q| of the two, than either point's resolution ``res`` and
    than the sum of their batch-means errors ``err`` (NaN or absent: 0)."""
    q = np.asarray(q, float)
    ok = np.isfinite(q)
    span = np.ptp(q[ok]) if np.any(ok) else 0.0
    z = np.zeros(q.size)
    res = z if res is None else np.nan_to_num(np.asarray(res, float))
    err = z if err is None else np.nan_to_num(np.asarray(err, float))
    return [0.5 * (param[k] + param[k - 1]) for k in range(1, len(q))
            if ok[k] and ok[k - 1] and abs(q[k] - q[k - 1]) > rel * span > 0
            and abs(q[k] - q[k - 1]) > max(res[k], res[k - 1], err[k] + err[k - 1],
                                           level * max(abs(q[k]), abs(q[k - 1])))]


def resumable_sweep(model, params, out_dir, *, physics: str | None = None, callback=None,
                    root: bool | None = None, **sweep_kw) -> tuple[SweepResult, PartialStore | None, int]:
    """:func:`~vibrogear.solvers.sequential.sweep.sweep` with each finished point appended to
    ``out_dir/sweep.partial.jsonl`` and the points of a matching partial file reused.
    ``physics``: fingerprint of the model (default: its content hash).  Returns (result,
    store, resumed points); ``store`` is None when ``root`` is False (MPI ranks other than 0
    touch no files).  The caller deletes ``store.path`` once the final files exist."""
    params = np.asarray(params, dtype=float).ravel()
    store, done = None, {}
    if out_dir is not None and (root if root is not None else is_root_process()):
        settings = {k: v for k, v in dataclasses.asdict(sweep_kw["settings"]).items()
                    if k not in _NOT_IN_SIGNATURE}
        u0 = sweep_kw.get("u0")
        store = PartialStore(Path(out_dir) / PARTIAL_NAME, {
            "analysis": "sweep", "physics": physics or fingerprint(model),
            "grid": [repr(float(p)) for p in params], "settings": settings,
            "options": sweep_kw.get("options"), "start": None if u0 is None else fingerprint(u0)})
        for item in store.items:
            rec = record_from_json(item)
            done[(rec.direction, rec.index)] = rec

    def on_point(rec):
        if store is not None:
            store.append(record_to_json(rec))
        return None if callback is None else callback(rec)

    result = sweep(model, params, callback=on_point, done=done, **sweep_kw)
    return result, store, len(done)


def run(study: Study, scene, ctx: RunContext) -> AnalysisOutcome:
    cfg = scene.sweep
    split = WallSplit(SERIAL_PART)
    lo, hi = cfg.param_range()
    params = np.linspace(lo, hi, cfg.n_points)
    opts = integration_options(scene, record=True, period_tol=cfg.period_tol, study=study)
    total = len(cfg.directions) * params.size
    with ctx.progress(total, "sweep") as bar:
        res, store, resumed = resumable_sweep(
            study.model, params, ctx.out, physics=study.physics, root=ctx.writes, split=split,
            callback=lambda rec: bar.update(1, f"{rec.param:.4g} {study.param_unit} "
                                               f"P{rec.period_n}"),
            settings=SweepOptions.of(cfg), options=opts, u0=study.start(params[0]))
    failed = int(np.sum(res.status != 0))
    if res.motion_class is not None and study.model.contacts.count:
        # kv_, rattle_db_, rattle_threshold_ (the linear model at each point's speed)
        from ..mesh_loads import mesh_judgement_arrays, rattle_threshold, static_mesh_forces
        from ...solvers.sequential.record_metrics import contact_groups
        groups, start = contact_groups(study.model), study.start(params[0])
        res.metrics.update(mesh_judgement_arrays(res.metrics, static_mesh_forces(
            study.model, start, groups)))
        speeds, at = np.unique(res.param, return_inverse=True)
        res.metrics.update({k: v[at] for k, v in rattle_threshold(
            study.model, start, groups, speeds).items()})
    if failed == res.param.size:
        raise NumericalFailure(f"sweep: all {failed} points failed; first: "
                               f"{study.param_name} = {res.param[0]:g}: {res.message[0]}")
    warnings = []
    if opts.rtol > cfg.period_tol:
        warnings.append(f"integration rtol = {opts.rtol:g} is looser than sweep.period_tol = "
                        f"{cfg.period_tol:g}: integration error alone can make periodic points "
                        f"look 'not periodic'; use rtol <= {cfg.period_tol:g}")
    up = res.direction == "up"
    classes = {str(int(k)): int(np.sum(res.period_n == k)) for k in np.unique(res.period_n)}
    # status, message, counters, wall time, error estimate: the runner's spine, from
    # res.outcome; here the domain entries
    rules = getattr(scene, "findings", None)
    jump_rule = {} if rules is None else {"rel": rules.jump_rel, "level": rules.jump_level_rel}
    summary = {
        "points": int(res.param.size),
        "resumed_points": resumed, "failed_points": failed, "period_classes": classes,
        "points_with_contact_loss": int(np.sum(res.impacts > 0)),
        "monitored": study.monitor.name or study.monitor.label,
        "point_wall_split_s": {k: round(v, 3) for k, v in res.timings.items()},
        "jumps_up": jumps(res.param[up], res.qmax[up], res=_m(res, "qmax_res", up),
                          err=_m(res, "qmax_err", up), **jump_rule),
        "jumps_down": jumps(res.param[~up], res.qmax[~up], res=_m(res, "qmax_res", ~up),
                            err=_m(res, "qmax_err", ~up), **jump_rule),
    }
    summary.update(motion_summary(res, cfg.transient_periods + cfg.extra_transient_periods))
    summary.update(split.summary())
    if store is not None and store.note:
        summary["resume"] = store.note
    # stopped: keep the partial file
    keep = store is None or res.status_code == Status.STOPPED_BY_CALLBACK
    return AnalysisOutcome(summary=summary, result=SweepStudyResult(res, study),
                           partial_files=() if keep else (store.path,),
                           warnings=tuple(warnings), solver=res.outcome)


def _m(res: SweepResult, key: str, sel):
    """A metric of the selected points, or None where the sweep has none."""
    v = res.metrics.get(key)
    return None if v is None else np.asarray(v, float)[sel]


def motion_summary(res: SweepResult, budget: int) -> dict:
    """Motion classes, the chaotic points with their exponents, transient lengths and,
    per contact metric, its largest value over the points (where, and its error)."""
    if res.motion_class is None:
        return {}
    ok = res.status == 0
    names = [MOTION_LEGEND[int(c)] for c in res.motion_class]
    ev = res.spectral
    chaotic = [{"param": float(res.param[k]), "direction": str(res.direction[k]),
                "lyapunov": float(res.lyapunov[k]),
                "lyapunov_ci": [float(c) for c in res.lyapunov_ci[k]],
                **{name: _num(res.metrics[name][k]) for name in
                   ("lyapunov_per_s", "lyapunov_lo_per_s", "lyapunov_per_period",
                    "lyapunov_lo_per_period", "lyapunov_floor_per_period")
                   if name in res.metrics},
                "strob_flatness": float(ev["strob_flatness"][k])}
               for k in np.flatnonzero(res.motion_class == CHAOTIC)]
    # a quasi-periodic point names its base frequencies: the excitation's and f2
    quasi = [{"param": float(res.param[k]), "direction": str(res.direction[k]),
              "f2_order": float(ev["base_f2_order"][k]),
              "lyapunov_ci": [float(c) for c in res.lyapunov_ci[k]],
              "strob_flatness": float(ev["strob_flatness"][k])}
             for k in np.flatnonzero(res.motion_class == QUASI_PERIODIC)]
    used = res.transient_used[ok]
    metrics = {}
    for key, v in res.metrics.items():
        if key.endswith("_err") or key.startswith(("period_n_", "motion_class_", "lyapunov",
                                                   "resolution_", "qmax_")):
            continue
        v = np.where(ok, np.asarray(v, float), np.nan)
        if not np.any(np.isfinite(v)):
            continue
        k = int(np.nanargmax(v))
        err = res.metrics.get(f"{key}_err")
        tol = res.metrics.get(f"{key}_tol_err")
        metrics[key] = {"max": float(v[k]), "at": float(res.param[k]),
                        "direction": str(res.direction[k]),
                        "err": _num(err[k]) if err is not None else None}
        if tol is not None:
            metrics[key]["tol_err"] = _num(tol[k])
    return {"motion_classes": {n: names.count(n) for n in MOTION_LEGEND if n in names},
            "chaotic_points": chaotic, "quasi_periodic_points": quasi,
            "transient": {"budget": int(budget), "mean_used": _num(np.mean(used))
                          if used.size else None,
                          "max_used": int(used.max()) if used.size else None,
                          "settled_by": {s: int(np.sum(res.settled_by[ok] == s))
                                         for s in ("map", "statistics", "budget")}},
            "contact_metrics_max": metrics}
