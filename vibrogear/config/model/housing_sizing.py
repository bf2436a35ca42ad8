"""The parametric housing sized for you: what a gearbox scene's ``[housing]`` leaves out is
filled from the gearbox before the scene is built (the keys it gives are kept).

* **bores**: one per bore name the shafts use (``gearbox.shafts[].bore``), in the order of
  first use.  A bore without ``x``/``z``: the first at the corner margin, each next one
  from its mesh partner's bore at the pair's centre distance along x (m_n (z_a + z_b) /
  (2 cos beta), the working distance for profile-shifted pairs), at the same height.
  ``bore_radius``: half the outside diameter of its first bearing (designation or
  ``outer_diameter``), else 1.8 x the journal radius; ``boss_radius`` 1.5 x the bore;
  ``rolling_elements`` the bearing's element count (its element-set rule) or 8.
* **wall_thickness**: :data:`WALL`.
* **length / height**: the bores' extent plus, each side, the largest gear tip radius
  (pitch radius + module), one wall and :data:`CLEARANCE`; the bores move so that the
  smallest x and z sit that far in.
* **width**: the back bearings' housing y plus half a wall (their bore's middle), at least
  the front bearings' y plus one wall.
* **wall_rolling_elements** (only with ``inner_walls`` given): where the bearings of one
  bore axis sit in walls (front, inner, back: the nearest wall plane) with different element
  counts (``elements``, designation or boundary dimensions), one count per wall, the bore's
  ``rolling_elements`` for a wall without such a bearing.
"""
from __future__ import annotations

import math

from .bearing_catalogue import boundary_dimensions, element_set

__all__ = ["fill_housing", "WALL", "CLEARANCE"]

#: wall thickness of a sized housing [m]
WALL = 0.015
#: radial room between a gear tip and a wall [m]
CLEARANCE = 0.005


def _num(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _tip(g) -> float:
    beta = math.radians(g.get("helix_angle", 0.0) if _num(g.get("helix_angle", 0.0)) else 0.0)
    return 0.5 * g["module"] * g["teeth"] / math.cos(beta) + g["module"]


def _centre(ga, gb, mesh) -> float:
    from .layout import working_centre_distance
    from types import SimpleNamespace as NS
    a = NS(helix_angle=ga.get("helix_angle", 0.0), module=ga["module"], teeth=ga["teeth"])
    b = NS(teeth=gb["teeth"])
    m = NS(profile_shift_a=mesh.get("profile_shift_a", 0.0),
           profile_shift_b=mesh.get("profile_shift_b", 0.0),
           pressure_angle=mesh.get("pressure_angle", 20.0))
    return working_centre_distance(a, b, m)


def _bearing_size(b) -> tuple[float | None, int | None]:
    try:
        if isinstance(b.get("designation"), str) and b["designation"]:
            bd = boundary_dimensions(b["designation"])
            return bd.D, element_set(bd.kind, bd.d, bd.D, bd.B).count
        if all(_num(b.get(k)) for k in ("bore_diameter", "outer_diameter", "width")):
            kind = "ball" if b.get("type", "ball") == "ball" else "cylindrical"
            es = element_set(kind, b["bore_diameter"], b["outer_diameter"], b["width"])
            return b["outer_diameter"], es.count
    except Exception:             # a bad bearing is reported by its own check
        pass
    return None, None


def fill_housing(data: dict) -> None:
    """Fill the missing sizes of a parametric ``[housing]`` of a gearbox scene (in place).
    Anything malformed is left as it is, for the scene's own checks to report."""
    h, gb = data.get("housing"), data.get("gearbox")
    if not isinstance(h, dict) or not isinstance(gb, dict) or \
            h.get("source", "parametric") != "parametric":
        return
    try:
        _fill(h, gb)
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError):
        return


