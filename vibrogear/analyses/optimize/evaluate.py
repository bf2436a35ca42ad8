"""One evaluation of ``vibrogear optimize``: the scene with the variables set, its analyses run
as the runner runs them (from the verb registry, :mod:`vibrogear.config.verbs`), and the
objective and constraint metrics read from the returned outcomes.

A metric is read from an analysis's outcome (:func:`metric_values`), first from its result
object, then from its summary:

* a sweep (:class:`~.sweep.SweepStudyResult`) or an operating map: a per-point quantity
  (``qmax``, ``qmin``, ``impacts``, ``period_n``, ...) or contact metric (``rattle_G2``,
  ``impacts_drive_G2``, ``max_force_G1``, ...) over its settled points;
* a continuation: ``LP`` / ``PD`` / ``NS`` (the parameter of each such point), ``qmax``;
* any other array attribute of the result (nvh: ``erp_w``, ``erp_db``);
* a summary entry by its dotted path (``erp_max_w``, ``folds``, ``first_frequencies_hz``,
  ``contact_metrics_max.rattle_G2.max``): a number or a list of numbers.

``reduce`` makes one number of the values: max, min, mean, sum, count or range (max - min;
0 for fewer than two values).  An evaluation that fails (invalid scene, numerical failure,
a metric that is missing or has no values) returns its reason; it never stops the run.
"""
from __future__ import annotations

import shutil
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...config.base import ConfigError
from ...config.sections.optimize import data_with
from ...config.verbs import VERBS
from ...pipeline.outcome import AnalysisOutcome, RunContext
from ...status import Outcome
from ..invoke import invoke, load, with_needs

__all__ = ["Evaluation", "MetricError", "metric_values", "reduce_values", "scene_with", "evaluate",
           "solver_record", "solver_outcome"]


class MetricError(Exception):
    """A metric the outcome does not have, or has no finite value of."""


@dataclass(frozen=True)
class Evaluation:
    """What each evaluation needs (plain data: it travels to worker processes by fork)."""
    base: dict                 # the evaluated scene as data (evaluation_data)
    config: object             # OptimizeConfig
    scratch: str | None        # folder for the analyses' partial files (removed after);
                               # None: evaluations in memory (a run without an output folder)


def scene_with(base: dict, config, values: dict):
    """The scene built from ``base`` with each variable key set to ``values[key]``."""
    from ...config.scene import scene_from_dict

    return scene_from_dict(data_with(base, {v.key: values[v.key] for v in config.variables}))


def _run_analyses(scene, ctx: RunContext,
                  outcomes: dict[str, AnalysisOutcome]) -> dict[str, AnalysisOutcome]:
    """The scene's analyses run in order into ``outcomes`` (those before a failure stay)."""
    kind = scene.model_kind
    study = None
    for name in scene.scene.analyses:
        run = VERBS[name].runs[kind]
        if run.study and study is None:
            from ..study import build_study
            study = build_study(scene)
        outcomes[name] = invoke(load(f"vibrogear.analyses.{run.analysis}"),
                                study if run.study else None, scene, ctx,
                                with_needs(name, kind, study, scene, ctx, outcomes))
    return outcomes


def _ok_points(res):
    return np.asarray(res.status) == 0


def _from_sweep_like(rows, name):
    parts = []
    for res in rows:
        vals = getattr(res, name, None)
        if vals is None:
            vals = getattr(res, "metrics", {}).get(name)
        if vals is None:
            return None
        vals = np.asarray(vals)
        if vals.ndim != 1 or vals.dtype.kind not in "iuf":
            return None
        parts.append(vals[_ok_points(res)].astype(float))
    return np.concatenate(parts) if parts else None


def _summary_value(summary: dict, name: str):
    node = summary
    for part in name.split("."):
        if isinstance(node, dict) and part in node:
            node = node[part]
        elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        else:
            return None
    if isinstance(node, bool):
        return np.array([float(node)])
    if isinstance(node, (int, float)):
        return np.array([float(node)])
    if isinstance(node, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                      for v in node):
        return np.array(node, dtype=float)
    return None


def metric_values(outcome: AnalysisOutcome, name: str) -> np.ndarray | None:
    """The values of metric ``name`` over the analysis's operating range (module
    docstring); None where the outcome has no such metric."""
    r = outcome.result
    rows = None
    if hasattr(r, "sweep") and hasattr(r.sweep, "status"):
        rows = (r.sweep,)
    elif hasattr(r, "rows") and r.rows and hasattr(r.rows[0], "status"):
        rows = tuple(r.rows)
    if rows is not None:
        got = _from_sweep_like(rows, name)
        if got is not None:
            return got
    inner = getattr(r, "result", None)
    if name in ("LP", "PD", "NS", "BP") and hasattr(inner, "special_points"):
        return np.array([s.param for s in inner.special_points if s.label == name], float)
    if name == "qmax" and hasattr(r, "branches"):
        return np.array([p.qmax for b in r.branches for p in b.points], float)
    vals = getattr(r, name, None) if r is not None and not name.startswith("_") else None
    if isinstance(vals, np.ndarray) and vals.dtype.kind in "iuf":
        return vals.astype(float).ravel()
    return _summary_value(outcome.record(), name)


