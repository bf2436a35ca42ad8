"""The casing of an imported gearbox from a CAD solid (``vibrogear import MODEL.rexs
--housing CASING.step --fixed-region ...``): a ``source = "step"`` housing with one bore per
casing bearing.

Frame.  The STEP solid is taken in the housing frame that ``--housing box`` uses
(:func:`~.mapping_housing.box_frame`): y along the shafts with y = 0.01 m (half the box's
0.02 m wall) at the first casing bearing's plane; x and z across, with the lowest shaft axis
at x (resp. z) = the largest gear tip radius + 0.03 m (one box wall and the 0.01 m tip
clearance).  A casing exported from CAD in another frame must be moved into this one first.

Bores.  Each casing bearing (bearings within :data:`~.mapping_housing.WALL` of each other on
one shaft axis share one) gets a ``[[housing.bores]]`` line: centre = the bearing's point on
its shaft axis, axis = +y, ``bore_radius`` = half the bearing's outside diameter (designation
or boundary dimensions; else 0.9 x the shaft's largest diameter, the box's rule),
``rolling_elements`` = its element count (else 8), ``length`` = :data:`SEAT_WIDTHS` bearing
widths (a bearing without a width: :data:`DEFAULT_WIDTH`), at most the distance to the next
casing bearing on that axis, so that only that seat's faces are taken.  The bores of one axis
are named ``<axis>/front``, ``<axis>/inner1`` .., ``<axis>/back`` (front to back; one bearing:
``<axis>/front``), the shafts on it carry ``bore = "<axis>"``.

Mesh.  ``mesh.size`` = :data:`SIZE_PER_BORE_RADIUS` x the smallest bore radius (the bore
rings then have ~25 elements around at bore_size = size / 2), degree 2.
"""
from __future__ import annotations

import math

from ..base import ConfigError
from .mapping_housing import (STEEL, WALL, box_frame, casing_bearing_ys, seat_diameter,
                              shafts_into_housing_frame)

__all__ = ["step_housing", "set_mesh_size", "parse_fixed_region", "SEAT_WIDTHS", "DEFAULT_WIDTH",
           "SIZE_PER_BORE_RADIUS", "FIXED_REGION_HELP"]

#: length of the face search window about a bearing's plane, in bearing widths
SEAT_WIDTHS = 4.0
#: width assumed for a bearing that gives none (a concept bearing) [m]
DEFAULT_WIDTH = 0.02
#: global element size of the STEP housing per smallest bore radius
SIZE_PER_BORE_RADIUS = 0.5
FIXED_REGION_HELP = ("--fixed-region XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX: the box (in the housing "
                     "frame, in --length-unit) around the clamped faces of the casing, e.g. the "
                     "undersides of its feet; every boundary face wholly inside it is clamped")


def parse_fixed_region(text: str | None, unit: float) -> dict:
    """``{"min": [..], "max": [..]}`` in metres from the flag's text; ConfigError naming the
    flag on anything but six finite numbers with min <= max."""
    if text is None:
        raise ConfigError("--fixed-region", "missing: a STEP casing needs the clamped region, "
                          + FIXED_REGION_HELP)
    parts = [p.strip() for p in text.split(",")]
    try:
        v = [float(p) for p in parts]
    except ValueError:
        v = []
    if len(v) != 6 or not all(math.isfinite(x) for x in v):
        raise ConfigError("--fixed-region", f"expected six comma-separated numbers, got {text!r}; "
                          + FIXED_REGION_HELP)
    for k, axis in enumerate("xyz"):
        if v[k] > v[k + 3]:
            raise ConfigError("--fixed-region", f"{axis.upper()}MIN = {v[k]:g} exceeds "
                              f"{axis.upper()}MAX = {v[k + 3]:g}; " + FIXED_REGION_HELP)
    return {"min": [round(x * unit, 12) for x in v[:3]], "max": [round(x * unit, 12) for x in v[3:]]}


def _width(b) -> float | None:
    if b.get("designation"):
        from ..model.bearing_catalogue import boundary_dimensions
        return boundary_dimensions(b["designation"]).B
    return b.get("width")


