"""The static load path of a gearbox scene: the torque and power on every shaft and coupling,
the tooth force of every mesh and the reactions of every bearing in the static state of the
elastic model, each against the nominal torque balance of the rigid gear train.

Nominal torque balance: every torsional body (a shaft, a free gear) in equilibrium under
its couplings' torques and its meshes' tooth forces, sum_c T_c - sum_j F_j a_j = 0, a_j the
mesh's torque arm on the body (its base radius x cos(beta_b), signed: the torsional entry
of the mesh's coupling vector).  The torques of the couplings given by ``torque`` or
``power`` are known; a coupling given by ``twist`` takes the torque its twist produces in
the static state (the first motor's when no coupling gives a torque), the others follow
from the balance.  The balance leaves out the free gears' drag: an idle mesh carries no
nominal force.

Mesh roles (structural, not a threshold): a mesh is ``idle`` when it lies on no torque path
between a motor and a load coupling (removing it leaves the motor side and the load side
connected as before, e.g. it drives a free gear whose only load is its drag); otherwise
``loaded``.

Static tooth force: the mesh contact's force at the static state (mean mesh stiffness, no
transmission error), along the tooth normal; its transverse tangential component at the
working pitch circle is F_t = F_n cos(alpha_wt) cos(beta_b) = |torque on gear a| / r_w,a.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace

import numpy as np

from ..contact_law import evaluate_set
from .synthesis import PhysicalVector, modal_vector
from .torque_balance import coupling_signs, mesh_arms, mesh_roles, nominal_torques

__all__ = ["MeshLoad", "LoadPath", "compute_load_path", "mesh_roles", "mesh_arms",
           "nominal_torques", "coupling_signs", "coupling_dofs", "with_coupling_angles",
           "coupling_angles", "assumed_from_scene_text", "RPM"]

#: rad/s per rpm
RPM = 2.0 * math.pi / 60.0


@dataclass(frozen=True)
class MeshLoad:
    name: str                      # the mesh name as in the scene
    role: str                      # "loaded" | "idle"
    normal_force_N: float          # static tooth normal force (static state of the elastic model)
    tangential_force_N: float      # transverse tangential component at the working pitch circle
    nominal_normal_force_N: float  # from the nominal torque balance (0 for an idle mesh)
    torque_ratio: float            # output / input torque of the stage (driven / driving gear)
    power_kW: float                # at the reference speed (nan without one)
    torque_a_Nm: float = 0.0       # static torque on gear_a (F_n x r_b,a cos(beta_b))
    torque_b_Nm: float = 0.0
    nominal_torque_a_Nm: float = 0.0
    arm_a_m: float = 0.0           # r_b,a cos(beta_b)
    arm_b_m: float = 0.0

    @property
    def difference(self) -> float:
        """(static - nominal) / nominal normal force; nan for an idle mesh."""
        n = self.nominal_normal_force_N
        return (self.normal_force_N - n) / n if n > 0 else float("nan")


@dataclass(frozen=True)
class LoadPath:
    meshes: tuple[MeshLoad, ...]
    shafts: tuple[dict, ...]       # name, torque_Nm, nominal_torque_Nm, power_kW
    couplings: tuple[dict, ...]    # name, role, given, torque_Nm (static), nominal_torque_Nm
    bearings: tuple[dict, ...]     # name, shaft, radial_N, axial_N
    assumed: tuple[dict, ...] = ()  # {"what", "value", "where"}
    reference_rpm: float | None = None
    notes: tuple[str, ...] = field(default=())

    def as_dict(self) -> dict:
        """JSON-ready (summary.json ``load_path``)."""
        def num(v):
            return None if v is None or not math.isfinite(v) else float(v)
        meshes = [{"name": m.name, "role": m.role, "normal_force_N": num(m.normal_force_N),
                   "tangential_force_N": num(m.tangential_force_N),
                   "nominal_normal_force_N": num(m.nominal_normal_force_N),
                   "difference": num(m.difference), "torque_ratio": num(m.torque_ratio),
                   "power_kW": num(m.power_kW), "torque_a_Nm": num(m.torque_a_Nm),
                   "torque_b_Nm": num(m.torque_b_Nm),
                   "nominal_torque_a_Nm": num(m.nominal_torque_a_Nm)} for m in self.meshes]
        clean = lambda rows: [{k: (num(v) if isinstance(v, float) else v)  # noqa: E731
                               for k, v in r.items()} for r in rows]
        return {"reference_rpm": num(self.reference_rpm), "meshes": meshes,
                "shafts": clean(self.shafts), "couplings": clean(self.couplings),
                "bearings": clean(self.bearings), "assumed": [dict(a) for a in self.assumed],
                "notes": list(self.notes)}

    def mesh_roles(self) -> list[dict]:
        return [{"name": m.name, "role": m.role, "static_force_N": float(m.normal_force_N)}
                for m in self.meshes]

    def table_lines(self) -> list[str]:
        """The short table `vibrogear check` prints."""
        at = "" if self.reference_rpm is None else f", powers at {self.reference_rpm:.6g} rpm"
        out = [f"load path (static state{at}):"]
        for c in self.couplings:
            out.append(f"  coupling {c['name']!r} ({c['role']}, {c['given']}): "
                       f"{c['torque_Nm']:.6g} N m, nominal {c['nominal_torque_Nm']:.6g} N m "
                       f"({_pct(c['torque_Nm'], c['nominal_torque_Nm'])})")
        for s in self.shafts:
            p = "" if s["power_kW"] is None or not math.isfinite(s["power_kW"]) \
                else f", {s['power_kW']:.4g} kW"
            out.append(f"  shaft {s['name']!r}: {s['torque_Nm']:.6g} N m{p}, nominal "
                       f"{s['nominal_torque_Nm']:.6g} N m "
                       f"({_pct(s['torque_Nm'], s['nominal_torque_Nm'])})")
        for m in self.meshes:
            p = "" if not math.isfinite(m.power_kW) else f", {m.power_kW:.4g} kW"
            out.append(f"  mesh {m.name!r} ({m.role}): F_n {m.normal_force_N:.6g} N, "
                       f"F_t {m.tangential_force_N:.6g} N, nominal F_n "
                       f"{m.nominal_normal_force_N:.6g} N "
                       f"({_pct(m.normal_force_N, m.nominal_normal_force_N)}), torque ratio "
                       f"{m.torque_ratio:.6g}{p}")
        for b in self.bearings:
            out.append(f"  bearing {b['name']!r} on {b['shaft']!r}: radial {b['radial_N']:.5g} N, "
                       f"axial {b['axial_N']:.5g} N")
        if self.assumed:
            out.append("  the numbers this rests on that the scene assumed:")
            out += [f"    {a['where']}: {a['what']}" for a in self.assumed]
        out += [f"  note: {n}" for n in self.notes]
        return out


def _pct(value, nominal) -> str:
    if nominal is None or not math.isfinite(nominal) or abs(nominal) == 0.0:
        return "no nominal"
    return f"{100.0 * (value - nominal) / nominal:+.3g} %"


# ------------------------------------------------------------------ the static state

def coupling_dofs(cfg, gm) -> list[tuple[int, int]]:
    """(shaft, torsional DOF) of each coupling."""
    out = []
    for c in cfg.couplings:
        s = cfg.shaft_index(c.shaft, "")
        rotor = gm.rotors[s]
        out.append((s, rotor.dof(rotor.node_at(c.position), "psi")))
    return out


def coupling_angles(cfg) -> np.ndarray:
    """The couplings' disc angles of the scene as given (signed, rad): sense x static twist."""
    return np.array([sg * c.static_twist for sg, c in zip(coupling_signs(cfg), cfg.couplings)])


