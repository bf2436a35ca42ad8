"""The load path's short tables in report.html (summary.json ``load_path``,
:mod:`vibrogear.models.gearbox.load_path`)."""
from __future__ import annotations

import math

from .html_parts import esc, fmt, table

__all__ = ["load_path_html"]


def _diff(value, nominal) -> str:
    if value is None or not nominal:
        return "-"
    return f"{100.0 * (value - nominal) / nominal:+.3g} %"


def _num(v, digits: int = 4) -> str:
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else fmt(v, digits)


def load_path_html(lp: dict | None) -> list[str]:
    """The section: couplings and shafts, meshes, bearings, and what the scene assumed."""
    if not lp:
        return []
    rpm = lp.get("reference_rpm")
    at = "" if rpm is None else f" (powers at {fmt(rpm, 4)} rpm of the driving shaft)"
    parts = ['<h2 id="load_path">The static load path</h2>',
             f"<p>The static state of the elastic model against the nominal torque balance "
             f"(input torque x stage ratios; idle gears carry none){esc(at)}.</p>"]
    rows = [(f"coupling {c['name']} ({c['role']}, {c['given']})", _num(c["torque_Nm"]),
             _num(c["nominal_torque_Nm"]), _diff(c["torque_Nm"], c["nominal_torque_Nm"]),
             _num(c.get("power_kW"))) for c in lp.get("couplings", [])]
    rows += [(f"shaft {s['name']}", _num(s["torque_Nm"]), _num(s["nominal_torque_Nm"]),
              _diff(s["torque_Nm"], s["nominal_torque_Nm"]), _num(s.get("power_kW")))
             for s in lp.get("shafts", [])]
    parts.append(table(["", "torque [N m]", "nominal [N m]", "difference", "power [kW]"], rows))
    rows = [(m["name"], m["role"], _num(m["normal_force_N"]), _num(m["tangential_force_N"]),
             _num(m["nominal_normal_force_N"]),
             _diff(m["normal_force_N"], m["nominal_normal_force_N"]),
             _num(m["torque_ratio"]), _num(m["power_kW"])) for m in lp.get("meshes", [])]
    parts.append(table(["mesh", "role", "normal force [N]", "tangential force [N]",
                        "nominal normal force [N]", "difference", "torque ratio",
                        "power [kW]"], rows))
    rows = [(b["name"], b["shaft"], _num(b["radial_N"]), _num(b["axial_N"]))
            for b in lp.get("bearings", [])]
    if rows:
        parts.append(table(["bearing", "shaft", "radial reaction [N]", "axial reaction [N]"],
                           rows))
    assumed = lp.get("assumed") or []
    if assumed:
        parts.append("<p>What the scene assumed (the answer rests on these):</p><ul>")
        parts += [f"<li>{esc(a['where'])}: {esc(a['what'])}</li>" for a in assumed]
        parts.append("</ul>")
    parts += [f"<p>{esc(n)}</p>" for n in lp.get("notes") or []]
    return parts