def _fill(h: dict, gb: dict) -> None:
    shafts = [s for s in gb.get("shafts", []) if isinstance(s, dict)]
    gears = {g["name"]: g for g in gb.get("gears", []) if isinstance(g, dict)}
    t = h.get("wall_thickness") if _num(h.get("wall_thickness")) else WALL
    h.setdefault("wall_thickness", t)
    names = list(dict.fromkeys(s["bore"] for s in shafts if isinstance(s.get("bore"), str)
                               and s["bore"]))
    if "bores" not in h:            # one per bore name the shafts use
        h["bores"] = [{"name": n} for n in names]
    given = {b.get("name"): b for b in h["bores"] if isinstance(b, dict)}
    if any(n not in given for n in names):
        return                        # a shaft names a bore [housing] lacks: its check says so
    shaft_bore = {s["name"]: s.get("bore") for s in shafts}
    for n in names:
        b = given[n]
        mine = [x for x in gb.get("bearings", []) if isinstance(x, dict)
                and shaft_bore.get(x.get("shaft")) == n and not x.get("outer_shaft")]
        D, count = _bearing_size(mine[0]) if mine else (None, None)
        if "bore_radius" not in b:
            if D is None:
                sh = next(s for s in shafts if s.get("bore") == n)
                D = 1.8 * max(sec["outer_diameter"] for sec in sh["sections"])
            b["bore_radius"] = round(0.5 * D, 9)
        b.setdefault("boss_radius", round(1.5 * b["bore_radius"], 9))
        b.setdefault("rolling_elements", count or 8)
    # positions from the centre distances (bores without x / z)
    pos = {n: (given[n]["x"], given[n]["z"]) for n in names
           if _num(given[n].get("x")) and _num(given[n].get("z"))}
    tip = max((_tip(g) for g in gears.values()), default=0.0)
    margin = tip + t + CLEARANCE
    if names and not pos:
        pos[names[0]] = (0.0, 0.0)
    changed = True
    while changed and len(pos) < len(names):
        changed = False
        for m in gb.get("meshes", []):
            ga, gbb = gears.get(m.get("gear_a")), gears.get(m.get("gear_b"))
            if ga is None or gbb is None:
                continue
            na, nb = shaft_bore.get(ga["shaft"]), shaft_bore.get(gbb["shaft"])
            for here, there in ((na, nb), (nb, na)):
                if here in pos and there in given and there not in pos:
                    x, z = pos[here]
                    pos[there] = (x + _centre(ga, gbb, m), z)
                    changed = True
    if len(pos) < len(names):
        return
    lo_x, lo_z = min(p[0] for p in pos.values()), min(p[1] for p in pos.values())
    hi_x, hi_z = max(p[0] for p in pos.values()), max(p[1] for p in pos.values())
    auto = not all(_num(given[n].get("x")) and _num(given[n].get("z")) for n in names)
    for n in names:
        if auto and not (_num(given[n].get("x")) and _num(given[n].get("z"))):
            given[n]["x"] = round(pos[n][0] - lo_x + margin, 9)
            given[n]["z"] = round(pos[n][1] - lo_z + margin, 9)
    xs = [given[n]["x"] for n in names]
    zs = [given[n]["z"] for n in names]
    h.setdefault("length", round(max(xs) + margin, 9))
    h.setdefault("height", round(max(zs) + margin, 9))
    ys = [s.get("y0", 0.0) + b["position"] for b in gb.get("bearings", [])
          if isinstance(b, dict) and not b.get("outer_shaft") for s in shafts
          if s["name"] == b.get("shaft") and _num(s.get("y0", 0.0)) and _num(b.get("position"))]
    if ys:
        h.setdefault("width", round(max(max(ys) + 0.5 * t, min(ys) + 2 * t), 9))
    _fill_wall_counts(h, gb, shafts, names, given, t)


def _fill_wall_counts(h: dict, gb: dict, shafts: list, names: list, given: dict, t: float) -> None:
    walls = h.get("inner_walls")
    if not (isinstance(walls, list) and walls and all(_num(y) for y in walls) and _num(h.get("width"))):
        return
    planes = [0.5 * t] + list(walls) + [h["width"] - 0.5 * t]
    y0 = {s["name"]: s.get("y0", 0.0) for s in shafts}
    bore_of = {s["name"]: s.get("bore") for s in shafts}
    for n in names:
        b = given[n]
        if "wall_rolling_elements" in b or not isinstance(b.get("rolling_elements"), int):
            continue
        counts: list[int | None] = [None] * len(planes)
        for x in gb.get("bearings", []):
            if not isinstance(x, dict) or x.get("outer_shaft") or bore_of.get(x.get("shaft")) != n \
                    or not _num(x.get("position")) or not _num(y0.get(x["shaft"])):
                continue
            y = y0[x["shaft"]] + x["position"]
            j = min(range(len(planes)), key=lambda k: abs(y - planes[k]))
            count = x["elements"] if isinstance(x.get("elements"), int) else _bearing_size(x)[1]
            counts[j] = counts[j] or count
        per = [c or b["rolling_elements"] for c in counts]
        if len(set(per)) > 1:
            b["wall_rolling_elements"] = per
