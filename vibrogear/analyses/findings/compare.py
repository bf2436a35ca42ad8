"""Two runs' findings side by side (``vibrogear compare RUN_A RUN_B``): the engineer's next
step after a design change.

:func:`compare_findings` is a pure function of the two ``summary.json`` ``findings``
records.  A band of A and a band of B are the *same* band when they name the same kind
(``quantity``), place (``where``), severity and sweep direction and their speed ranges
overlap; such a pair is ``moved`` when its edges differ by more than the larger grid step
of the two (their ``edge_err``), else ``kept``.  Bands of B without a partner in A are
``added``, bands of A without one in B ``removed``.  Per mesh: the role, the kv peak (loaded)
and the loudest / quietest rattle level (idle) of each run, and their change.
"""
from __future__ import annotations

import json
from pathlib import Path

__all__ = ["compare_findings", "read_findings"]


def read_findings(run: str | Path) -> dict:
    """``findings`` of the run folder ``run`` (its summary.json); ValueError naming the file
    where it has none."""
    path = Path(run) / "summary.json"
    if not path.is_file():
        raise ValueError(f"{path}: no such file (a run folder holds summary.json)")
    try:
        summary = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: not readable as JSON ({exc})") from None
    findings = summary.get("findings") if isinstance(summary, dict) else None
    if not isinstance(findings, dict) or "bands" not in findings:
        raise ValueError(f"{path}: no findings (run a sweep, map, run-up or states first)")
    return {**findings, "scene": summary.get("scene", {}).get("name")
            if isinstance(summary.get("scene"), dict) else summary.get("scene"),
            "folder": str(Path(run))}


def _key(b: dict) -> tuple:
    return (b["quantity"], b["where"], b["severity"], b["direction"])


def _overlap(a: dict, b: dict) -> bool:
    return a["from"] <= b["to"] and b["from"] <= a["to"]


def compare_findings(a: dict, b: dict) -> dict:
    """{"bands": {"added", "removed", "moved", "kept"}, "meshes": [...], "verdicts": [A, B],
    "windows": [A's, B's], "runs": [A folder, B folder]} (module docstring)."""
    used: set[int] = set()
    moved, kept, removed = [], [], []
    bb = [x for x in b.get("bands", []) if x["severity"] != "fine"]
    for x in (x for x in a.get("bands", []) if x["severity"] != "fine"):
        match = next((j for j, y in enumerate(bb) if j not in used and _key(y) == _key(x)
                      and _overlap(x, y)), None)
        if match is None:
            removed.append(x)
            continue
        used.add(match)
        y = bb[match]
        tol = max(float(x.get("edge_err", 0.0)), float(y.get("edge_err", 0.0)))
        pair = {"a": x, "b": y, "from_change": y["from"] - x["from"],
                "to_change": y["to"] - x["to"],
                "margin_change": float(y.get("margin", 0.0)) - float(x.get("margin", 0.0))}
        (moved if abs(pair["from_change"]) > tol or abs(pair["to_change"]) > tol
         else kept).append(pair)
    added = [y for j, y in enumerate(bb) if j not in used]
    meshes = []
    ma = {m["name"]: m for m in a.get("meshes", []) or []}
    mb = {m["name"]: m for m in b.get("meshes", []) or []}
    for name in list(ma) + [n for n in mb if n not in ma]:
        x, y = ma.get(name, {}), mb.get(name, {})
        row = {"name": name, "role": [x.get("role"), y.get("role")]}
        for k in ("kv_peak", "kv_peak_at", "rattle_db_max", "rattle_db_max_at",
                  "rattle_db_min", "rattle_db_min_at", "static_force_N"):
            if k in x or k in y:
                row[k] = [x.get(k), y.get(k)]
        iso = [(x.get("iso6336") or {}).get("n_E1_rpm"), (y.get("iso6336") or {}).get("n_E1_rpm")]
        if any(v is not None for v in iso):
            row["n_E1_rpm"] = iso
        meshes.append(row)
    return {"runs": [a.get("folder"), b.get("folder")], "scenes": [a.get("scene"), b.get("scene")],
            "param_unit": b.get("param_unit", a.get("param_unit", "rpm")),
            "verdicts": [a.get("verdict", ""), b.get("verdict", "")],
            "windows": [a.get("windows", []), b.get("windows", [])],
            "ranges": [a.get("range"), b.get("range")],
            "bands": {"added": added, "removed": removed, "moved": moved, "kept": kept},
            "meshes": meshes}