def available_metrics(outcome: AnalysisOutcome) -> list[str]:
    """Names :func:`metric_values` reads (for the message of a missing metric)."""
    names = []
    r = outcome.result
    res = getattr(r, "sweep", None) or (r.rows[0] if getattr(r, "rows", None) else None)
    if res is not None and hasattr(res, "metrics"):
        names += sorted(k for k in res.metrics if not k.endswith("_err"))
        names += ["qmax", "qmin", "impacts", "period_n"]
    if hasattr(getattr(r, "result", None), "special_points"):
        names += ["LP", "PD", "NS", "qmax"]
    if r is not None and hasattr(r, "__dict__"):
        names += [k for k, v in vars(r).items() if isinstance(v, np.ndarray)]
    names += _summary_paths(outcome.record())
    return list(dict.fromkeys(names))


def _summary_paths(node, prefix: str = "", depth: int = 3) -> list[str]:
    out = []
    for k, v in node.items():
        path = f"{prefix}{k}"
        if isinstance(v, dict) and depth > 1:
            out += _summary_paths(v, f"{path}.", depth - 1)
        elif _summary_value({k: v}, k) is not None:
            out.append(path)
    return out


def reduce_values(values: np.ndarray, how: str) -> float:
    """One number from a metric's values (NaN ones left out); NaN where max/min/mean have
    no value."""
    v = np.asarray(values, dtype=float).ravel()
    v = v[np.isfinite(v)]
    if how == "count":
        return float(v.size)
    if how == "sum":
        return float(v.sum())
    if how == "range":
        return float(np.ptp(v)) if v.size >= 2 else 0.0
    if v.size == 0:
        return float("nan")
    return float({"max": np.max, "min": np.min, "mean": np.mean}[how](v))


def _read(cfg, item, values: dict, outcomes: dict) -> float:
    if item.metric in values and cfg.analysis_of(item) is None:
        return float(values[item.metric])
    name = cfg.analysis_of(item)
    got = metric_values(outcomes[name], item.metric)
    if got is None:
        raise MetricError(f"{name} has no metric {item.metric!r}; it has: "
                          f"{', '.join(available_metrics(outcomes[name]))}")
    x = reduce_values(got, item.reduce)
    if not np.isfinite(x):
        raise MetricError(f"{name}: metric {item.metric!r} has no finite value to "
                          f"reduce ({item.reduce})")
    return x


def evaluate(task: Evaluation, index: int, values: dict) -> dict:
    """Run one evaluation; returns its record (JSON-able): the values, objective,
    constraint values, status ("ok" | "failed"), reason, wall time and ``solver``: the
    outcome of the solves its analyses ran (:func:`solver_record`; those of the analyses
    that finished where one failed)."""
    cfg = task.config
    t0, c0 = time.perf_counter(), time.process_time()
    record = {"index": int(index), "values": dict(values), "objective": None,
              "constraints": [], "status": "failed", "reason": ""}
    scratch = None if task.scratch is None else Path(task.scratch) / f"eval-{index}"
    outcomes: dict[str, AnalysisOutcome] = {}
    try:
        scene = scene_with(task.base, cfg, values)
        from ...models.validate import validate_scene
        validate_scene(scene)
        if scratch is not None:
            scratch.mkdir(parents=True, exist_ok=True)
        _run_analyses(scene, RunContext(out=scratch, quiet=True), outcomes)
        record["objective"] = _read(cfg, cfg.objective, values, outcomes)
        record["constraints"] = [_read(cfg, c, values, outcomes) for c in cfg.constraints]
        record["status"] = "ok"
    except (KeyboardInterrupt, SystemExit):
        raise
    except ConfigError as exc:
        record["reason"] = f"invalid scene: {exc}"
    except MetricError as exc:
        record["reason"] = str(exc)
    except Exception as exc:                       # noqa: BLE001 - recorded, penalised
        record["reason"] = f"{type(exc).__name__}: {exc}"
        record["traceback"] = traceback.format_exc(limit=6)
    finally:
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)
    record["wall_s"] = time.perf_counter() - t0
    record["cpu_s"] = time.process_time() - c0
    record["solver"] = solver_record(Outcome.combine(
        o.solver for o in outcomes.values() if o.solver is not None))
    return record


def solver_record(outcome: Outcome) -> dict:
    """An :class:`~vibrogear.status.Outcome` as JSON-able data (status code, message,
    counters, wall time; an evaluation's record travels between processes and to the
    partial file); :func:`solver_outcome` reads it back."""
    return {"status": int(outcome.status), "message": outcome.message,
            "counters": dict(outcome.counters), "wall_s": outcome.wall_s}


def solver_outcome(record: dict) -> Outcome:
    """The outcome of an evaluation's solves from its record (no solves: a record written
    before records carried them, or an evaluation that failed before any analysis ran)."""
    s = record.get("solver") or {}
    return Outcome(s.get("status", 0), s.get("message", "ok"), s.get("counters", {}),
                   s.get("wall_s", 0.0), {})
