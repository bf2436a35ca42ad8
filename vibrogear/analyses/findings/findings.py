"""Findings: where the gearbox loses contact, rattles, jumps or goes chaotic, and which
speeds to avoid, derived from the files a run wrote.

:func:`derive_findings` is a pure function of the per-point arrays of the run's files
(``sweep.npz``, ``branch.npz``, ``erp.csv``, ``map.npz``, ``states.npz``: file name ->
{array name -> array}), the run's summary records and the rules of ``[findings]``
(:class:`~vibrogear.config.sections.findings.FindingsConfig`).  It returns::

    {"verdict": str,
     "windows": [{"from", "to", "status", "limits", "margin"}],
     "meshes": [{"name", "role", "static_force_N", ...}],
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

from ...config.numbers import fmt, fmt_param
from ...pipeline.files import listed_paths

from .band_rule import Band
from .bands import map_bands, sweep_bands
from .iso_resonance import iso_bands
from .events import branch_events, erp_findings, resonance_events, runup_findings, states_findings
from .text import verdict_text

__all__ = ["derive_findings", "run_findings", "read_sources", "SOURCE_FILES", "Band",
           "mesh_roles", "windows", "mesh_summary"]

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


def run_findings(scene, results: dict, sources: dict | None = None,
                 load_path: dict | None = None) -> dict | None:
    """The findings of a run of ``scene`` whose summary records are ``results`` (None for
    scenes without a speed parameter: rotor-only and housing-only scenes).  ``sources``:
    {file name: arrays} of a run in memory (the arrays its results would write), besides
    the files the records list; ``load_path``: ``summary["load_path"]`` (the meshes' roles;
    absent: the roles from the structure alone)."""
    parameter = scene.parameter
    if parameter is None:
        return None
    gearbox = parameter.name == "rpm"
    resonance = None
    if load_path is None and gearbox and getattr(scene, "gearbox", None) is not None:
        # no load path in the summary (an older run): the roles from the structure alone
        from ...models.gearbox.load_path import mesh_roles as structural_roles
        load_path = {"meshes": [{"name": m.name, "role": r, "static_force_N": None}
                                for m, r in zip(scene.gearbox.meshes,
                                                structural_roles(scene.gearbox))]}
    if gearbox and getattr(scene, "gearbox", None) is not None:
        try:
            from .iso_resonance import iso_resonances
            resonance = iso_resonances(scene.gearbox)
        except Exception as exc:      # the standard's data incomplete: stated, not fatal
            resonance = {"error": f"{type(exc).__name__}: {exc}"}
    found = {**read_sources(results), **(sources or {})}
    return derive_findings(found, results, scene.findings,
                           param_unit=parameter.unit, length_scale=1e6 if gearbox else 1.0,
                           length_unit="µm" if gearbox else "", load_path=load_path,
                           iso=resonance)


def _key(name: str) -> str:
    """A mesh name as the sweep's array names spell it (record_metrics.contact_groups)."""
    import re
    return re.sub(r"[^0-9A-Za-z]+", "_", str(name)).strip("_") or "contact"


def mesh_roles(load_path: dict | None) -> list[dict]:
    """[{"name", "role", "static_force_N"}] from ``summary["load_path"]`` (its ``meshes``:
    LoadPath.as_dict()); [] without one."""
    out = []
    for m in (load_path or {}).get("meshes", []) or []:
        force = m.get("static_force_N", m.get("normal_force_N"))
        out.append({"name": str(m["name"]), "role": str(m.get("role", "loaded")),
                    "static_force_N": None if force is None else float(force)})
    return out