def with_coupling_angles(gm, cfg, angles):
    """``gm`` with the couplings' disc angles [rad, signed] replaced: the static force's
    coupling parts (stiffness x angle) and the reduced model's F0; the links, modes and
    dynamics are unchanged."""
    angles = np.asarray(angles, dtype=float)
    parts = list(gm.static_force.parts)
    for i, (c, (sc, dof)) in enumerate(zip(cfg.couplings, coupling_dofs(cfg, gm))):
        s, idx, _ = parts[i]
        if s != sc or list(idx) != [dof]:       # build_gearbox puts the couplings first
            raise RuntimeError(f"static force part {i} is not coupling {c.name!r}")
        parts[i] = (s, idx, np.array([c.stiffness * angles[i]]))
    sf = PhysicalVector(tuple(parts))
    r = gm.reduced
    F0 = modal_vector(sf, gm.subsystems) / gm.omega_ref ** 2
    reduced = replace(r, forcing=replace(r.forcing, F0=F0))
    return replace(gm, static_force=sf, reduced=reduced, coupling_angles=tuple(angles))


def _angles_of(gm, cfg) -> np.ndarray:
    a = getattr(gm, "coupling_angles", ())
    return np.asarray(a, dtype=float) if len(a) == len(cfg.couplings) else coupling_angles(cfg)


