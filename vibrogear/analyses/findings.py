"""Findings: where the gearbox loses contact, rattles, jumps or goes chaotic, and which
speeds to avoid, derived from the files a run wrote.

:func:`derive_findings` is a pure function of the per-point arrays of the run's files
(``sweep.npz``, ``branch.npz``, ``erp.csv``, ``map.npz``, ``states.npz``: file name ->
{array name -> array}), the run's summary records and the rules of ``[findings]``
(:class:`~vibrogear.config.findings_section.FindingsConfig`).  It returns::

    {"verdict": str,
     "bands":  [{"quantity", "where", "direction", "from", "to", "severity",
                 "metric", "op", "threshold", "evidence", "source", "edge_err", ...}],
     "events": [{"kind", "at", "where", "evidence"}],
     "rules":  {...}, "checked": [...], "partial": [...]}

A band is a run of neighbouring grid points at which ``metric op threshold`` holds on the
array ``metric`` of the file ``source``; ``from``/``to`` are the first and last such grid
points (in the scene's parameter unit) and ``edge_err`` the grid step: the true edge lies
within one step outside.  ``direction`` is ``up`` or ``down`` where the test holds in one
sweep direction only, ``both`` where it holds in both.  ``compare = "abs(up - down)"``
marks the one band whose test is on the difference of the two directions at equal speed.
The evidence quotes the metric's range over the band with its batch-means error (``_err``).
Every band can so be recomputed from the file: ``tests/unit/test_findings.py`` does it.
"""
from __future__ import annotations

import numpy as np

from ..pipeline.files import listed_paths

from .findings_bands import Band, map_bands, sweep_bands
from .findings_events import (branch_events, erp_findings, resonance_events, runup_findings,
                              states_findings)
from .findings_text import verdict_text

__all__ = ["derive_findings", "run_findings", "read_sources", "SOURCE_FILES", "Band"]

#: the files findings are derived from (as the run's analyses list them in ``files``)
SOURCE_FILES = ("sweep.npz", "branch.npz", "erp.csv", "map.npz", "states.npz", "runup.npz")


def read_sources(results: dict) -> dict[str, dict[str, np.ndarray]]:
    """{file name: {array: values}} of the source files that this run's analyses wrote
    (their summary records' ``files``), so that findings never mix in another run's files."""
    from pathlib import Path
    found: dict[str, dict[str, np.ndarray]] = {}
    for record in results.values():
        if not isinstance(record, dict):
            continue
        for text in listed_paths(record.get("files")):
            path = Path(text)
            if path.name not in SOURCE_FILES or path.name in found or not path.is_file():
                continue
            if path.suffix == ".npz":
                with np.load(path, allow_pickle=False) as z:
                    found[path.name] = {k: z[k] for k in z.files}
            else:
                found[path.name] = _read_csv(path)
    return found


def _read_csv(path) -> dict[str, np.ndarray]:
    import csv
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], rows[1:]
    return {name: np.array([float(r[i]) if r[i] else np.nan for r in body])
            for i, name in enumerate(header)}


def run_findings(scene, results: dict, sources: dict | None = None) -> dict | None:
    """The findings of a run of ``scene`` whose summary records are ``results`` (None for
    scenes without a speed parameter: rotor-only and housing-only scenes).  ``sources``:
    {file name: arrays} of a run in memory (the arrays its results would write), besides
    the files the records list."""
    parameter = scene.parameter
    if parameter is None:
        return None
    gearbox = parameter.name == "rpm"
    found = {**read_sources(results), **(sources or {})}
    return derive_findings(found, results, scene.findings,
                           param_unit=parameter.unit, length_scale=1e6 if gearbox else 1.0,
                           length_unit="µm" if gearbox else "")


def derive_findings(sources: dict[str, dict[str, np.ndarray]], records: dict, rules, *,
                    param_unit: str = "rpm", length_scale: float = 1e6,
                    length_unit: str = "µm") -> dict:
    """The findings of one run (module docstring).  ``records``: ``summary["results"]``;
    ``length_scale``/``length_unit``: how deformations are quoted (m -> µm for a gearbox,
    1 and "" for the nondimensional impact pair)."""
    bands: list[Band] = []
    events: list[dict] = []
    checked: list[str] = []
    units = dict(param_unit=param_unit, length_scale=length_scale, length_unit=length_unit)
    sweep = sources.get("sweep.npz")
    if sweep is not None and np.asarray(sweep.get("param", [])).size:
        rec = records.get("sweep")
        monitored = rec.get("monitored") if isinstance(rec, dict) else None
        b, e, c = sweep_bands(sweep, rules, **units, monitored=monitored or "monitored contact")
        bands += b
        events += e
        checked += c
    grid = sources.get("map.npz")
    if grid is not None and np.asarray(grid.get("rpm", [])).size:
        b, c = map_bands(grid, rules, param_unit=param_unit)
        bands += b
        checked += c
    runup = sources.get("runup.npz")
    if runup is not None:
        bands += runup_findings(runup, rules, param_unit=param_unit)
        checked.append("run-up / run-down: contact losses over the instantaneous speed")
    branch = sources.get("branch.npz")
    if branch is not None and np.asarray(branch.get("param", [])).size:
        events += branch_events(branch, **units)
        checked.append("continuation: folds (LP), period doublings (PD), tori (NS) on the "
                       "traced branches")
    erp = sources.get("erp.csv")
    if erp is not None and np.asarray(erp.get("rpm", [])).size:
        b, e = erp_findings(erp, rules, direction=_nvh_direction(records))
        bands += b
        events += e
        checked.append("radiated power (ERP) of the housing")
    states = sources.get("states.npz")
    if states is not None and np.asarray(states.get("attractor_param", [])).size:
        b, e = states_findings(states, rules, **units)
        bands += b
        events += e
        checked.append("coexisting states from random starts")
    modes = records.get("modes")
    if isinstance(modes, dict) and modes.get("resonance_speeds_rpm"):
        events += resonance_events(modes["resonance_speeds_rpm"], rules)
        checked.append("resonance speeds: mesh orders x modes")
    partial = [f"{name}: {rec.get('status')}" + (f" ({rec['message']})" if rec.get("message")
                                                 else "")
               for name, rec in records.items()
               if isinstance(rec, dict) and rec.get("status") not in (None, "ok")]
    span = _span(sources)
    bands.sort(key=lambda b: (-_rank(b.severity), b.quantity, b.where, b.start))
    events.sort(key=lambda e: (e["kind"], e["at"]))
    out_bands = [b.as_dict() for b in bands]
    return {"verdict": verdict_text(out_bands, checked, span, partial, param_unit),
            "bands": out_bands, "events": events, "rules": rules.rules(),
            "checked": checked, "partial": partial,
            "range": None if span is None else [span[0], span[1]], "param_unit": param_unit}


def _rank(severity: str) -> int:
    return {"fine": 0, "caution": 1, "avoid": 2}.get(severity, 0)


def _nvh_direction(records: dict) -> str:
    nvh = records.get("nvh")
    if isinstance(nvh, dict) and nvh.get("sweep_direction") in ("up", "down"):
        return nvh["sweep_direction"]
    return "up"


def _span(sources) -> tuple[float, float] | None:
    for name, key in (("sweep.npz", "param"), ("map.npz", "rpm"), ("erp.csv", "rpm"),
                      ("states.npz", "attractor_param")):
        arrays = sources.get(name)
        if arrays is not None and np.asarray(arrays.get(key, [])).size:
            p = np.asarray(arrays[key], float)
            return float(p.min()), float(p.max())
    return None

