"""REXS components -> scene tables: shafts, cylindrical gears, cylindrical stages (meshes),
and the analysis sections; bearings in :mod:`.mapping_supports`, loads in :mod:`.mapping_loads`.

Frames.  A REXS model places every part by its ``support_vector`` and ``u_axis_vector`` in
the gear unit's frame.  All shafts must be parallel with the same u direction a (else exit
2).  The scene's housing frame takes y = a (along the shafts, y = 0 at the start of the
shaft that starts first), x = the gear unit's z projected normal to a (its x where a is
along z) and z = x cross y; a shaft's axis is its support point in (x, z).

Power flow.  ``shafts[0]`` (the driving shaft of the scene) is the shaft with
``defines_speed`` (else the one carrying the torque-defining load, else the first); the
stages order the other shafts outwards from it, and each mesh's ``gear_a`` is the gear on
the shaft nearer the driving shaft.

Gears.  Each gear sits at its face centre (:func:`.mapping_shafts.axial_reference`: face-start
positions where only they seat the file's gears); a stage's mesh takes the axial overlap of
its two faces as its face width.

Problems.  Every component is mapped on its own: a problem (missing attribute, unknown unit,
broken reference, ...) is collected and the others go on; :class:`MappingStopped` then
carries all of them and the scene as far as it was mapped (the draft).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..base import ConfigError, NAME_MAX_LEN
from ..model.shaft_mesh import mesh_sections
from .mapping_scope import KNOWN_IGNORED, MAPPED_TYPES, refuse_unsupported
from .mapping_shafts import STEEL, axial_reference, diameter_at, gear_data, shafts_of
from .reader import RexsModel, read_rexs

__all__ = ["import_rexs", "RexsImport", "MappingReport", "MappingStopped", "is_rexs_path",
           "STEEL"]


def is_rexs_path(path) -> bool:
    return Path(str(path)).suffix.lower() in (".rexs", ".rexsj")


@dataclass
class MappingReport:
    """What the import did: each line names the REXS component (type and id)."""
    mapped: list = field(default_factory=list)
    assumed: list = field(default_factory=list)
    ignored: list = field(default_factory=list)

    def lines(self) -> list[str]:
        out = [f"mapped ({len(self.mapped)}):"] + [f"  {m}" for m in self.mapped]
        out += [f"assumed ({len(self.assumed)}):"] + [f"  {a}" for a in self.assumed]
        out += [f"ignored ({len(self.ignored)}):"] + [f"  {i}" for i in self.ignored]
        return out


@dataclass(frozen=True)
class RexsImport:
    data: dict              # the scene as TOML data
    comments: dict          # (table, index) -> comment naming the REXS component
    report: MappingReport
    model: RexsModel


def _name(text: str) -> str:
    s = re.sub(r"[^A-Za-z0-9._+-]+", "_", text).strip("._-") or "rexs_model"
    return s[:NAME_MAX_LEN]


def _owner(model, part_id: str, owner_type: str):
    return model.owner(part_id, owner_type)


class MappingStopped(ConfigError):
    """The mapping stopped: ``errors`` holds every problem found (each naming the component,
    the attribute and the fix), ``draft`` the scene mapped as far as it went (a
    :class:`RexsImport`), which ``vibrogear import`` writes as the draft beside the errors."""

    def __init__(self, errors: list, draft: "RexsImport"):
        super().__init__(errors[0].path, errors[0].message, errors)
        self.draft = draft


def _overlap(gears, shafts, ga, gb):
    """(face width common to both gears [m], housing y of its centre [m]) of a stage: each
    gear's face about its own centre, the mesh on the overlap."""
    lo, hi = [], []
    for g in (ga, gb):
        d = gears[g]
        y = shafts[d["shaft"]]["y0"] + d["pos"]
        lo.append(y - 0.5 * d["width"])
        hi.append(y + 0.5 * d["width"])
    return round(min(hi) - max(lo), 12), 0.5 * (min(hi) + max(lo))


