"""Files of ``vibrogear optimize`` (:mod:`vibrogear.analyses.optimize.optimize`).

* ``optimize.csv``: every evaluation in the order the method asked for it: its number, the
  variables, the objective, each constraint's value, whether it is feasible, the penalised
  value the method minimised, status ("ok" | "failed"), the reason of a failure, wall time;
* ``optimize.json``: the summary (method, why it stopped, counts), the best evaluation and
  the whole history;
* ``best_scene.toml``: the evaluated scene (its analyses, without [optimize]) with the best
  variables: ``vibrogear check`` accepts it and ``vibrogear run`` runs it;
* ``optimize_convergence.png/.svg`` and, for one or two variables,
  ``optimize_landscape.png/.svg`` (:mod:`..plots.optimize`).
"""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

from ...config.sections.optimize import data_with
from ...pipeline.files import atomic_write_csv, atomic_write_text, finite_json
from ..figure import save_figure
from ..plots.optimize import plot_convergence, plot_landscape

__all__ = ["write", "toml_text", "best_so_far"]


def best_so_far(result) -> list[float]:
    """After each evaluation, the best feasible objective so far (NaN before the first)."""
    s = 1.0 if result.objective.sense == "min" else -1.0
    out, best = [], math.nan
    for h in result.history:
        if h["feasible"] and (math.isnan(best) or s * h["objective"] < s * best):
            best = h["objective"]
        out.append(best)
    return out


def _csv(result, out: Path) -> Path:
    keys = [v.key for v in result.variables]
    cons = [f"constraint_{i}_{c.reduce}_{c.metric}" for i, c in enumerate(result.constraints)]
    header = ["evaluation", *keys, f"objective_{result.objective.reduce}_"
              f"{result.objective.metric}", *cons, "feasible", "penalised", "status",
              "wall_s", "cpu_s", "reason"]
    rows = []
    for h in result.history:
        cvals = list(h["constraints"]) or [None] * len(cons)
        rows.append([h["evaluation"], *(repr(h["values"][k]) for k in keys),
                     "" if h["objective"] is None else repr(float(h["objective"])),
                     *("" if c is None else repr(float(c)) for c in cvals),
                     str(bool(h["feasible"])).lower(), repr(float(h["f"])), h["status"],
                     f"{h.get('wall_s', 0.0):.3f}", f"{h.get('cpu_s', 0.0):.3f}",
                     h.get("reason", "")])
    return atomic_write_csv(out / "optimize.csv", header, rows)


_BARE = re.compile(r"[A-Za-z0-9_-]+")


def _k(key: str) -> str:
    return key if _BARE.fullmatch(key) else json.dumps(key)


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("nan" if math.isnan(v) else
                                                 ("inf" if v > 0 else "-inf"))
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_k(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def toml_text(data: dict, prefix: str = "") -> str:
    """``data`` (tables, arrays of tables, values) as TOML text."""
    lines, tables = [], []
    for k, v in data.items():
        if isinstance(v, dict):
            tables.append((k, v, False))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            tables.append((k, v, True))
        else:
            lines.append(f"{_k(k)} = {_value(v)}")
    text = "\n".join(lines) + ("\n" if lines else "")
    for k, v, many in tables:
        name = f"{prefix}.{_k(k)}" if prefix else _k(k)
        for item in (v if many else [v]):
            text += f"\n{'[[' if many else '['}{name}{']]' if many else ']'}\n"
            text += toml_text(item, name)
    return text


def _best_scene(result) -> str:
    data = data_with(result.base, result.best["values"])
    values = ", ".join(f"{k} = {v!r}" for k, v in result.best["values"].items())
    head = (f"# best evaluation ({result.best['evaluation']}) of vibrogear optimize, method "
            f"{result.method}: {values}\n# objective {result.objective.reduce} "
            f"{result.objective.metric} = {result.best['objective']!r}"
            f"{'' if result.best['feasible'] else ' (violates a constraint)'}\n")
    return head + toml_text(data)


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    out = Path(out)
    files = {"csv": str(_csv(r, out))}
    doc = {**outcome.record(), "variables": [
        {"key": v.key, "min": v.min, "max": v.max, "log": v.log, "integer": v.integer}
        for v in r.variables], "history": [
        {k: h.get(k) for k in ("evaluation", "values", "objective", "constraints", "feasible",
                                "f", "status", "reason", "wall_s", "cpu_s")} for h in r.history]}
    files["json"] = str(atomic_write_text(out / "optimize.json",
                                          json.dumps(finite_json(doc), indent=2)))
    if r.best is not None:
        files["best_scene"] = str(atomic_write_text(out / "best_scene.toml", _best_scene(r)))
    label = (r.objective.metric if r.objective.metric in {v.key for v in r.variables}
             and r.objective.analysis is None else f"{r.objective.reduce} {r.objective.metric}")
    save_figure(plot_convergence(r.history, best_so_far(r), label=label, title=r.title),
                out / "optimize_convergence")
    files["convergence_png"] = str(out / "optimize_convergence.png")
    if len(r.variables) <= 2 and any(h["status"] == "ok" for h in r.history):
        save_figure(plot_landscape(r.history, r.variables, r.best, label=label, title=r.title,
                                   constraints=r.constraints), out / "optimize_landscape")
        files["landscape_png"] = str(out / "optimize_landscape.png")
    return files