def derive_findings(sources: dict[str, dict[str, np.ndarray]], records: dict, rules, *,
                    param_unit: str = "rpm", length_scale: float = 1e6,
                    length_unit: str = "µm", load_path: dict | None = None,
                    iso: dict | None = None) -> dict:
    """The findings of one run (module docstring).  ``records``: ``summary["results"]``;
    ``length_scale``/``length_unit``: how deformations are quoted (m -> µm for a gearbox,
    1 and "" for the nondimensional impact pair); ``load_path``: ``summary["load_path"]``
    (each mesh's role); ``iso``: the ISO 6336-1 resonance speeds
    (:func:`~.iso_resonance.iso_resonances`)."""
    bands: list[Band] = []
    events: list[dict] = []
    checked: list[str] = []
    units = dict(param_unit=param_unit, length_scale=length_scale, length_unit=length_unit)
    meshes = mesh_roles(load_path)
    roles = {_key(m["name"]): m["role"] for m in meshes} if meshes else None
    sweep = sources.get("sweep.npz")
    if sweep is not None and np.asarray(sweep.get("param", [])).size:
        rec = records.get("sweep")
        monitored = rec.get("monitored") if isinstance(rec, dict) else None
        b, e, c = sweep_bands(sweep, rules, **units, monitored=monitored or "monitored contact",
                              roles=roles)
        bands += b
        events += e
        checked += c
    grid = sources.get("map.npz")
    if grid is not None and np.asarray(grid.get("rpm", [])).size:
        b, c = map_bands(grid, rules, param_unit=param_unit, roles=roles)
        bands += b
        checked += c
    runup = sources.get("runup.npz")
    if runup is not None:
        bands += runup_findings(runup, rules, param_unit=param_unit, roles=roles)
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
        b, e = states_findings(states, rules, **units, roles=roles)
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
    if iso and iso.get("meshes") and span is not None and param_unit == "rpm":
        b, c = iso_bands(iso, roles, rules, span)
        bands += b
        checked += c
    bands.sort(key=lambda b: (-_rank(b.severity), -float(b.extra.get("margin", 0.0)),
                              b.quantity, b.where, b.start))
    events.sort(key=lambda e: (e["kind"], e["at"]))
    out_bands = [b.as_dict() for b in bands]
    grid = _grid(sources)
    win = windows(out_bands, grid, sources)
    judged = mesh_summary(meshes, sweep, iso)
    for b in out_bands:          # the standard's resonance beside the simulated kv peak
        m = next((m for m in judged if m["name"] == b["where"]), None)
        if b["source"] == "iso6336" and m is not None and "kv_peak" in m:
            b["evidence"] += (f"; the simulated dynamic factor peaks at kv = "
                              f"{fmt(m['kv_peak'], 3)} at {fmt_param(m['kv_peak_at'])} rpm")
        ratio = _within(sweep, f"rattle_threshold_{_key(b['where'])}", b)
        if str(b.get("metric", "")).startswith("rattle_db_") and ratio is not None:
            b["evidence"] += (f"; its inertia torque to follow the mesh is "
                              f"{_span_text(ratio)} x its drag torque there (the rattle "
                              "threshold ratio, linear model: above 1 the drag cannot hold "
                              "it on its drive flank)")
    return {"verdict": verdict_text(out_bands, checked, span, partial, param_unit, win),
            "windows": win, "meshes": judged,
            "bands": out_bands, "events": events, "rules": rules.rules(),
            "checked": checked, "partial": partial,
            "range": None if span is None else [span[0], span[1]], "param_unit": param_unit}


def _within(sweep, key: str, band: dict):
    """The finite values of the sweep array ``key`` at the points of ``band``'s speed range
    (None where there are none)."""
    if sweep is None or key not in sweep or band.get("from") is None:
        return None
    p = np.asarray(sweep["param"], float)
    v = np.asarray(sweep[key], float)
    lo, hi = band["from"], band.get("to", band["from"])
    v = v[(p >= lo - 1e-9 * abs(lo)) & (p <= hi + 1e-9 * abs(hi)) & np.isfinite(v)]
    return v if v.size else None


def _span_text(v) -> str:
    lo, hi = float(np.min(v)), float(np.max(v))
    return fmt(lo, 2) if fmt(lo, 2) == fmt(hi, 2) else f"{fmt(lo, 2)}-{fmt(hi, 2)}"


def mesh_summary(meshes: list[dict], sweep, iso) -> list[dict]:
    """``findings.meshes``: each mesh's name, role and static force, with what it was
    judged by: a loaded mesh's kv peak (and the ISO 6336-1 resonance speed), an idle
    mesh's loudest and quietest rattle level and the range of its rattle threshold ratio."""
    by_name = {m["name"]: m for m in (iso or {}).get("meshes", [])}
    out = []
    for m in meshes:
        row = dict(m)
        k = _key(m["name"])
        if sweep is not None:
            ok = np.asarray(sweep.get("ok", np.ones(np.asarray(sweep["param"]).size, bool)),
                            bool)
            p = np.asarray(sweep["param"], float)[ok]
            if row.get("static_force_N") is None and f"static_force_{k}" in sweep:
                row["static_force_N"] = float(np.asarray(sweep[f"static_force_{k}"]).ravel()[0])
            kv = sweep.get(f"kv_{k}")
            if m["role"] == "loaded" and kv is not None and p.size:
                v = np.asarray(kv, float)[ok]
                i = int(np.argmax(v))
                row.update(kv_peak=float(v[i]), kv_peak_at=float(p[i]))
            db = sweep.get(f"rattle_db_{k}")
            if m["role"] == "idle" and db is not None and p.size:
                v = np.asarray(db, float)[ok]
                i, j = int(np.argmax(v)), int(np.argmin(v))
                row.update(rattle_db_max=float(v[i]), rattle_db_max_at=float(p[i]),
                           rattle_db_min=float(v[j]), rattle_db_min_at=float(p[j]))
            ratio = sweep.get(f"rattle_threshold_{k}")
            if m["role"] == "idle" and ratio is not None and p.size:
                # the inertia torque to follow the mesh over the drag torque (linear model)
                v = np.asarray(ratio, float)[ok]
                row.update(rattle_threshold_min=float(np.min(v)),
                           rattle_threshold_max=float(np.max(v)))
        if m["name"] in by_name and m["role"] == "loaded":
            row["iso6336"] = by_name[m["name"]]
        out.append(row)
    return out