def coupling_torques(gm, cfg, x, scale: float = 1.0) -> np.ndarray:
    """Static torque of each coupling on its shaft (signed on its DOF) [N m]:
    stiffness x (disc angle - DOF angle); ``scale``: every disc angle scaled by it (the
    operating map's load rows, :mod:`vibrogear.analyses.map.load_scaling`)."""
    angles = scale * _angles_of(gm, cfg)
    out = []
    for i, (c, (s, dof)) in enumerate(zip(cfg.couplings, coupling_dofs(cfg, gm))):
        psi = modal_vector(PhysicalVector.of((s, [dof], [1.0])), gm.subsystems) @ x
        out.append(c.stiffness * (angles[i] - psi))
    return np.array(out)


def contact_forces(gm, x) -> np.ndarray:
    """Static force of every contact [N] (positive: pushes the contact apart along -d)."""
    r = gm.reduced
    if not r.contacts.count:
        return np.zeros(0)
    law = evaluate_set(r.contacts, r.contacts.directions @ x)
    return np.asarray(law.force) * r.force_unit_n


def _bearing_reactions(gm, cfg, x, fc) -> list[dict]:
    """Per bearing: the force of its contacts, links and blocks on the journal [N]."""
    out = []
    for b in cfg.bearings:
        s = cfg.shaft_index(b.shaft, "")
        rotor = gm.rotors[s]
        jd = rotor.node_dofs(rotor.node_at(b.position))[:3]
        f = np.zeros(3)

        def add(vec, force):
            for k, idx, val in vec.parts:
                if k != s:
                    continue
                for d, v in zip(idx, val):
                    hit = np.nonzero(jd == d)[0]
                    if hit.size:
                        f[hit[0]] -= force * v
                break
        for j, c in enumerate(gm.contacts):
            if c.kind == "bearing" and c.group == b.name:
                add(c.vector, fc[j])
        for link in gm.links:
            if link.name.partition(":")[0] == b.name and link.name in (
                    f"{b.name}:axial", f"{b.name}:x", f"{b.name}:y") or (
                    link.name.startswith(f"{b.name}:stiffness")):
                add(link.vector, link.stiffness * (modal_vector(link.vector, gm.subsystems) @ x))
        for blk in gm.blocks:
            if blk.name.partition(":")[0] == b.name:
                q = np.array([modal_vector(v, gm.subsystems) @ x for v in blk.vectors])
                for v, fr in zip(blk.vectors, np.asarray(blk.stiffness) @ q):
                    add(v, fr)
        f[np.abs(f) < 1e-6] = 0.0               # round-off of an unloaded direction [N]
        out.append({"name": b.name, "shaft": b.shaft, "radial_N": float(math.hypot(f[0], f[1])),
                    "axial_N": float(abs(f[2]))})
    return out


def _shaft_torque(cfg, s, applied) -> float:
    """Largest internal torque along shaft s from the applied (position, torque) pairs."""
    if not applied:
        return 0.0
    applied = sorted(applied)
    run, peak = 0.0, 0.0
    for _, t in applied:
        run += t
        peak = max(peak, abs(run))
    return peak


def _working_radii(scene, cfg):
    """Working pitch radius of gear_a of each mesh [m] (None without the scene)."""
    if scene is None:
        return None
    from .mesh_contacts import mesh_geometry        # the model's own geometry
    from .model import shaft_axis
    _, gear_p = cfg.speed_ratios()
    axes = [shaft_axis(scene, sh, i) for i, sh in enumerate(cfg.shafts)]
    out = []
    for j in range(len(cfg.meshes)):
        geom, _, _ = mesh_geometry(cfg, j, axes, gear_p)
        out.append(geom.base_radius_a / math.cos(geom.transverse_pressure_angle))
    return out


