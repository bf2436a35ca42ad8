"""REXS external loads and load spectrum -> ``[[gearbox.couplings]]`` and the analysis
sections (``[time_response]``, ``[sweep]``, ``[map]``); the bearings are mapped in
:mod:`.mapping_supports`.

Loads.  An ``external_load`` that ``transmits_torque`` becomes a torsional coupling at its
position: the one on the driving shaft the motor, the others loads.  Its torque is the
``torque_around_u_axis`` (else ``power`` / omega) of the load case used: the one named
(``--load-case N``), else the one with the largest duration share
(``load_duration_fraction``, REXS 1.6 ``operating_time_fraction``); without a load spectrum
the components' own attributes (the loads' torque or power, the speed-defining shaft's
``rotational_speed``).  A load without a torque takes the input torque times its shaft's
speed reduction (lossless).  Forces of external loads are not mapped (reported).
"""
from __future__ import annotations

import math

from ..base import ConfigError

__all__ = ["loads", "analysis_sections", "choose_load_case", "duration_shares",
           "COUPLING_TWIST"]

#: twist [rad] the assumed coupling stiffness gives at the load case's torque
COUPLING_TWIST = 0.02

_FRACTIONS = ("load_duration_fraction", "operating_time_fraction")   # 1.0-1.5; 1.6 on
_CASE_ATTRS = ("rotational_speed", "torque_around_u_axis", "power")


def _case_value(model, case, cid, attr, where=""):
    """``attr`` of component ``cid`` in a load case, in SI units through the unit table
    (speeds rpm, torques N m, power W); None where absent or empty."""
    from .reader import Component
    v = case.get(cid, {}).get(attr)
    if v is None:
        return None
    comp = model.components[cid]
    one = Component(cid, comp.type, comp.name, {attr: v})
    if not one.given(attr):
        return None
    try:
        return one.number(attr, model.source)
    except ConfigError as exc:
        raise ConfigError(exc.path, f"{where}{exc.message}") from None


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


def duration_shares(model) -> list:
    """Each load case's duration share [%] (``load_duration_fraction``, in REXS 1.6 on
    ``operating_time_fraction``, on the gear unit or any component of the case); None where
    the case gives none."""
    out = []
    for k, case in enumerate(model.load_cases):
        units = [c.id for c in model.of_type("gear_unit")]
        ids = units + [cid for cid in case if cid not in units]
        out.append(next((v for cid in ids for a in _FRACTIONS
                         if (v := _case_value(model, case, cid, a,
                                              f"load case {k + 1}: ")) is not None), None))
    return out


def choose_load_case(model, load_case: int | None = None) -> tuple[int, str]:
    """(index of the load case taken, why): the one named (1-based ``load_case``), else the one
    with the largest duration share (the first of equal ones), else the first."""
    n = len(model.load_cases)
    if load_case is not None:
        if not 1 <= load_case <= n:
            raise ConfigError("--load-case", f"must be 1 to {n} (the file's load cases), got "
                              f"{load_case}" if n else "the file has no load spectrum: "
                              "leave --load-case out")
        return load_case - 1, "named with --load-case"
    shares = duration_shares(model)
    if all(f is None for f in shares):
        return 0, "the first: the file gives no duration shares"
    k = max(range(n), key=lambda i: (shares[i] if shares[i] is not None else -1.0, -i))
    return k, f"the largest duration share, {shares[k]:g} %"


def _static_case(model) -> dict:
    """The operating point a file without a load spectrum gives on its components (the
    shafts' rotational_speed, the external loads' torque_around_u_axis or power)."""
    case = {}
    for c in model.of_type("shaft", "external_load"):
        for attr in _CASE_ATTRS:
            if c.given(attr):
                case.setdefault(c.id, {})[attr] = c.attributes[attr]
    return case


