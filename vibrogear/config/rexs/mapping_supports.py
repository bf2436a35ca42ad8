"""REXS bearings and loads -> ``[[gearbox.bearings]]``, ``[[gearbox.couplings]]`` and the
analysis sections (``[time_response]``, ``[sweep]``, ``[map]``) from the load spectrum.

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
get an axial spring (``axial_stiffness``, assumed 1e8 N/m where none is given).

Loads.  An ``external_load`` that ``transmits_torque`` becomes a torsional coupling at its
position: the one on the driving shaft the motor, the others loads.  Its torque is the
``torque_around_u_axis`` of the load case used (the one with the largest
``load_duration_fraction``); a load without one takes the input torque times its shaft's
speed reduction (lossless).  Forces of external loads are not mapped (reported).
"""
from __future__ import annotations

from ..base import ConfigError
from ..bearing_catalogue import bearing_kind, boundary_dimensions

__all__ = ["bearings", "loads", "analysis_sections", "COUPLING_TWIST", "CONCEPT_STIFFNESS",
           "AXIAL_STIFFNESS"]

#: twist [rad] the assumed coupling stiffness gives at the load case's torque
COUPLING_TWIST = 0.02
#: radial stiffness of a concept bearing that gives none [N/m]
CONCEPT_STIFFNESS = 1e9
#: axial stiffness of a bearing that takes axial force and gives none [N/m]
AXIAL_STIFFNESS = 1e8
_BEARING_TYPES = ("rolling_bearing_with_catalog_geometry",
                  "rolling_bearing_with_detailed_geometry", "concept_bearing")


def _side(model, bid):
    rel = next((r for r in model.relations_of("side") if r.ref("assembly") == bid), None)
    if rel is None or rel.ref("inner_part") is None or rel.ref("outer_part") is None:
        raise ConfigError(model.source, f"component {bid} (bearing): no side relation naming "
                          "its inner_part and outer_part")
    return model.components[rel.ref("inner_part")], model.components[rel.ref("outer_part")]


def bearings(model, shafts, report) -> list[dict]:
    src = model.source
    out = []
    for c in model.of_type(*_BEARING_TYPES):
        inner, outer = _side(model, c.id)
        if inner.type != "shaft":
            raise ConfigError(src, f"component {c.id} ({c.type}): its inner_part {inner.id} "
                              f"is a {inner.type!r}, expected a shaft")
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
            k = c.number("radial_stiffness", src) if c.has("radial_stiffness") else None
            if k is None:
                k = CONCEPT_STIFFNESS
                report.assumed.append(f"concept_bearing {c.id}: radial stiffness "
                                      f"{CONCEPT_STIFFNESS:g} N/m (the file gives none)")
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
        if c.text("axial_force_absorption", src, "no_direction") != "no_direction":
            ka = c.number("axial_stiffness", src) if c.has("axial_stiffness") else AXIAL_STIFFNESS
            b["axial_stiffness"] = ka
            if not c.has("axial_stiffness"):
                report.assumed.append(f"{c.type} {c.id}: axial stiffness {ka:g} N/m")
        report.assumed.append(f"{c.type} {c.id}: viscous damping 200 N s/m")
        b["_comment"] = f"REXS {c.type} {c.id} ({c.name}): shaft {inner.id} in {where}"
        report.mapped.append(f"{c.type} {c.id} -> bearing{c.id}: shaft {inner.id} in {where}; "
                             f"{what}")
        out.append(b)
    return out


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


def _case_value(case, cid, attr):
    v = case.get(cid, {}).get(attr)
    if v is None:
        return None
    from .reader import UNIT_FACTORS
    return float(v[0]) * UNIT_FACTORS.get(v[1], 1.0)


def _speed_ratios(shafts, gears, stages, order) -> dict:
    p = {order[0]: 1.0}
    changed = True
    while changed:
        changed = False
        for _, g1, g2 in stages:
            for a, b in ((g1, g2), (g2, g1)):
                sa, sb = gears[a]["shaft"], gears[b]["shaft"]
                if sa in p and sb not in p:
                    p[sb] = -p[sa] * gears[a]["teeth"] / gears[b]["teeth"]
                    changed = True
    return p


def _load_case(model) -> int:
    """Index of the load case with the largest load_duration_fraction (the first on a tie)."""
    units = [c.id for c in model.of_type("gear_unit")]
    best, frac = 0, -1.0
    for k, case in enumerate(model.load_cases):
        f = next((_case_value(case, u, "load_duration_fraction") for u in units
                  if _case_value(case, u, "load_duration_fraction") is not None), 0.0)
        if f > frac:
            best, frac = k, f
    return best


