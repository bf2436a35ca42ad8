"""REXS bearings -> ``[[gearbox.bearings]]`` (the external loads, the couplings and the
analysis sections they give: :mod:`.mapping_loads`).

Bearings.  A ``side`` relation names the bearing (``assembly``), the shaft in its inner ring
(``inner_part``) and the shaft or casing in its outer ring (``outer_part``).  A bearing in
a shaft becomes a bearing between two shafts (``outer_shaft``); one in the casing a bearing
to ground.
* ``rolling_bearing_with_catalog_geometry``: its ``catalogue_designation`` when the ISO
  table knows it, else its boundary dimensions (``inner_diameter``, ``outer_diameter``,
  ``width``); the type from ``bearing_type``.  The contact constant then follows from the
  element set (Harris / Palmgren) when the scene is loaded.
* ``rolling_bearing_with_detailed_geometry``: its boundary dimensions.
* ``concept_bearing``: a linear spring bearing with its ``radial_stiffness`` (assumed
  1e9 N/m where the file gives none).
Bearings that take an axial force (``axial_force_absorption`` other than ``no_direction``)
get an axial spring (``axial_stiffness``, assumed 1e8 N/m where none is given).  Exporter
placeholders count as not given: a stiffness of 0, of :data:`PLACEHOLDER_STIFFNESS` (1e20
N/m) or more, or an empty value (listed under "assumed" with the file's value).
"""
from __future__ import annotations

from ..base import ConfigError
from ..model.bearing_catalogue import bearing_kind, boundary_dimensions

__all__ = ["bearings", "CONCEPT_STIFFNESS", "AXIAL_STIFFNESS", "PLACEHOLDER_STIFFNESS"]

#: radial stiffness of a concept bearing that gives none [N/m]
CONCEPT_STIFFNESS = 1e9
#: axial stiffness of a bearing that takes axial force and gives none [N/m]
AXIAL_STIFFNESS = 1e8
#: a stiffness at or above this [N/m] is an exporter's "rigid" placeholder, not a value
PLACEHOLDER_STIFFNESS = 1e20
_BEARING_TYPES = ("rolling_bearing_with_catalog_geometry",
                  "rolling_bearing_with_detailed_geometry", "concept_bearing")


def _side(model, bid):
    rel = next((r for r in model.relations_of("side") if r.ref("assembly") == bid), None)
    if rel is None or rel.ref("inner_part") is None or rel.ref("outer_part") is None:
        raise ConfigError(model.source, f"component {bid} (bearing): no side relation naming "
                          "its inner_part and outer_part")
    return model.components[rel.ref("inner_part")], model.components[rel.ref("outer_part")]


def _stiffness(c, attr: str, src: str):
    """(value [N/m], why it is not taken): the file's stiffness, or None with the reason
    where it is an exporter's placeholder (absent, empty, zero, or 1e20 N/m and above)."""
    if not c.has(attr):
        return None, "the file gives none"
    if not c.given(attr):
        return None, "the file's value is empty"
    k = c.number(attr, src)
    if k == 0.0:
        return None, "the file's 0 N/m is an exporter placeholder"
    if abs(k) >= PLACEHOLDER_STIFFNESS:
        return None, f"the file's {k:.3g} N/m is an exporter placeholder (>= 1e20 N/m: 'rigid')"
    if k < 0.0:
        raise ConfigError(src, f"component {c.id} ({c.type}): attribute {attr!r} = {k:g} N/m "
                          "must be >= 0; fix: give the bearing's stiffness, or leave it out for "
                          "the default")
    return k, None


def bearings(model, shafts, report, errs=None) -> list[dict]:
    from ..base import ErrorList
    errs = ErrorList() if errs is None else errs
    out = []
    for c in model.of_type(*_BEARING_TYPES):
        with errs.catch():
            b = _bearing(model, c, shafts, report)
            if b is not None:
                out.append(b)
    return out