def loads(model, shafts, gears, stages, order, report, load_case: int | None = None):
    """(couplings, the load case used, as {"index", "rpm", "torque", "speeds", "torques"}).
    Every problem is collected and raised together (each naming the component, the attribute
    and the fix)."""
    from ..base import ErrorList
    src = model.source
    errs = ErrorList()
    _owner = type(model).owner
    ratios = _speed_ratios(shafts, gears, stages, order)
    first = order[0]
    if model.load_cases:
        k, how = choose_load_case(model, load_case)
        cases = list(model.load_cases)
        label = f"load case {k + 1}"
    else:
        if load_case is not None:
            raise ConfigError("--load-case", "the file has no load spectrum: leave --load-case "
                              "out (the operating point is the external loads' torque and the "
                              "speed-defining shaft's speed)")
        k, how, cases, label = 0, "no load spectrum", [_static_case(model)], "the model"
    case = cases[k]
    speed_shaft = next((sid for sid in order if shafts[sid]["comp"].flag("defines_speed")),
                       first)

    def driving_rpm(c, where):
        for sid in [speed_shaft] + [s for s in order if s != speed_shaft]:
            v = _case_value(model, c, sid, "rotational_speed", where)
            if v is not None and sid in ratios:
                return abs(v / ratios[sid])
        return None
    rpm = None
    with errs.catch():
        rpm = driving_rpm(case, f"{label}: ")
        if rpm is None:
            raise ConfigError(src, f"{label}, component {speed_shaft} (shaft): missing "
                              "attribute 'rotational_speed'; fix: give the speed-defining shaft "
                              + ("its speed in the load case" if model.load_cases else
                                 "its rotational_speed (the file has no load spectrum)"))
    ext = [c for c in model.of_type("external_load") if c.flag("transmits_torque")]

    def torque_of(c, cid, sid, shaft_rpm, where):
        t = _case_value(model, c, cid, "torque_around_u_axis", where)
        if t is None or t == 0.0:
            p = _case_value(model, c, cid, "power", where)
            if p is not None and p != 0.0 and shaft_rpm:
                return abs(p) / (shaft_rpm * math.pi / 30.0), "power"
        return (abs(t), "torque") if t is not None else (None, None)

    definer = next((c for c in ext if c.flag("defines_torque")), None) or next(
        (c for c in ext if any(case.get(c.id, {}).get(a) for a in _CASE_ATTRS[1:])), None)
    t_in, d_shaft = None, None
    with errs.catch():
        if definer is None:
            raise ConfigError(src, "no external_load transmits a torque (transmits_torque = true "
                              "with defines_torque = true, or a torque_around_u_axis or power); "
                              "fix: give the input or output load its torque")
        owner = _owner(model, definer.id, "shaft")
        if owner is None or owner.id not in ratios:
            raise ConfigError(src, f"component {definer.id} (external_load) is not part of a "
                              "driven shaft; fix: an assembly relation with its shaft")
        d_shaft = owner.id
        t, kind = torque_of(case, definer.id, d_shaft,
                            rpm * abs(ratios[d_shaft]) if rpm else None, f"{label}: ")
        if t is None:
            raise ConfigError(src, f"{label}, component {definer.id} (external_load): missing "
                              "attribute 'torque_around_u_axis' (or 'power'); fix: give the "
                              "load's torque or power" + ("" if model.load_cases else
                                                          " on the component (the file has no "
                                                          "load spectrum)"))
        t_in = t * abs(ratios[d_shaft])             # torque at the driving shaft, lossless
        if kind == "power":
            report.mapped.append(f"external_load {definer.id}: its power "
                                 f"{_case_value(model, case, definer.id, 'power') / 1e3:.6g} kW "
                                 f"at {rpm * abs(ratios[d_shaft]):.6g} rpm -> torque {t:.6g} N m")
    errs.raise_if()
    couplings = []
    for c in ext:
        with errs.catch():
            owner = _owner(model, c.id, "shaft")
            if owner is None or owner.id not in ratios:
                raise ConfigError(src, f"component {c.id} (external_load) is not part of a "
                                  "driven shaft; fix: an assembly relation with its shaft")
            sid = owner.id
            own, _ = torque_of(case, c.id, sid, rpm * abs(ratios[sid]), f"{label}: ")
            torque = own or t_in / abs(ratios[sid])
            role = "motor" if sid == first else "load"
            stiffness = float(f"{torque / COUPLING_TWIST:.4g}")
            couplings.append({
                "name": f"{role}{c.id}", "shaft": sid,
                "position": round(c.number("u_coordinate_on_shaft", src) - shafts[sid]["u0"],
                                  12),
                "role": role, "stiffness": stiffness, "torque": float(f"{torque:.10g}"),
                "damping": float(f"{2e-4 * stiffness:.3g}"),
                "_comment": f"REXS external_load {c.id} ({c.name}), {label}"})
            report.mapped.append(f"external_load {c.id} -> coupling '{role}{c.id}' ({role}) on "
                                 f"shaft {sid}: torque {torque:.6g} N m"
                                 + ("" if own else " (input torque x speed reduction, "
                                    "lossless)"))
            report.assumed.append(f"external_load {c.id}: torsional stiffness {stiffness:g} N m/"
                                  f"rad (twist {COUPLING_TWIST:g} rad at its torque), damping "
                                  f"{2e-4 * stiffness:.3g} N m s/rad")
    errs.raise_if()
    for c in model.of_type("external_load"):
        if not c.flag("transmits_torque"):
            report.ignored.append(f"external_load {c.id}: forces and bending moments are not "
                                  "mapped (the scene's static load is the torque)")
    speeds, torques = [], []
    for j, c in enumerate(cases):
        where = f"load case {j + 1}: "
        n = driving_rpm(c, where)
        speeds.append(n)
        t, _ = torque_of(c, definer.id, d_shaft, n * abs(ratios[d_shaft]) if n else None, where)
        torques.append((t or 0.0) * abs(ratios[d_shaft]))
    if model.load_cases:
        report.mapped.append(f"load case {k + 1} of {len(cases)} ({how}) -> the operating "
                             f"point: {rpm:g} rpm, {t_in:.6g} N m at the driving shaft"
                             + ("; the other load cases span the map's speed and load axes"
                                if len(cases) > 1 else ""))
        if how.startswith("the first"):
            report.assumed.append(f"load spectrum: load case 1 of {len(cases)} ({how})")
    else:
        report.mapped.append(f"no load spectrum: the operating point from the components' own "
                             f"attributes (shaft {speed_shaft} rotational_speed, external_load "
                             f"{definer.id} torque): {rpm:g} rpm, {t_in:.6g} N m at the driving "
                             "shaft")
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