def step_housing(model, data: dict, report, file: str, fixed_region: dict) -> None:
    """Add a ``source = "step"`` ``[housing]`` to the imported scene ``data`` (in place): the
    shafts moved into the box frame, one bore per casing bearing (group)."""
    gb = data["gearbox"]
    casing, ys = casing_bearing_ys(model, gb, "--housing STEP")
    margin, x0, z0, front = box_frame(gb)
    shafts = {s["name"]: s for s in gb["shafts"]}
    keys = {s["name"]: (round(s["x"], 9), round(s["z"], 9)) for s in gb["shafts"]}
    axes: dict[tuple[float, float], str] = {}
    where: dict[tuple[float, float], tuple[float, float]] = {}
    for s in gb["shafts"]:
        axes.setdefault(keys[s["name"]], f"axis{len(axes) + 1}")
        where.setdefault(keys[s["name"]], (round(s["x"] - x0 + margin, 9),
                                           round(s["z"] - z0 + margin, 9)))
    bores, lines = [], []
    for key, axis in axes.items():
        mine = sorted((b for b in casing if keys[b["shaft"]] == key), key=lambda b: ys[b["name"]])
        if not mine:
            names = ", ".join(s for s in shafts if keys[s] == key)
            raise ConfigError(model.source, f"--housing STEP: shaft(s) {names} sit in no casing "
                              "bearing, so no bore of the casing carries their axis")
        groups: list[list[dict]] = []
        for b in mine:
            if groups and ys[b["name"]] - ys[groups[-1][0]["name"]] <= WALL:
                groups[-1].append(b)
            else:
                groups.append([b])
        planes = [sum(ys[b["name"]] for b in g) / len(g) for g in groups]
        for k, g in enumerate(groups):
            b = g[0]
            side = ("front" if k == 0 else "back" if k == len(groups) - 1 else f"inner{k}")
            D, n, assumed = seat_diameter(b, shafts[b["shaft"]])
            how_r = ("0.9 x the shaft's largest diameter (no outside diameter given)" if assumed
                     else "half the outside diameter")
            B = _width(b)
            how_l = f"{SEAT_WIDTHS:g} x the bearing width"
            if B is None:
                B, how_l = DEFAULT_WIDTH, (f"{SEAT_WIDTHS:g} x {DEFAULT_WIDTH * 1e3:g} mm (no "
                                           "bearing width given)")
            length = SEAT_WIDTHS * B
            gaps = [abs(planes[k] - planes[j]) for j in (k - 1, k + 1) if 0 <= j < len(planes)]
            if gaps and min(gaps) < length:
                length, how_l = min(gaps), "the distance to the next casing bearing on the axis"
            y = planes[k] - front + 0.5 * WALL
            x, z = where[key]
            bores.append({"name": f"{axis}/{side}", "center": [x, round(y, 9), z],
                          "axis": [0.0, 1.0, 0.0], "bore_radius": round(0.5 * D, 9),
                          "length": round(length, 9), "rolling_elements": n or 8})
            ids = ", ".join(x["name"].removeprefix("bearing") for x in g)
            lines.append(f"housing bore '{axis}/{side}' (bearing {ids}): centre ({x:.4g}, {y:.4g}, "
                         f"{z:.4g}) m, radius {0.5 * D * 1e3:.4g} mm ({how_r}), faces searched "
                         f"within +-{0.5 * length * 1e3:.4g} mm along the axis ({how_l}), "
                         f"{n or 8} coupling points ("
                         + ("the bearing's rolling elements)" if n else "assumed: no element count)"))
    shafts_into_housing_frame(gb, casing, lambda s: axes[keys[s["name"]]], front)
    data["housing"] = {
        "source": "step", "file": file, "fixed_region": fixed_region, "support": "fixed",
        "bores": bores, "material": dict(STEEL),
        "mesh": {"size": 0.0, "degree": 2}, "modes": {"count": 20, "shapes": 0}}
    report.assumed.append(
        f"gear_casing: the STEP solid {file} in the housing frame of `--housing box` (y along "
        f"the shafts, y = {0.5 * WALL:g} m at the first casing bearing's plane; the smallest "
        f"shaft-axis x and z at {margin:.4g} m, the largest gear tip radius + 0.03 m); "
        "a casing exported in another frame must be moved there first; steel, clamped on the "
        f"faces inside fixed_region = {fixed_region['min']} .. {fixed_region['max']} m, 20 "
        "housing modes")
    report.assumed += [f"gear_casing: {line}" for line in lines]
    set_mesh_size(data, report)


def set_mesh_size(data: dict, report) -> None:
    """``[housing.mesh] size`` = :data:`SIZE_PER_BORE_RADIUS` x the smallest bore radius, and
    its report line (replaced where the bore radii changed since)."""
    r = min(b["bore_radius"] for b in data["housing"]["bores"])
    size = round(SIZE_PER_BORE_RADIUS * r, 6)
    data["housing"]["mesh"]["size"] = size
    report.assumed[:] = [a for a in report.assumed if not a.startswith(_MESH_LINE)]
    report.assumed.append(f"{_MESH_LINE}size {size:g} m ({SIZE_PER_BORE_RADIUS:g} x the "
                          f"smallest bore radius, {r * 1e3:.4g} mm), bore faces at size / 2")


_MESH_LINE = "gear_casing: tetrahedral P2 mesh, "