def import_rexs(path, *, name: str | None = None, housing: str | None = None,
                fixed_region: dict | None = None, load_case: int | None = None) -> RexsImport:
    """Read and map a REXS file (nothing is written by this function).  A file that cannot be
    read as REXS raises ConfigError; a model whose mapping meets problems raises
    :class:`MappingStopped` with every problem found and the draft scene.  ``housing``: None
    (casing = ground), ``"box"`` or the path of a STEP casing (then ``fixed_region`` = {"min",
    "max"} in m).  ``load_case``: the load case to take (1-based; default the one with the
    largest duration share)."""
    from ..base import ErrorList
    from .mapping_loads import analysis_sections, loads
    from .mapping_supports import bearings
    model = read_rexs(path)
    src = model.source
    errs = ErrorList()
    refuse_unsupported(model, errs)
    report = MappingReport()
    frame, shafts = shafts_of(model, report, errs)
    gears, comments = {}, {}
    for g in model.of_type("cylindrical_gear"):
        with errs.catch():
            owner = _owner(model, g.id, "shaft")
            if owner is None:
                raise ConfigError(src, f"component {g.id} (cylindrical_gear) is not part of "
                                  "any shaft; fix: add an assembly relation with its shaft")
            d = gear_data(model, g, src, report)
            if owner.id not in shafts:
                continue                    # its shaft's problem is listed
            d["shaft"] = owner.id
            gears[g.id] = d
    axial_reference(gears, shafts, report)
    for d in gears.values():
        shafts[d["shaft"]]["features"].add(round(d["pos"], 12))
    discs = {}
    with errs.catch():
        discs = _additional_masses(model, shafts, report)
    stages = []
    for st in model.of_type("cylindrical_stage"):
        with errs.catch():
            rel = next((r for r in model.relations_of("stage") if r.ref("stage") == st.id), None)
            g1 = rel.ref("gear_1") if rel else None
            g2 = rel.ref("gear_2") if rel else None
            if g1 not in gears or g2 not in gears:
                if any(g in model.components and model.components[g].type == "cylindrical_gear"
                       for g in (g1, g2)) and all(g in model.components for g in (g1, g2)):
                    continue                # a gear's own problem is listed
                raise ConfigError(src, f"component {st.id} (cylindrical_stage): its stage "
                                  "relation must name two cylindrical gears as gear_1 and "
                                  "gear_2")
            if gears[g1]["shaft"] == gears[g2]["shaft"]:
                raise ConfigError(src, f"component {st.id} (cylindrical_stage): gears {g1} and "
                                  f"{g2} are both on shaft {gears[g1]['shaft']}; a stage's "
                                  "gears must sit on two shafts; fix: the assembly relations "
                                  "of the gears with their shafts")
            a = st.number("center_distance", src)
            s1, s2 = shafts[gears[g1]["shaft"]], shafts[gears[g2]["shaft"]]
            dist = math.hypot(s1["x"] - s2["x"], s1["z"] - s2["z"])
            if abs(dist - a) > 1e-4 * a:
                raise ConfigError(src, f"component {st.id} (cylindrical_stage): attribute "
                                  f"'center_distance' = {a * 1e3:g} mm, but its gears' shafts "
                                  f"{gears[g1]['shaft']} and {gears[g2]['shaft']} are "
                                  f"{dist * 1e3:.6g} mm apart; fix: the shafts' "
                                  "support_vector or the centre distance")
            b_common, _ = _overlap(gears, shafts, g1, g2)
            if b_common <= 0.0:
                raise ConfigError(src, f"component {st.id} (cylindrical_stage): the faces of "
                                  f"gears {g1} and {g2} do not overlap axially (gap "
                                  f"{-b_common * 1e3:.4g} mm); fix: their "
                                  "u_coordinate_on_shaft or the shafts' support_vector")
            stages.append((st, g1, g2))
    # the power flow and the loads follow the gear train: where a part of it has a problem,
    # the consequences would only repeat it
    train_ok = not errs
    order = list(shafts)
    if train_ok:
        with errs.catch():
            order = _power_flow(model, shafts, gears, stages)
        train_ok = not errs
    data = {"scene": {}, "gearbox": {"name": model.application and
                                     f"{Path(src).stem} ({model.application} export)"
                                     or Path(src).stem}}
    supports = bearings(model, shafts, report, errs)
    couplings, case = [], None
    if train_ok:
        with errs.catch():
            couplings, case = loads(model, shafts, gears, stages, order, report, load_case)
    for sid in order:
        sh = shafts[sid]
        sh["features"].update(b["position"] for b in supports if b["shaft"] == sid)
        sh["features"].update(b["outer_position"] for b in supports
                              if b.get("outer_shaft") == sid)
        sh["features"].update(c["position"] for c in couplings if c["shaft"] == sid)
    names = {sid: f"shaft{sid}" for sid in order}
    data["gearbox"]["shafts"] = []
    for k, sid in enumerate(order):
        sh = shafts[sid]
        secs = sh["sections"]        # meshed when the scene loads (nodes at every feature)
        n_el = sum(s["elements"] for s in mesh_sections(secs, sh["features"]))
        data["gearbox"]["shafts"].append({
            "name": names[sid], "x": sh["x"], "z": sh["z"], "y0": sh["y0"], "master_count": 20,
            "modal_damping": 0.01, "material": sh["material"], "sections": secs,
            **({"discs": discs[sid]} if discs.get(sid) else {})})
        comments[("shafts", k)] = f"REXS shaft {sid} ({sh['comp'].name})"
        report.mapped.append(f"shaft {sid} ({sh['comp'].name}) -> gearbox.shafts[{k}] "
                             f"{names[sid]!r}: {len(sh['sections'])} sections, meshed into "
                             f"{n_el} elements when the scene loads (nodes at every gear, "
                             "bearing, load and section change, elements <= 20 mm)")
    report.assumed.append("every shaft: 20 master modes, modal damping ratio 0.01")
    data["gearbox"]["gears"] = []
    for k, (gid, d) in enumerate(sorted(gears.items(), key=lambda kv: order.index(kv[1]["shaft"]))):
        inner = d["bore"] if d["bore"] else diameter_at(shafts[d["shaft"]], d["pos"])
        data["gearbox"]["gears"].append({
            "name": f"gear{gid}", "shaft": names[d["shaft"]], "position": round(d["pos"], 12),
            "teeth": d["teeth"], "module": d["module"], "helix_angle": abs(d["beta"]),
            "width": d["width"], "inner_diameter": inner})
        comments[("gears", k)] = f"REXS cylindrical_gear {gid}"
        report.mapped.append(f"cylindrical_gear {gid} -> gearbox.gears[{k}] 'gear{gid}': "
                             f"z = {d['teeth']}, m_n = {d['module'] * 1e3:g} mm, beta = "
                             f"{d['beta']:g} deg, b = {d['width'] * 1e3:g} mm, x = {d['shift']:g}")
        report.assumed.append(f"cylindrical_gear {gid}: "
                              + ("" if d["bore"] else f"bore = the shaft's diameter there "
                                 f"({inner * 1e3:g} mm); ")
                              + "inertia of the pitch-diameter disc (face width x pitch "
                              "circle, the shaft's density)")
    data["gearbox"]["meshes"] = []
    for k, (st, ga, gb) in enumerate(_stages_in_flow(stages, gears, order)):
        a, b = gears[ga], gears[gb]
        width, y_mesh = _overlap(gears, shafts, ga, gb)
        data["gearbox"]["meshes"].append({
            "name": f"stage{st.id}", "gear_a": f"gear{ga}", "gear_b": f"gear{gb}",
            "pressure_angle": a["alpha"], "hand": 1 if a["beta"] >= 0 else -1,
            "stiffness": "iso6336", "profile_shift_a": a["shift"], "profile_shift_b": b["shift"],
            "face_width": width, "backlash": 1.0e-4,
            "damping": _mesh_damping(a, b, width)})
        comments[("meshes", k)] = f"REXS cylindrical_stage {st.id} ({st.name})"
        report.mapped.append(f"cylindrical_stage {st.id} -> gearbox.meshes[{k}] 'stage{st.id}': "
                             f"gear{ga} drives gear{gb}, centre distance "
                             f"{st.number('center_distance', src) * 1e3:g} mm, mesh stiffness "
                             "by ISO 6336-1 (method B) with its single/double contact harmonics")
        if abs(width - min(a["width"], b["width"])) > 1e-9:
            report.assumed.append(
                f"cylindrical_stage {st.id}: the faces of gear{ga} (b = {a['width'] * 1e3:g} mm) "
                f"and gear{gb} (b = {b['width'] * 1e3:g} mm) overlap over {width * 1e3:.6g} mm: "
                f"the mesh's face width; the overlap's centre at housing y = "
                f"{y_mesh * 1e3:.6g} mm (each gear stays at its own face centre)")
        report.assumed.append(f"cylindrical_stage {st.id}: backlash 0.1 mm, mesh damping "
                              f"{_mesh_damping(a, b, width):.4g} N s/m (damping ratio 0.05 of "
                              "the pair's mesh mode), hand +1 = positive REXS helix angle")
    data["gearbox"]["bearings"] = supports
    data["gearbox"]["couplings"] = couplings
    for k, b in enumerate(supports):
        comments[("bearings", k)] = b.pop("_comment")
        b["shaft"] = names.get(b["shaft"], f"shaft{b['shaft']}")
        if b.get("outer_shaft"):
            b["outer_shaft"] = names.get(b["outer_shaft"], f"shaft{b['outer_shaft']}")
    for k, c in enumerate(couplings):
        comments[("couplings", k)] = c.pop("_comment")
        c["shaft"] = names[c["shaft"]]
    if case is not None:
        data.update(analysis_sections(model, case, couplings))
        data["gearbox"]["modes_rpm"] = data["time_response"]["rpm"]
    data["scene"] = {"name": _name(name or Path(src).stem), "analyses": ["modes", "sweep"],
                     "description": f"imported from {Path(src).name} (REXS {model.version})"}
    skip = ("shaft_section", "material", "cylindrical_gear_flank", "rolling_bearing_row",
            "rolling_element")
    if housing is not None and housing != "box" and \
            Path(housing).suffix.lower() not in (".step", ".stp"):
        raise ConfigError("--housing", f"expected 'box' or a STEP file (*.step, *.stp), got "
                          f"{housing!r}")
    if housing is not None and not errs:    # the housing is built around a complete gearbox
        with errs.catch():
            if housing == "box":
                from .mapping_housing import box_housing
                box_housing(model, data, report)
                what = "a generated box (see assumed)"
            else:
                from .mapping_casing_step import step_housing
                step_housing(model, data, report, str(housing), fixed_region)
                what = f"the STEP solid {housing} (see assumed)"
            skip += ("gear_casing",)
            report.mapped += [f"gear_casing {c.id} -> [housing]: {what}"
                              for c in model.of_type("gear_casing")]
    for c in model.components.values():
        if c.type in KNOWN_IGNORED and c.type not in skip:
            report.ignored.append(f"{c.type} {c.id}: {KNOWN_IGNORED[c.type]}")
        elif c.type not in KNOWN_IGNORED and c.type not in MAPPED_TYPES:
            report.ignored.append(f"{c.type} {c.id}: a component type the importer does not "
                                  "map (it carries no power path of the scene)")
    imp = RexsImport(data, comments, report, model)
    if errs:
        raise MappingStopped(errs.errors, imp)
    return imp


