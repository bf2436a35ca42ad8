"""An imported scene as TOML text a person can read and edit: the mapping report as the
header, one comment per shaft, gear, mesh, bearing and coupling naming the REXS component
it came from."""
from __future__ import annotations

import json
import math

__all__ = ["scene_toml", "toml_value"]


def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"no TOML for {v}")
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(f"no TOML for {type(v).__name__}")


def _scalars(table: dict) -> list[str]:
    return [f"{k} = {toml_value(v)}" for k, v in table.items()
            if not isinstance(v, dict) and not (isinstance(v, list) and v
                                                and isinstance(v[0], dict))]


def scene_toml(imp, command: str = "") -> str:
    """The TOML text of a :class:`~vibrogear.config.rexs.RexsImport`."""
    src = imp.model
    lines = [f"# Scene imported from {src.source} (REXS {src.version}"
             f"{', ' + src.application if src.application else ''})",
             *([f"# by: {command}"] if command else []),
             "# Units: SI (m, kg, s, N, Pa); angles in degrees; speeds in rpm.",
             "# Mapping report (every REXS component: mapped, assumed with its value, or ignored):"]
    lines += [f"#   {line}" for line in imp.report.lines()]
    lines.append("")
    data = imp.data
    for name in ("scene",):
        lines += [f"[{name}]", *_scalars(data[name]), ""]
    gb = data["gearbox"]
    lines += ["[gearbox]", *_scalars(gb), ""]
    for group in ("shafts", "gears", "meshes", "bearings", "couplings"):
        for k, item in enumerate(gb.get(group, [])):
            comment = imp.comments.get((group, k))
            if comment:
                lines.append(f"# {comment}")
            lines += [f"[[gearbox.{group}]]", *_scalars(item)]
            if group == "shafts":
                lines += ["[gearbox.shafts.material]", *_scalars(item["material"])]
                for s in item["sections"]:
                    lines += ["[[gearbox.shafts.sections]]", *_scalars(s)]
                for d in item.get("discs", []):
                    lines += ["[[gearbox.shafts.discs]]", *_scalars(d)]
            lines.append("")
    for name, table in data.items():
        if name not in ("scene", "gearbox"):
            _table(name, table, lines, array=False)
    return "\n".join(lines)


def _table(name: str, table: dict, lines: list, array: bool) -> None:
    lines += [f"[[{name}]]" if array else f"[{name}]", *_scalars(table)]
    for k, v in table.items():
        if isinstance(v, dict):
            _table(f"{name}.{k}", v, lines, array=False)
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for item in v:
                _table(f"{name}.{k}", item, lines, array=True)
    if not array:
        lines.append("")
