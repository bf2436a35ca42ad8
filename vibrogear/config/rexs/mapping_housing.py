"""A generated box housing for an imported gearbox (``vibrogear import --housing box``).

The parametric housing of ``[housing]`` is a box with a front and a back wall, one bore pair
per shaft axis (coaxial shafts share one).  The box is sized from the model:

* the walls: the bearings in the casing must sit in two planes along the shafts (front and
  back, each bearing within one wall thickness of its plane; a bearing elsewhere exits 2
  naming it, since the box has no middle wall);  the wall thickness is
  :data:`WALL`; width = back - front + one wall, so each plane is a wall's middle;
* length and height: the shaft axes' extent plus, on each side, the largest gear tip radius
  (pitch radius + module), one wall and :data:`CLEARANCE`;
* each bore: radius = half the outside diameter of its front bearing (from its designation
  or boundary dimensions; else 1.8 x the shaft radius there), boss radius 1.5 x the bore,
  boss length one wall, one coupling point per rolling element of its front bearing.
Every sized value is reported as assumed.
"""
from __future__ import annotations

import math

from ..base import ConfigError
from ..bearing_catalogue import boundary_dimensions, element_set

__all__ = ["box_housing", "WALL", "CLEARANCE"]

#: wall thickness of the generated box [m]
WALL = 0.02
#: radial clearance between a gear tip and the wall [m]
CLEARANCE = 0.01


def _outer_diameter_and_count(b) -> tuple[float | None, int | None]:
    if b.get("designation"):
        bd = boundary_dimensions(b["designation"])
        es = element_set(bd.kind, bd.d, bd.D, bd.B)
        return bd.D, es.count
    if b.get("outer_diameter"):
        kind = "ball" if b.get("type") == "ball" else "cylindrical"
        es = element_set(kind, b["bore_diameter"], b["outer_diameter"], b["width"])
        return b["outer_diameter"], es.count
    return None, None


def box_housing(model, data: dict, report) -> None:
    """Add a parametric ``[housing]`` to the imported scene ``data`` (in place): bores per
    shaft axis, shafts moved onto them; ConfigError naming a casing bearing off the walls."""
    gb = data["gearbox"]
    shafts = {s["name"]: s for s in gb["shafts"]}
    casing = [b for b in gb["bearings"] if not b.get("outer_shaft")]
    if not casing:
        raise ConfigError(model.source, "--housing box: no bearing sits in the gear_casing")
    ys = {b["name"]: shafts[b["shaft"]]["y0"] + b["position"] for b in casing}
    front, back = min(ys.values()), max(ys.values())
    for b in casing:
        y = ys[b["name"]]
        if min(abs(y - front), abs(y - back)) > WALL:
            cid = b["name"].removeprefix("bearing")
            raise ConfigError(model.source, f"--housing box: bearing component {cid} sits at "
                              f"{(y - front) * 1e3:.4g} mm from the front wall, between the "
                              f"walls (front at 0, back at {(back - front) * 1e3:.4g} mm): the "
                              "generated box has only a front and a back wall; import without "
                              "--housing (bearings to rigid ground) or give a STEP housing")
    width = back - front + WALL
    tip = max(0.5 * g["module"] * g["teeth"] / math.cos(math.radians(g["helix_angle"]))
              + g["module"] for g in gb["gears"])
    margin = tip + WALL + CLEARANCE
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
            D, n = _outer_diameter_and_count(mine[0]) if mine else (None, None)
            if D is None:
                D = 1.8 * max(sec["outer_diameter"] for sec in s["sections"])
                report.assumed.append(f"housing bore {axes[key]!r}: radius {0.5 * D:.4g} m "
                                      "(1.8 x the shaft's largest radius)")
            bores.append({"name": axes[key], "x": round(s["x"] - min(xs) + margin, 9),
                          "z": round(s["z"] - min(zs) + margin, 9),
                          "bore_radius": round(0.5 * D, 9), "boss_radius": round(0.75 * D, 9),
                          "boss_length": WALL, "rolling_elements": n or 8})
        s["bore"] = axes[key]
        s.pop("x")
        s.pop("z")
        s["y0"] = round(s["y0"] - front + 0.5 * WALL, 12)
    for b in casing:
        b.pop("elements", None)
    data["housing"] = {
        "length": round(max(xs) - min(xs) + 2 * margin, 9), "width": round(width, 9),
        "height": round(max(zs) - min(zs) + 2 * margin, 9), "wall_thickness": WALL,
        "base": "plate", "support": "fixed", "bores": bores,
        "material": {"E": 2.1e11, "nu": 0.3, "rho": 7850.0, "beta": 1e-6},
        "modes": {"count": 20, "shapes": 0}}
    report.assumed.append(
        f"gear_casing: a generated steel box {data['housing']['length']:.4g} x "
        f"{width:.4g} x {data['housing']['height']:.4g} m (walls {WALL:g} m, gear tips "
        f"{CLEARANCE:g} m from the walls), bores at the {len(bores)} shaft axes, base plate "
        "clamped, 20 housing modes; each bore's coupling points = its front bearing's "
        "rolling elements")