def _additional_masses(model, shafts, report) -> dict:
    """REXS ``additional_mass`` parts of a shaft -> rigid discs (mass, polar inertia about u,
    diametral inertia the mean about v and w); eccentricity is not mapped."""
    src, out = model.source, {}
    for c in model.of_type("additional_mass"):
        owner = model.owner(c.id, "shaft")
        if owner is None:
            raise ConfigError(src, f"component {c.id} (additional_mass) is not part of a shaft")
        sh = shafts[owner.id]
        pos = round(c.number("u_coordinate_on_shaft", src) - sh["u0"], 12)
        m = c.number("mass_of_component", src)
        ip = c.number("moment_of_inertia_u_axis", src, 0.0)
        idv = [c.number(a, src, 0.0) for a in ("moment_of_inertia_v_axis",
                                              "moment_of_inertia_w_axis")]
        disc = {"name": f"mass{c.id}", "position": pos, "mass": m, "Ip": ip,
                "Id": 0.5 * sum(idv)}
        out.setdefault(owner.id, []).append(disc)
        sh["features"].add(pos)
        report.mapped.append(f"additional_mass {c.id} -> a disc on shaft {owner.id}: {m:g} kg, "
                             f"Ip = {ip:g} kg m^2, Id = {0.5 * sum(idv):g} kg m^2"
                             + (" (eccentricity not mapped)" if c.has("eccentricity_vector")
                                else ""))
    return out