def compute_load_path(gearbox_model, gearbox_config, static_x, *, scene=None,
                      reference_rpm: float | None = None, assumed=()) -> LoadPath:
    """The load path of ``gearbox_model`` at its static state ``static_x`` (the reduced
    model's coordinates, :func:`vibrogear.solvers.static.static_equilibrium`)."""
    gm, cfg, x = gearbox_model, gearbox_config, np.asarray(static_x, dtype=float)
    shaft_p, gear_p = cfg.speed_ratios()
    fc = contact_forces(gm, x)
    mesh_idx = [j for j, c in enumerate(gm.contacts) if c.kind == "mesh"]
    arms = mesh_arms(gm)
    T_c = coupling_torques(gm, cfg, x)
    produced = {i: float(T_c[i]) for i, c in enumerate(cfg.couplings) if c.load_given == "twist"}
    F_nom, T_nom, notes = nominal_torques(cfg, [a[:2] for a in arms], produced)
    roles = mesh_roles(cfg)
    radii = _working_radii(scene, cfg)
    w_ref = None if reference_rpm is None else reference_rpm * RPM
    meshes, applied, applied_nom = [], {}, {}
    for i, (c, (s, dof)) in enumerate(zip(cfg.couplings, coupling_dofs(cfg, gm))):
        applied.setdefault(s, []).append((c.position, T_c[i]))
        applied_nom.setdefault(s, []).append((c.position, T_nom[i]))
    for j, m in enumerate(cfg.meshes):
        ka, kb = cfg.gear_index(m.gear_a, ""), cfg.gear_index(m.gear_b, "")
        f = float(fc[mesh_idx[j]])
        arm_a, arm_b = arms[j][0], arms[j][1]
        ta, tb = -f * arm_a, -f * arm_b                # torques on the gears [N m]
        ga, gb = cfg.gears[ka], cfg.gears[kb]
        for k, g, t, tn in ((ka, ga, ta, -F_nom[j] * arm_a), (kb, gb, tb, -F_nom[j] * arm_b)):
            if not g.free:
                s = cfg.shaft_index(g.shaft, "")
                applied.setdefault(s, []).append((g.position, t))
                applied_nom.setdefault(s, []).append((g.position, tn))
        # the driving gear: its torque works with its spin (power flows out of it into b)
        drive_a = ta * gear_p[ka] <= 0.0 if f != 0 else True
        ratio = abs(arm_b / arm_a) if drive_a else abs(arm_a / arm_b)
        r_w = radii[j] if radii is not None else abs(arm_a)
        ft = abs(ta) / r_w if radii is not None else float("nan")
        power = abs(ta * gear_p[ka]) * w_ref / 1e3 if w_ref is not None else float("nan")
        meshes.append(MeshLoad(name=m.name, role=roles[j], normal_force_N=abs(f),
                               tangential_force_N=ft,
                               nominal_normal_force_N=abs(float(F_nom[j])),
                               torque_ratio=float(ratio), power_kW=float(power),
                               torque_a_Nm=float(ta), torque_b_Nm=float(tb),
                               nominal_torque_a_Nm=float(-F_nom[j] * arm_a),
                               arm_a_m=float(arm_a), arm_b_m=float(arm_b)))
    shafts = []
    for s, sh in enumerate(cfg.shafts):
        t = _shaft_torque(cfg, s, applied.get(s, []))
        tn = _shaft_torque(cfg, s, applied_nom.get(s, []))
        shafts.append({"name": sh.name, "torque_Nm": float(t), "nominal_torque_Nm": float(tn),
                       "speed_ratio": float(shaft_p[s]),
                       "power_kW": (float(t * abs(shaft_p[s]) * w_ref / 1e3)
                                    if w_ref is not None else None)})
    couplings = []
    for i, c in enumerate(cfg.couplings):
        s = cfg.shaft_index(c.shaft, "")
        couplings.append({"name": c.name, "role": c.role, "shaft": c.shaft,
                          "given": c.load_given, "torque_Nm": float(abs(T_c[i])),
                          "nominal_torque_Nm": float(abs(T_nom[i])),
                          "twist_rad": float(abs(_angles_of(gm, cfg)[i])),
                          "power_kW": (float(abs(T_c[i] * shaft_p[s]) * w_ref / 1e3)
                                       if w_ref is not None else None)})
    bearings = _bearing_reactions(gm, cfg, x, fc)
    return LoadPath(meshes=tuple(meshes), shafts=tuple(shafts), couplings=tuple(couplings),
                    bearings=tuple(bearings), assumed=tuple(assumed),
                    reference_rpm=reference_rpm, notes=tuple(notes))


# ------------------------------------------------------------------ what the scene assumed

_NUMBER = re.compile(r"[-+]?\d[\d.]*(?:e[-+]?\d+)?(?:\s*(?:N m/rad|N m s/rad|N s/m|N/m|N m|mm|"
                     r"um|m|rad|deg|kg))?")


def assumed_from_scene_text(text: str) -> tuple[dict, ...]:
    """The "assumed" lines of an imported scene's mapping report (its leading comments):
    {"what", "value", "where"} each, the value the first number with its unit."""
    out, inside = [], False
    for line in text.splitlines():
        if not line.startswith("#"):
            if line.strip():
                break
            continue
        body = line[1:].rstrip()
        head = body.strip()
        if re.match(r"assumed \(\d+\):", head):
            inside = True
            continue
        if inside and re.match(r"\w[\w ]* \(\d+\):$", head):
            inside = False
        if inside and head:
            where, _, what = head.partition(": ")
            mv = _NUMBER.search(what)
            out.append({"where": where, "what": what or where,
                        "value": mv.group(0) if mv else ""})
    return tuple(out)