def loads(model, shafts, gears, stages, order, report):
    """(couplings, the load case used, as {"index", "rpm", "torque", "speeds", "torques"})."""
    src = model.source
    _owner = type(model).owner
    if not model.load_cases:
        raise ConfigError(src, "the model has no load case (load_spectrum/load_case): the "
                          "speed and torque come from it")
    k = _load_case(model)
    case = model.load_cases[k]
    first = order[0]
    ratios = _speed_ratios(shafts, gears, stages, order)
    speed_shaft = next((sid for sid in order if shafts[sid]["comp"].flag("defines_speed")), first)

    def driving_rpm(c):
        v = _case_value(c, speed_shaft, "rotational_speed")
        return None if v is None else abs(v / ratios[speed_shaft])
    rpm = driving_rpm(case)
    if rpm is None:
        raise ConfigError(src, f"load case {k + 1}, component {speed_shaft} (shaft): missing "
                          "attribute 'rotational_speed'")
    ext = [c for c in model.of_type("external_load") if c.flag("transmits_torque")]
    definer = next((c for c in ext if c.flag("defines_torque")), None)
    if definer is None:
        raise ConfigError(src, "no external_load with defines_torque = true: the torque of the "
                          "load case sets the load")
    t_def = _case_value(case, definer.id, "torque_around_u_axis")
    if t_def is None:
        raise ConfigError(src, f"load case {k + 1}, component {definer.id} (external_load): "
                          "missing attribute 'torque_around_u_axis'")
    d_shaft = _owner(model, definer.id, "shaft").id
    t_in = abs(t_def) * abs(ratios[d_shaft])        # torque at the driving shaft, lossless
    couplings = []
    for c in ext:
        owner = _owner(model, c.id, "shaft")
        if owner is None:
            raise ConfigError(src, f"component {c.id} (external_load) is not part of a shaft")
        sid = owner.id
        torque = abs(_case_value(case, c.id, "torque_around_u_axis") or 0.0) or \
            t_in / abs(ratios[sid])
        role = "motor" if sid == first else "load"
        stiffness = float(f"{torque / COUPLING_TWIST:.4g}")
        couplings.append({
            "name": f"{role}{c.id}", "shaft": sid,
            "position": round(c.number("u_coordinate_on_shaft", src) - shafts[sid]["u0"], 12),
            "role": role, "stiffness": stiffness, "torque": float(f"{torque:.10g}"),
            "damping": float(f"{2e-4 * stiffness:.3g}"),
            "_comment": f"REXS external_load {c.id} ({c.name}), load case {k + 1}"})
        report.mapped.append(f"external_load {c.id} -> coupling '{role}{c.id}' ({role}) on "
                             f"shaft {sid}: torque {torque:.6g} N m"
                             + ("" if c.flag("defines_torque") else
                                " (input torque x speed reduction, lossless)"))
        report.assumed.append(f"external_load {c.id}: torsional stiffness {stiffness:g} N m/rad "
                              f"(twist {COUPLING_TWIST:g} rad at its torque), damping "
                              f"{2e-4 * stiffness:.3g} N m s/rad")
    for c in model.of_type("external_load"):
        if not c.flag("transmits_torque"):
            report.ignored.append(f"external_load {c.id}: forces and bending moments are not "
                                  "mapped (the scene's static load is the torque)")
    speeds = [driving_rpm(c) for c in model.load_cases]
    torques = [abs(_case_value(c, definer.id, "torque_around_u_axis") or 0.0)
               * abs(ratios[d_shaft]) for c in model.load_cases]
    report.mapped.append(f"load case {k + 1} of {len(model.load_cases)} (largest "
                         f"load_duration_fraction) -> the operating point: {rpm:g} rpm, "
                         f"{t_in:.6g} N m at the driving shaft")
    return couplings, {"index": k, "rpm": rpm, "torque": t_in,
                       "speeds": [s for s in speeds if s], "torques": torques}


def analysis_sections(model, case, couplings) -> dict:
    lo, hi = min(case["speeds"]), max(case["speeds"])
    if hi <= lo:
        lo, hi = 0.5 * case["rpm"], 1.5 * case["rpm"]
    out = {"time_response": {"rpm": float(f"{case['rpm']:.6g}"), "periods": 100,
                             "samples_per_period": 32},
           "sweep": {"rpm_min": float(f"{lo:.6g}"), "rpm_max": float(f"{hi:.6g}"),
                     "n_points": 41, "transient_periods": 150, "record_periods": 32}}
    t = [x for x in case["torques"] if x > 0]
    if len(set(t)) >= 2:
        out["map"] = {"rpm_min": float(f"{lo:.6g}"), "rpm_max": float(f"{hi:.6g}"),
                      "n_speeds": 21, "n_loads": len(set(t)),
                      "torque_min": float(f"{min(t):.6g}"), "torque_max": float(f"{max(t):.6g}")}
    return out
