"""A generated box housing for an imported gearbox (``vibrogear import --housing box``).

The parametric housing of ``[housing]`` is a box with a front and a back wall and, where the
casing bearings need them, inner walls (``inner_walls``), each shaft axis bored through every
wall (coaxial shafts share one axis).  The box is sized from the model:

* the walls: the casing bearings' planes along the shafts.  The first bearing plane is the
  front wall's middle, the last the back wall's; the bearings between are grouped from the
  front, a bearing within one wall thickness (:data:`WALL`) of a group's first bearing joining
  it, and each group gets an inner wall in the middle of its bearings' span (so each sits
  within half a wall of its plane).  Width = back - front + one wall.  An inner wall that
  would cut a gear's face or leave less than one wall of cavity to its neighbour exits 2
  naming the bearings that need it;
* length and height: the shaft axes' extent plus, on each side, the largest gear tip radius
  (pitch radius + module), one wall and :data:`CLEARANCE`;
* each bore axis: radius = half the outside diameter of its front bearing (from its
  designation or boundary dimensions; else 1.8 x the shaft radius there) in every wall, boss
  radius 1.5 x the bore, boss length one wall; in each wall one coupling point per rolling
  element of the bearing that wall carries (``wall_rolling_elements`` where the walls'
  bearings differ), the axis's first counted bearing's count (or 8) in a wall without one.
Every sized value is reported as assumed.
"""
from __future__ import annotations

import math

from ..base import ConfigError
from ..model.bearing_catalogue import boundary_dimensions, element_set
from ..model.housing_walls import MIN_GAP_WALLS

__all__ = ["box_housing", "box_frame", "casing_bearing_ys", "outer_diameter_and_count", "seat_diameter",
           "shafts_into_housing_frame", "STEEL", "WALL", "CLEARANCE"]

#: wall thickness of the generated box [m]
WALL = 0.02
#: radial clearance between a gear tip and the wall [m]
CLEARANCE = 0.01


def outer_diameter_and_count(b) -> tuple[float | None, int | None]:
    if b.get("designation"):
        bd = boundary_dimensions(b["designation"])
        es = element_set(bd.kind, bd.d, bd.D, bd.B)
        return bd.D, es.count
    if b.get("outer_diameter"):
        kind = "ball" if b.get("type") == "ball" else "cylindrical"
        es = element_set(kind, b["bore_diameter"], b["outer_diameter"], b["width"])
        return b["outer_diameter"], es.count
    return None, None


#: the generated housings' material (steel) and stiffness-proportional damping
STEEL = {"E": 2.1e11, "nu": 0.3, "rho": 7850.0, "beta": 1e-6}


def seat_diameter(b, shaft: dict) -> tuple[float, int | None, bool]:
    """(outside diameter of bearing ``b`` [m], its element count or None, whether the
    diameter was assumed): the designation's or boundary dimensions' D, else 1.8 x the
    shaft's largest section diameter (a bore radius 1.8 x the shaft radius)."""
    D, n = outer_diameter_and_count(b) if b is not None else (None, None)
    if D is not None:
        return D, n, False
    return 1.8 * max(sec["outer_diameter"] for sec in shaft["sections"]), n, True


def shafts_into_housing_frame(gb: dict, casing, axis_of, front: float) -> None:
    """The shafts of ``gb`` onto their housing bores (in place): ``bore`` = ``axis_of`` their
    (x, z), x and z dropped (the bores carry them), y0 shifted so that the first casing
    bearing's plane lies at half a wall; the casing bearings' element counts dropped (the
    housing's coupling points carry them)."""
    for s in gb["shafts"]:
        s["bore"] = axis_of(s)
        s.pop("x")
        s.pop("z")
        s["y0"] = round(s["y0"] - front + 0.5 * WALL, 12)
    for b in casing:
        b.pop("elements", None)