def _bearing(model, c, shafts, report):
    src = model.source
    inner, outer = _side(model, c.id)
    if inner.type != "shaft":
        raise ConfigError(src, f"component {c.id} ({c.type}): its inner_part {inner.id} "
                          f"is a {inner.type!r}, expected a shaft")
    if inner.id not in shafts or (outer.type == "shaft" and outer.id not in shafts):
        return None                     # its shaft's problem is listed
    sh = shafts[inner.id]
    pos = c.number("u_coordinate_on_shaft_inner_side", src) - sh["u0"]
    b = {"name": f"bearing{c.id}", "shaft": inner.id, "position": round(pos, 12)}
    where = "the casing (ground)"
    if outer.type == "shaft":
        b["outer_shaft"] = outer.id
        b["outer_position"] = round(c.number("u_coordinate_on_shaft_outer_side", src)
                                    - shafts[outer.id]["u0"], 12)
        where = f"shaft {outer.id}"
    elif outer.type != "gear_casing":
        raise ConfigError(src, f"component {c.id} ({c.type}): its outer_part {outer.id} is "
                          f"a {outer.type!r}, expected a shaft or the gear_casing")
    if c.type == "concept_bearing":
        k, why = _stiffness(c, "radial_stiffness", src)
        if k is None:
            k = CONCEPT_STIFFNESS
            report.assumed.append(f"concept_bearing {c.id}: radial stiffness "
                                  f"{CONCEPT_STIFFNESS:g} N/m ({why})")
        b.update(type="spring", stiffness=k, damping=200.0)
        what = f"linear spring bearing, {k:.4g} N/m"
    else:
        kind = bearing_kind(c.text("bearing_type", src, "radial_grooved_ball_bearing"))
        if "axial" in c.text("bearing_type", src, "") and "radial" not in \
                c.text("bearing_type", src, ""):
            raise ConfigError(src, f"component {c.id} ({c.type}): bearing_type "
                              f"{c.text('bearing_type', src)!r} (a thrust bearing) is not "
                              "supported: vibrogear's rolling elements are radial")
        desig = c.text("catalogue_designation", src, "")
        try:
            boundary_dimensions(desig) if desig else None
            known = bool(desig)
        except ConfigError:
            known = False
        if known:
            b["designation"] = desig
            what = f"designation {desig!r} (ISO boundary dimensions, element-set rule)"
        elif c.type == "rolling_bearing_with_detailed_geometry" and \
                _detailed(model, c, b, kind, report):
            b["type"] = "ball" if kind == "ball" else "roller"
            what = "the detailed element set (rolling_bearing_row, rolling_element)"
        elif all(c.has(k) for k in ("inner_diameter", "outer_diameter", "width")):
            b.update(bore_diameter=c.number("inner_diameter", src),
                     outer_diameter=c.number("outer_diameter", src),
                     width=c.number("width", src))
            b["type"] = "ball" if kind == "ball" else "roller"
            if kind == "tapered":
                b["contact_angle"] = 12.0
            what = "boundary dimensions (element-set rule)"
            if desig:
                report.assumed.append(f"{c.type} {c.id}: designation {desig!r} is not in "
                                      "the ISO table; its boundary dimensions are used")
        else:
            attr = "catalogue_designation" if c.type.endswith("catalog_geometry") \
                else "inner_diameter"
            raise ConfigError(src, f"component {c.id} ({c.type}): attribute {attr!r}"
                              f"{' = ' + repr(desig) if desig else ''}: the designation is "
                              "not in the built-in ISO 15 / ISO 355 table and the file "
                              "gives no inner_diameter, outer_diameter and width")
        b["damping"] = 200.0
        attr = next((a for a in ("operating_radial_bearing_clearance",
                                 "mounted_radial_bearing_clearance",
                                 "radial_bearing_clearance") if c.has(a)), None)
        if attr is not None:        # the bearing's radial play; the gap per side is half
            b["clearance"] = 0.5 * c.number(attr, src)
            report.mapped.append(f"{c.type} {c.id}: {attr} "
                                 f"{c.number(attr, src) * 1e6:g} um -> clearance (gap per "
                                 f"side) {b['clearance'] * 1e6:g} um")
        else:
            report.assumed.append(f"{c.type} {c.id}: radial clearance 0")
        if c.given("radial_stiffness"):
            k, why = _stiffness(c, "radial_stiffness", src)
            report.ignored.append(f"{c.type} {c.id}: radial_stiffness "
                                  + (f"{k:.4g} N/m" if k is not None else f"not taken ({why})")
                                  + ": the rolling bearing's stiffness follows from its "
                                  "element set and the load")
    locating = c.text("axial_force_absorption", src, "no_direction") != "no_direction"
    if locating:
        ka, why = _stiffness(c, "axial_stiffness", src)
        if ka is None:
            ka = AXIAL_STIFFNESS
            report.assumed.append(f"{c.type} {c.id}: axial stiffness {ka:g} N/m ({why}; "
                                  f"the bearing locates shaft {inner.id} axially: "
                                  f"axial_force_absorption = "
                                  f"{c.text('axial_force_absorption', src)!r})")
        b["axial_stiffness"] = ka
    report.assumed.append(f"{c.type} {c.id}: viscous damping 200 N s/m")
    b["_comment"] = f"REXS {c.type} {c.id} ({c.name}): shaft {inner.id} in {where}"
    report.mapped.append(f"{c.type} {c.id} -> bearing{c.id}: shaft {inner.id} in {where}; "
                         f"{what}")
    return b


def _detailed(model, c, b, kind, report) -> str | None:
    """The element set of a bearing with detailed geometry: its first rolling_bearing_row
    (number_of_rolling_elements, reference diameter, pressure_angle) and that row's
    rolling_element (diameter, length); None where the file has no row."""
    src = model.source
    rows = [model.components[r.ref("part")] for r in model.relations_of("assembly")
            if r.ref("assembly") == c.id and r.ref("part") is not None
            and model.components[r.ref("part")].type == "rolling_bearing_row"]
    if not rows:
        return None
    row = rows[0]
    elems = [model.components[r.ref("part")] for r in model.relations_of("assembly")
             if r.ref("assembly") in (row.id, c.id) and r.ref("part") is not None
             and model.components[r.ref("part")].type == "rolling_element"]
    dm_attr = next((a for a in ("reference_diameter", "reference_diameter_rolling_bearing")
                    if row.has(a)), "reference_diameter")
    b["elements"] = int(round(row.number("number_of_rolling_elements", src)))
    b["pitch_diameter"] = row.number(dm_attr, src)
    if row.has("pressure_angle") and row.number("pressure_angle", src):
        b["contact_angle"] = row.number("pressure_angle", src)
    if elems:
        b["element_diameter"] = elems[0].number("diameter_of_rolling_element", src)
        if kind != "ball" and elems[0].has("length_of_rolling_element"):
            b["element_length"] = elems[0].number("length_of_rolling_element", src)
    report.mapped.append(f"rolling_bearing_row {row.id} -> the element set of {c.type} {c.id}")
    return "the detailed element set (rolling_bearing_row, rolling_element)"
