"""REXS shafts and cylindrical gears -> scene data: the frame, the sections and material of
each shaft, the data of each gear (frames as in :mod:`.mapping`)."""
from __future__ import annotations

import math

from ..base import ConfigError

__all__ = ["Frame", "shafts_of", "gear_data", "diameter_at", "axial_reference", "pitch_diameter",
           "STEEL"]

#: the material assumed where a shaft references none [Pa, -, kg/m^3]
STEEL = {"E": 2.1e11, "nu": 0.3, "rho": 7850.0}


class Frame:
    """The housing frame of the module docstring, from the shafts' axes."""

    def __init__(self, axis):
        n = math.sqrt(sum(c * c for c in axis))
        self.a = tuple(c / n for c in axis)
        ref = (0.0, 0.0, 1.0) if abs(self.a[2]) < 0.9 else (1.0, 0.0, 0.0)
        d = sum(r * a for r, a in zip(ref, self.a))
        ex = tuple(r - d * a for r, a in zip(ref, self.a))
        m = math.sqrt(sum(c * c for c in ex))
        self.ex = tuple(c / m for c in ex)
        a, e = self.a, self.ex
        self.ez = (e[1] * a[2] - e[2] * a[1], e[2] * a[0] - e[0] * a[2], e[0] * a[1] - e[1] * a[0])

    def along(self, p) -> float:
        return sum(x * y for x, y in zip(p, self.a))

    def xz(self, p) -> tuple[float, float]:
        return (round(sum(x * y for x, y in zip(p, self.ex)), 9),
                round(sum(x * y for x, y in zip(p, self.ez)), 9))


def shafts_of(model, report, errs=None):
    """(frame, {shaft id: its data}); with ``errs`` (an ErrorList) a shaft with a problem
    is recorded there and left out, and the others are mapped."""
    from ..base import ErrorList
    errs = ErrorList() if errs is None else errs
    src = model.source
    shafts = model.of_type("shaft")
    if not shafts:
        raise ConfigError(src, "the model has no component of type 'shaft'")
    axis = shafts[0].vector("u_axis_vector", src)
    frame = Frame(axis)
    out = {}
    for sh in shafts:
        with errs.catch():
            a = sh.vector("u_axis_vector", src)
            n = math.sqrt(sum(c * c for c in a))
            dot = sum(x * y for x, y in zip(a, frame.a)) / max(n, 1e-300)
            if dot < 1.0 - 1e-9:
                raise ConfigError(src, f"component {sh.id} (shaft): attribute 'u_axis_vector' "
                                  f"{list(a)} is not parallel to shaft {shafts[0].id}'s "
                                  f"{list(axis)} pointing the same way: vibrogear's shafts are "
                                  "parallel")
            secs = sorted([model.components[r.ref("part")] for r in model.relations_of("assembly")
                           if r.ref("assembly") == sh.id and r.ref("part") is not None
                           and model.components[r.ref("part")].type == "shaft_section"],
                          key=lambda c: c.number("u_coordinate_on_shaft", src))
            if not secs:
                raise ConfigError(src, f"component {sh.id} (shaft) has no shaft_section parts")
            rows, u = [], secs[0].number("u_coordinate_on_shaft", src)
            u0 = u
            for c in secs:
                start = c.number("u_coordinate_on_shaft", src)
                if abs(start - u) > 1e-6:
                    raise ConfigError(src, f"component {c.id} (shaft_section): attribute "
                                      f"'u_coordinate_on_shaft' = {start * 1e3:g} mm leaves a gap "
                                      f"or overlap at {u * 1e3:g} mm on shaft {sh.id}")
                do = [c.number(k, src) for k in ("outer_diameter_begin", "outer_diameter_end")]
                di = [c.number(k, src, 0.0) for k in ("inner_diameter_begin", "inner_diameter_end")]
                if do[0] != do[1] or di[0] != di[1]:
                    report.assumed.append(f"shaft_section {c.id}: conical, taken as a cylinder of "
                                          f"the mean diameters {0.5 * sum(do) * 1e3:g} / "
                                          f"{0.5 * sum(di) * 1e3:g} mm")
                length = c.number("length", src)
                rows.append({"length": round(length, 12),
                             "outer_diameter": round(0.5 * sum(do), 12),
                             "inner_diameter": round(0.5 * sum(di), 12)})
                u = start + length
            S = sh.vector("support_vector", src)
            start_y = frame.along(S) + u0
            mats = [model.components[r.ref("referenced")] for r in model.relations_of("reference")
                    if r.ref("origin") == sh.id and r.ref("referenced") is not None
                    and model.components[r.ref("referenced")].type == "material"]
            if mats:
                m = mats[0]
                mat = {"E": m.number("elastic_modulus", src), "nu": m.number("poisson_ratio", src),
                       "rho": m.number("density", src)}
                report.mapped.append(f"material {m.id} ({m.name}) -> material of shaft {sh.id}: "
                                     f"E = {mat['E']:.4g} Pa, nu = {mat['nu']:g}, "
                                     f"rho = {mat['rho']:g} kg/m^3")
            else:
                mat = dict(STEEL)
                report.assumed.append(f"shaft {sh.id}: no material referenced; steel E = 2.1e11 "
                                      "Pa, nu = 0.3, rho = 7850 kg/m^3")
            x, z = frame.xz(S)
            out[sh.id] = {"comp": sh, "sections": rows, "u0": u0, "start_y": start_y, "x": x,
                          "z": z, "material": mat, "length": u - u0, "features": set()}
    if not out:
        errs.raise_if()
    y_ref = min(s["start_y"] for s in out.values())
    for s in out.values():
        s["y0"] = round(s["start_y"] - y_ref, 12)
    return frame, out