def box_housing(model, data: dict, report) -> None:
    """Add a parametric ``[housing]`` to the imported scene ``data`` (in place): bores per
    shaft axis, shafts moved onto them; ConfigError naming a casing bearing off the walls."""
    gb = data["gearbox"]
    shafts = {s["name"]: s for s in gb["shafts"]}
    casing, ys = casing_bearing_ys(model, gb, "--housing box")
    front, back = min(ys.values()), max(ys.values())
    walls = _inner_walls(model, gb, shafts, casing, ys, front, back)
    width = back - front + WALL
    margin = box_frame(gb)[0]
    xs = [s["x"] for s in gb["shafts"]]
    zs = [s["z"] for s in gb["shafts"]]
    axes: dict[tuple[float, float], str] = {}
    bores = []
    keys = {s["name"]: (round(s["x"], 9), round(s["z"], 9)) for s in gb["shafts"]}
    for s in gb["shafts"]:
        key = keys[s["name"]]
        if key not in axes:
            axes[key] = f"axis{len(axes) + 1}"
            mine = sorted((b for b in casing if keys[b["shaft"]] == key),
                          key=lambda b: ys[b["name"]])
            D, n, assumed = seat_diameter(mine[0] if mine else None, s)
            if assumed:
                report.assumed.append(f"housing bore {axes[key]!r}: radius {0.5 * D:.4g} m "
                                      "(1.8 x the shaft's largest radius)")
            counts = _wall_counts(mine, ys, [front] + [y for y, _ in walls] + [back])
            default = n or next((c for c in counts if c), 8)
            bores.append({"name": axes[key], "x": round(s["x"] - min(xs) + margin, 9),
                          "z": round(s["z"] - min(zs) + margin, 9),
                          "bore_radius": round(0.5 * D, 9), "boss_radius": round(0.75 * D, 9),
                          "boss_length": WALL, "rolling_elements": default})
            if len({c or default for c in counts}) > 1:
                bores[-1]["wall_rolling_elements"] = [c or default for c in counts]
    shafts_into_housing_frame(gb, casing, lambda s: axes[keys[s["name"]]], front)
    data["housing"] = {
        "length": round(max(xs) - min(xs) + 2 * margin, 9), "width": round(width, 9),
        "height": round(max(zs) - min(zs) + 2 * margin, 9), "wall_thickness": WALL,
        **({"inner_walls": [round(y - front + 0.5 * WALL, 9) for y, _ in walls]} if walls else {}),
        "base": "plate", "support": "fixed", "bores": bores,
        "material": dict(STEEL), "modes": {"count": 20, "shapes": 0}}
    report.assumed.append(
        f"gear_casing: a generated steel box {data['housing']['length']:.4g} x "
        f"{width:.4g} x {data['housing']['height']:.4g} m (walls {WALL:g} m, gear tips "
        f"{CLEARANCE:g} m from the walls), bores at the {len(bores)} shaft axes, base plate "
        "clamped, 20 housing modes; each axis's bore radius = half its front bearing's outside "
        "diameter in every wall; each wall's bore has one coupling point per rolling element of "
        "the bearing it carries (wall_rolling_elements where they differ), the axis's first "
        "counted bearing's elements (or 8) where it carries none")
    for k, (y, names) in enumerate(walls):
        ids = ", ".join(n.removeprefix("bearing") for n in names)
        report.assumed.append(
            f"gear_casing: inner wall {k + 1} at y = {y - front + 0.5 * WALL:.4g} m "
            f"(housing.inner_walls[{k}], {WALL:g} m thick, the box's full height and length, "
            f"bored at every shaft axis) for the casing bearing{'s' if ',' in ids else ''} "
            f"{ids} between the front and the back wall")


def casing_bearing_ys(model, gb, flag: str) -> tuple[list, dict]:
    """(the casing bearings of the imported ``gearbox`` data, {name: y in the model frame});
    ConfigError naming ``flag`` where no bearing sits in the casing."""
    shafts = {s["name"]: s for s in gb["shafts"]}
    casing = [b for b in gb["bearings"] if not b.get("outer_shaft")]
    if not casing:
        raise ConfigError(model.source, f"{flag}: no bearing sits in the gear_casing")
    return casing, {b["name"]: shafts[b["shaft"]]["y0"] + b["position"] for b in casing}