def _grid(sources) -> np.ndarray:
    """The speeds the run judged (the sweep's, else the map's, the ERP's, the states')."""
    for name, key in (("sweep.npz", "param"), ("map.npz", "rpm"), ("erp.csv", "rpm"),
                      ("states.npz", "attractor_param")):
        arrays = sources.get(name)
        if arrays is not None and np.asarray(arrays.get(key, [])).size:
            return np.unique(np.asarray(arrays[key], float))
    return np.zeros(0)


def _margin_within(band: dict, lo: float, hi: float, sources) -> float:
    """``band``'s margin over its file's points in [lo, hi] (its own margin where the file
    or the metric is not at hand)."""
    from .band_rule import margin_of
    arrays = (sources or {}).get(band.get("source", ""))
    if arrays is None or band["metric"] not in arrays or "param" not in arrays \
            or band["op"] in ("==", "in") or band.get("compare"):
        return float(band.get("margin", 0.0))
    p = np.asarray(arrays["param"], float)
    sel = (p >= max(lo, band["from"])) & (p <= min(hi, band["to"])) & \
        np.asarray(arrays.get("ok", np.ones(p.size, bool)), bool)
    if band["direction"] in ("up", "down") and "direction" in arrays:
        sel &= np.asarray(arrays["direction"], str) == band["direction"]
    if not np.any(sel):
        return float(band.get("margin", 0.0))
    return margin_of(np.asarray(arrays[band["metric"]], float)[sel], band["op"],
                     float(band["threshold"]),
                     "dB" if band.get("margin_unit") == "dB" else "relative")


def windows(bands: list[dict], grid, sources=None) -> list[dict]:
    """``findings.windows``: runs of neighbouring grid speeds where no avoid or caution
    band holds (``status`` "fine"); where there are none, the runs without an avoid band
    (``status`` "caution", ``limits``: the caution bands there, ``margin`` the largest of
    their margins over the window's own points, ``worst``: that band), least severe first.
    Each: from, to (grid speeds), status, limits, margin."""
    grid = np.asarray(grid, float)
    if grid.size == 0:
        return []

    def covered(sev):
        m = np.zeros(grid.size, bool)
        for b in bands:
            if b["severity"] in sev:
                m |= (grid >= b["from"]) & (grid <= b["to"])
        return m

    from .band_rule import segments
    flagged = covered(("avoid", "caution"))
    fine = [{"from": float(grid[a]), "to": float(grid[b]), "status": "fine", "limits": [],
             "margin": 0.0} for a, b in segments(~flagged)]
    if fine:
        return fine
    # no fine speed: the runs without an avoid band, split where the caution bands that
    # hold change, least severe (fewest limits, then smallest margin) first
    def label(x):
        return x["quantity"] if x["where"] in ("gearbox", "system") else \
            f"{x['where']} {x['quantity']}"
    caution = [x for x in bands if x["severity"] == "caution"]
    sets = [tuple(sorted({label(x) for x in caution if x["from"] <= p <= x["to"]}))
            for p in grid]
    out = []
    for a, b in segments(~covered(("avoid",))):
        k = a
        for i in range(a, b + 2):
            if i == b + 1 or sets[i] != sets[k]:
                lo, hi = grid[k], grid[i - 1]
                here = [(x, _margin_within(x, lo, hi, sources)) for x in caution
                        if x["to"] >= lo and x["from"] <= hi and label(x) in sets[k]]
                worst = max(here, key=lambda xm: xm[1], default=None)
                out.append({"from": float(lo), "to": float(hi), "status": "caution",
                            "limits": list(sets[k]),
                            "margin": worst[1] if worst else 0.0,
                            "worst": None if worst is None or worst[1] <= 0 else
                            {"what": label(worst[0]), "margin": worst[1],
                             "margin_unit": worst[0].get("margin_unit", "relative")}})
                k = i
    out.sort(key=lambda w: (len(w["limits"]), w["margin"], -(w["to"] - w["from"])))
    return out


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