def gear_data(model, g, src, report):
    teeth = int(round(g.number("number_of_teeth", src)))
    mn = g.number("normal_module", src)
    attr = "helix_angle_reference_diameter" if g.has("helix_angle_reference_diameter") \
        else "helix_angle"
    beta = g.number(attr, src)
    flanks = [model.components[r.ref("left")] for r in model.relations_of("flank")
              if r.ref("gear") == g.id and r.ref("left") is not None]
    holder = flanks[0] if flanks else g
    if holder.has("normal_pressure_angle"):
        alpha = holder.number("normal_pressure_angle", src)
    else:
        alpha = 20.0
        report.assumed.append(f"cylindrical_gear {g.id}: normal pressure angle 20 deg")
    shift_attr = next((a for a in ("addendum_modification_coefficient",
                                   "profile_shift_coefficient") if holder.has(a)), None)
    shift = holder.number(shift_attr, src) if shift_attr else 0.0
    if shift_attr is None:
        report.assumed.append(f"cylindrical_gear {g.id}: profile shift 0")
    bore = g.number("inner_diameter", src) if g.has("inner_diameter") else None
    return {"teeth": teeth, "module": mn, "beta": beta, "alpha": alpha, "shift": shift,
            "bore": bore,
            "width": g.number("face_width", src), "u": g.number("u_coordinate_on_shaft", src)}


def diameter_at(shaft, pos) -> float:
    start = 0.0
    for s in shaft["sections"]:
        if pos <= start + s["length"] + 1e-9:
            return s["outer_diameter"]
        start += s["length"]
    return shaft["sections"][-1]["outer_diameter"]


def pitch_diameter(d) -> float:
    return d["module"] * d["teeth"] / math.cos(math.radians(d["beta"]))


def _seat(shaft, lo, hi) -> float | None:
    """The shaft's outer diameter under the face [lo, hi] (m from the shaft's start) where it
    is one diameter; None where the face leaves the shaft or spans a step."""
    if lo < -1e-9 or hi > shaft["length"] + 1e-9:
        return None
    start, ds = 0.0, set()
    for sec in shaft["sections"]:
        end = start + sec["length"]
        if end > lo + 1e-9 and start < hi - 1e-9:
            ds.add(sec["outer_diameter"])
        start = end
    return ds.pop() if len(ds) == 1 else None


def _fits(shaft, centre, d) -> bool:
    """The gear's face, centred at ``centre``, sits on one seat of its shaft, thinner than its
    pitch circle (a hub on a seat, or a pinion cut on its shaft)."""
    seat = _seat(shaft, centre - 0.5 * d["width"], centre + 0.5 * d["width"])
    return seat is not None and seat < pitch_diameter(d)


def axial_reference(gears, shafts, report) -> None:
    """Each gear's ``pos`` (its face centre on its shaft, m from the shaft's start) from its
    REXS ``u_coordinate_on_shaft``.

    REXS 1.0-2.0 document ``u_coordinate_on_shaft`` as the gear's position on the shaft and
    the reference exporters (Bearinx, the FVA models) write the centre of the face; some
    exporters write the start of the face (the face then runs from u to u + b).  The schemas
    carry no attribute that says which, so the file's gears decide: read as centres, every
    face must sit on one seat of its shaft (within the shaft, one outer diameter, thinner than
    the pitch circle).  Where that fails for any gear and reading every position as the start
    of its face seats them all, the whole file is read so (one exporter, one convention);
    otherwise each gear that fits only as face-start is read so.  Each face-start reading is
    listed under "assumed" with both values."""
    centre = {gid: d["u"] - shafts[d["shaft"]]["u0"] for gid, d in gears.items()}
    start = {gid: c + 0.5 * gears[gid]["width"] for gid, c in centre.items()}
    ok_c = {gid: _fits(shafts[d["shaft"]], centre[gid], d) for gid, d in gears.items()}
    ok_s = {gid: _fits(shafts[d["shaft"]], start[gid], d) for gid, d in gears.items()}
    if all(ok_c.values()):
        chosen = set()
    elif all(ok_s.values()):
        chosen = set(gears)
        off = [gid for gid, ok in ok_c.items() if not ok]
        report.assumed.append(
            f"cylindrical_gear {', '.join(off)}: read as face centres, these gears leave the "
            "shaft section that carries them; every gear's u_coordinate_on_shaft is read as "
            "the START of its face (the exporter's convention), which seats them all")
    else:
        chosen = {gid for gid in gears if not ok_c[gid] and ok_s[gid]}
    for gid, d in gears.items():
        d["pos"] = round(start[gid] if gid in chosen else centre[gid], 12)
        d["face_start"] = gid in chosen
        if gid in chosen:
            report.assumed.append(
                f"cylindrical_gear {gid}: u_coordinate_on_shaft = {d['u'] * 1e3:g} mm taken as "
                f"the start of its face: centre at {d['pos'] * 1e3:g} mm on shaft {d['shaft']} "
                f"(face {(d['pos'] - 0.5 * d['width']) * 1e3:g} to "
                f"{(d['pos'] + 0.5 * d['width']) * 1e3:g} mm)")