def box_frame(gb) -> tuple[float, float, float, float]:
    """(margin, x0, z0, y_front) of the generated box's housing frame for the imported
    ``gearbox`` data in the model frame: housing x = x - x0 + margin, z = z - z0 + margin,
    y = y - y_front + WALL / 2, where x0, z0 are the smallest shaft-axis coordinates, margin
    the largest gear tip radius + one wall + CLEARANCE and y_front the first casing
    bearing's plane (the front wall's middle)."""
    tip = max((0.5 * g["module"] * g["teeth"] / math.cos(math.radians(g["helix_angle"]))
               + g["module"] for g in gb["gears"]), default=0.0)
    shafts = {s["name"]: s for s in gb["shafts"]}
    casing = [b for b in gb["bearings"] if not b.get("outer_shaft")]
    y_front = min(shafts[b["shaft"]]["y0"] + b["position"] for b in casing)
    return (tip + WALL + CLEARANCE, min(s["x"] for s in gb["shafts"]),
            min(s["z"] for s in gb["shafts"]), y_front)


def _wall_counts(mine, ys, planes) -> list[int | None]:
    """The rolling-element count of the bearing in each wall plane (None: no counted bearing
    there), each bearing in the plane nearest to it."""
    counts: list[int | None] = [None] * len(planes)
    for b in mine:
        j = min(range(len(planes)), key=lambda k: abs(ys[b["name"]] - planes[k]))
        counts[j] = counts[j] or outer_diameter_and_count(b)[1]
    return counts


def _inner_walls(model, gb, shafts, casing, ys, front, back) -> list[tuple[float, list[str]]]:
    """(middle plane y in the model frame, names of its bearings) of each inner wall: the
    casing bearings more than one wall from the front and back planes, grouped from the front
    (a bearing within :data:`WALL` of its group's first bearing joins it), each wall in the
    middle of its group's span.  ConfigError where a wall cuts a gear face or crowds a
    neighbouring wall (less than one wall of cavity between)."""
    inner = sorted((ys[b["name"]], b["name"]) for b in casing
                   if min(abs(ys[b["name"]] - front), abs(ys[b["name"]] - back)) > WALL)
    groups: list[list[tuple[float, str]]] = []
    for y, name in inner:
        if groups and y - groups[-1][0][0] <= WALL:
            groups[-1].append((y, name))
        else:
            groups.append([(y, name)])
    walls = [(0.5 * (g[0][0] + g[-1][0]), [n for _, n in g]) for g in groups]

    def wall_of(ns):
        return "the inner wall for bearing component(s) " + ", ".join(n.removeprefix("bearing") for n in ns)

    planes = ([(front, "the front wall", False)] + [(y, wall_of(ns), True) for y, ns in walls]
              + [(back, "the back wall", False)])
    gap = MIN_GAP_WALLS * WALL
    for lo, hi in zip(planes, planes[1:]):
        room = hi[0] - lo[0] - WALL
        if room < gap - 1e-12:
            (y, what, _), other = (lo, hi[1]) if lo[2] else (hi, lo[1])
            raise ConfigError(model.source, f"--housing box: {what} ({(y - front) * 1e3:.4g} mm "
                              f"from the front bearings' plane, {WALL * 1e3:g} mm thick) would "
                              f"leave {room * 1e3:.3g} mm of cavity to {other}; at least "
                              f"{gap * 1e3:.3g} mm (one wall) is needed: import without --housing "
                              "(bearings to rigid ground)")
    for y, names in walls:
        cut = [f"gear {g['name'].removeprefix('gear')} ({(yg - front) * 1e3:.4g} mm, "
               f"{g['width'] * 1e3:.4g} mm wide)" for g in gb["gears"]
               for yg in [shafts[g["shaft"]]["y0"] + g["position"]]
               if abs(yg - y) < 0.5 * (g["width"] + WALL)]
        if cut:
            raise ConfigError(model.source, f"--housing box: {wall_of(names)} ({(y - front) * 1e3:.4g} "
                              f"mm from the front bearings' plane, {WALL * 1e3:g} mm thick) would cut the face of "
                              f"{' and '.join(cut)}: import without --housing (bearings to rigid "
                              "ground)")
    return walls