def _mesh_damping(a, b, width: float | None = None) -> float:
    """A viscous mesh damping of ratio 0.05 of the pair's mesh mode: c = 2 zeta sqrt(k m_e),
    k = c_gamma b with the ISO 6336 typical c_gamma = 20 N/(mm um), m_e the pair's equivalent
    mass on the line of action (solid steel pitch discs)."""
    def inertia_radius(g):
        r = 0.5 * g["module"] * g["teeth"] / math.cos(math.radians(g["beta"]))
        J = 0.5 * math.pi * r ** 4 * g["width"] * 7850.0
        return J, r
    (Ja, ra), (Jb, rb) = inertia_radius(a), inertia_radius(b)
    me = 1.0 / (ra ** 2 / Ja + rb ** 2 / Jb)
    k = 2e10 * (width if width is not None else min(a["width"], b["width"]))
    return float(f"{2 * 0.05 * math.sqrt(k * me):.3g}")


def _driving_shaft(model, shafts) -> str:
    for sid, s in shafts.items():
        if s["comp"].flag("defines_speed"):
            return sid
    for c in model.of_type("external_load"):
        if c.flag("defines_torque"):
            owner = _owner(model, c.id, "shaft")
            if owner is not None:
                return owner.id
    return next(iter(shafts))


def _power_flow(model, shafts, gears, stages) -> list:
    first = _driving_shaft(model, shafts)
    order, frontier = [first], [first]
    while frontier:
        nxt = []
        for sid in frontier:
            for _, g1, g2 in stages:
                for here, there in ((g1, g2), (g2, g1)):
                    t = gears[there]["shaft"]
                    if gears[here]["shaft"] == sid and t not in order:
                        order.append(t)
                        nxt.append(t)
        frontier = nxt
    for sid in shafts:
        if sid not in order:
            raise ConfigError(model.source, f"component {sid} (shaft) is joined to the driving "
                              f"shaft {first} by no cylindrical stage: every shaft must be "
                              "driven through gears")
    return order


def _stages_in_flow(stages, gears, order):
    out = []
    for st, g1, g2 in stages:
        a, b = (g1, g2) if order.index(gears[g1]["shaft"]) < order.index(gears[g2]["shaft"]) \
            else (g2, g1)
        out.append((st, a, b))
    return sorted(out, key=lambda t: order.index(gears[t[1]]["shaft"]))
