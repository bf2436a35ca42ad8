"""A gearbox scene -> subsystems, physical couplings and the reduced model (paper II-III).

Subsystems: one free-free shaft per ``[[gearbox.shafts]]`` (Timoshenko rotor with its
discs, fixed gears and free gears; master modes incl. rigid-body modes) and, when the scene
has ``[housing]``, the housing fixed at its base (master modes and their values at the
rolling-element points of the bores).  Couplings in physical coordinates
(:mod:`vibrogear.models.gearbox.couplings`): gear meshes (dead zone with backlash, mesh
stiffness and transmission-error harmonics, each mesh at its own mesh frequency:
:mod:`vibrogear.models.gearbox.mesh_contacts`), rolling elements (one-sided Hertzian
contacts with clearance, journal node to bore point, or to ground without housing),
linear links (axial bearing springs, radial bearing damping, spring bearings, external
torsional couplings; :mod:`vibrogear.models.gearbox.supports`).  :func:`build_gearbox`
joins them by :func:`~vibrogear.models.gearbox.synthesis.synthesize`.

Mesh stiffness: a number [N/m] along the tooth normal, or ``"iso6336"``: ISO 6336-1 method B
from the gear data (:mod:`vibrogear.models.gearbox.iso6336`; ``k_normal`` and, on every
mesh, the single/double contact harmonics unless the user gives harmonics), or two levels
(``stiffness_levels``, :func:`~vibrogear.models.gearbox.mesh_law.level_harmonics`).  The ISO
values of every mesh whose gear data lie in the method's range are kept in
``GearboxModel.mesh_stiffness``
next to the user's value.  Profile-shifted pairs (x_a + x_b != 0) mesh on their working
pitch cylinders (zero backlash), which fix the centre distance.  Static load: the
twist-angle torques, free-gear drag and, with ``[gearbox] gravity``, the weight of the
shafts with their discs and gears (``M g``; not the housing's own weight).

The coordinates q are deviations from the steady rigid-body rotation fixed by the motor and
load discs (they spin at omega_s with prescribed angles), so the paper's spin velocities of
eq. (9) are the frame itself: the initial state is the static equilibrium with zero
velocity.  The scene's parameter is the driving-shaft speed in rpm.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ...config.base import ConfigError
from ...config.model.gearbox_supports import torque_order_ratios
from ...config.model.layout import shaft_bore
from ...config.options import RPM as RPM_PARAMETER
from ...config.model.rotor import FreeGearConfig, DiscConfig, RotorConfig
from .supports import bearings as _bearings, gravity_load, housing_to_rotor
from .mesh_contacts import gear_mesh_contacts, mesh_geometry
from .mesh_law import iso_mesh_stiffness, mesh_law as _mesh_law
from .master_level import (coupling_loads, excitation_frequencies_hz, highest_speed,
                           shaft_master_modes)
from ..rotor.model import build_rotor_model
from .synthesis import (LinearLink, PhysicalVector, Subsystem, modal_projection,
                        synthesize)

__all__ = ["GearboxModel", "build_gearbox", "external_couplings", "check_layout", "OMEGA_REF", "RPM",
           "housing_to_rotor", "iso_mesh_stiffness", "gravity_load"]


#: model time unit 1 / OMEGA_REF s (tau = OMEGA_REF t)
OMEGA_REF = 2.0 * math.pi * 1000.0
#: rad/s per rpm
RPM = 2.0 * math.pi / 60.0


@dataclass(frozen=True, eq=False)
class GearboxModel:
    reduced: object                       # ReducedModel
    subsystems: tuple
    contacts: tuple                       # ContactLaw, in the reduced model's contact order
    links: tuple                          # LinearLink
    static_force: PhysicalVector
    shaft_ratios: tuple                   # p_s per shaft
    rotors: tuple                         # RotorModel per shaft
    mesh_teeth: int                       # teeth of meshes[0].gear_a: mesh frequency = z n / 60
    omega_ref: float = OMEGA_REF
    housing: object = None                # HousingModes or None
    timings: dict = field(default_factory=dict)
    blocks: tuple = ()                    # LinearBlock (cross-coupled bearing terms)
    mesh_stiffness: tuple = ()            # per mesh: user / ISO 6336 / used values (dicts)
    #: (m,) Phi^T M r, r the rigid rotation of the train (1 on the driving shaft's torsion
    #: DOF, the speed ratios elsewhere, a free gear its own; 0 on the housing): an
    #: acceleration alpha [rad/s^2] of the driving shaft adds the force -rigid_inertia alpha
    rigid_inertia: np.ndarray | None = None
    #: per torque order of a coupling: coupling, order, amplitude_Nm, phase_deg and its
    #: frequency over the mesh frequency (the reduced model's harmonic slot)
    torque_orders: tuple = ()
    #: per coupling: its disc angle [rad, signed on its DOF], stiffness x angle its static
    #: torque on the rigid train (the twist, or the one that meets a torque / power load:
    #: :mod:`vibrogear.models.gearbox.load_path`)
    coupling_angles: tuple = ()

    @property
    def time_unit_s(self) -> float:
        return 1.0 / self.omega_ref

    def inertia_force(self) -> np.ndarray:
        """-rigid_inertia alpha in model units per unit d rpm / d tau (the ``inertia_force``
        of :func:`~vibrogear.solvers.sequential.ramp.ramp`): alpha = RPM omega_ref d rpm / d tau."""
        return -self.rigid_inertia * (RPM / self.omega_ref)

    def mesh_frequency_hz(self, rpm: float) -> float:
        return self.mesh_teeth * rpm / 60.0

    def mesh_stiffness_summary(self) -> list[dict]:
        """Per mesh: the stiffness used [N/m], its source, the user's value and ISO 6336-1's
        (along the tooth normal, with c', c_gamma_alpha in N/(mm um) and the contact
        ratios) where both exist."""
        out = []
        for r in self.mesh_stiffness:
            iso = r["iso6336"] or {}
            out.append({"mesh": r["mesh"], "source": r["source"],
                        "used_N_per_m": r["stiffness_used_N_per_m"],
                        "user_N_per_m": r["user_N_per_m"],
                        "iso6336_N_per_m": iso.get("k_normal_N_per_m"),
                        "iso6336_c_prime_N_per_mm_um": iso.get("c_prime_N_per_mm_um"),
                        "iso6336_c_gamma_alpha_N_per_mm_um": iso.get("c_gamma_alpha_N_per_mm_um"),
                        "eps_alpha": iso.get("eps_alpha"), "eps_beta": iso.get("eps_beta"),
                        "harmonics_cos": r["harmonics_cos"], "harmonics_sin": r["harmonics_sin"],
                        "note": r.get("iso6336_note", "")})
        return out

    def contact_indices(self, kind: str) -> np.ndarray:
        return np.array([j for j, c in enumerate(self.contacts) if c.kind == kind], dtype=int)


def _rotor_config(sh, gears, gear_p, shaft_p) -> tuple[RotorConfig, list[int]]:
    discs, free, free_ids = list(sh.discs), [], []
    for k, g in gears:
        if g.mass is not None:
            geo = dict(position=g.position, mass=g.mass, Id=g.Id, Ip=g.Ip, name=g.name)
        else:
            geo = dict(position=g.position, outer_diameter=g.pitch_diameter,
                       inner_diameter=g.inner_diameter, width=g.width, density=g.density,
                       name=g.name)
        if g.free:
            free.append(FreeGearConfig(**geo, torsional_damping=g.torsional_damping,
                                       speed_ratio=gear_p[k] / shaft_p))
            free_ids.append(k)
        else:
            discs.append(DiscConfig(**geo))
    return RotorConfig(material=sh.material, sections=sh.sections, discs=tuple(discs),
                       free_gears=tuple(free), name=sh.name), free_ids


def _shaft_subsystem(sh, rotor, mm, p) -> Subsystem:
    V = mm.vectors
    proj = lambda A: V.T @ (A @ V)  # noqa: E731
    B, G, C = proj(rotor.B), proj(rotor.G), proj(rotor.C)
    zeta = np.where(mm.frequencies_hz > 0, sh.modal_damping, 0.0)
    return Subsystem(name=sh.name, kind="shaft", n_dofs=rotor.n_dofs, freqs_hz=mm.frequencies_hz,
                     vectors=V, damping_ratio=zeta, spin_ratio=p,
                     B=B if np.any(B) else None, G=G if np.any(G) else None,
                     C=C if np.any(C) else None,
                     labels={"n_rigid": mm.n_rigid, "n_static": mm.n_static})


def _housing_subsystem(scene, count):
    from ..housing.run import housing_modes

    hm = housing_modes(scene.housing)
    m = hm.freqs_hz.size if count is None else min(count, hm.freqs_hz.size)
    vals = np.nan_to_num(hm.bore_values[..., :m])        # (B, P, 3, m), NaN padding -> 0
    w = 2 * np.pi * hm.freqs_hz[:m]
    sub = Subsystem(name="housing", kind="housing", n_dofs=hm.n_dofs, freqs_hz=hm.freqs_hz[:m],
                    vectors=vals.reshape(-1, m), damping_ratio=0.5 * hm.beta * w,
                    labels={"points": vals.shape[1]})
    return sub, hm


def shaft_axis(scene, sh, i) -> tuple[float, float]:
    """Housing-frame (x, z) of shaft i's axis."""
    path = f"gearbox.shafts[{i}]"
    if scene.housing is not None:
        b = shaft_bore(scene.housing, sh.bore)
        if b is not None:
            if sh.x is not None or sh.z is not None:
                raise ConfigError(f"{path}.x", "with a housing the axis is the bore's: "
                                  "leave x and z out")
            return b.x, b.z
        names = ", ".join(repr(b.name) for b in scene.housing.bores)
        raise ConfigError(f"{path}.bore", f"unknown bore {sh.bore!r}; housing bores are {names}")
    if sh.x is None or sh.z is None:
        raise ConfigError(f"{path}.x", "without a housing each shaft needs its axis x and z")
    return sh.x, sh.z


def build_gearbox(scene, *, master_counts=None, housing_count=None,
                  master_level: str | None = None,
                  static_correction: bool | None = None) -> GearboxModel:
    """Build the reduced gearbox model of ``scene``; ``master_counts`` (one per shaft) and
    ``housing_count`` override the scene's reduction level (the reduction study), as do
    ``master_level`` ("count" | "frequency", :mod:`vibrogear.models.gearbox.master_level`) and
    ``static_correction``."""
    cfg = scene.gearbox
    t0 = time.perf_counter()
    shaft_p, gear_p = cfg.speed_ratios()
    axes = [shaft_axis(scene, sh, i) for i, sh in enumerate(cfg.shafts)]
    subsystems, rotors, free_dof = [], [], {}
    for i, sh in enumerate(cfg.shafts):
        gears = [(k, g) for k, g in enumerate(cfg.gears) if g.shaft == sh.name]
        rcfg, free_ids = _rotor_config(sh, gears, gear_p, shaft_p[i])
        rotor = build_rotor_model(rcfg)
        free_dof.update({k: rotor.free_gear_dofs[j] for j, k in enumerate(free_ids)})
        rotors.append(rotor)
    t_shafts = time.perf_counter()
    hm = housing_sub = None
    if scene.housing is not None:
        housing_sub, hm = _housing_subsystem(scene, housing_count)
    t_housing = time.perf_counter()
    contacts, links, forces = [], [], []
    mc, records, slot_orders = gear_mesh_contacts(cfg, axes, shaft_p, gear_p, rotors, free_dof)
    contacts += mc
    bc, bl, blocks = _bearings(scene, cfg, rotors, hm)
    contacts += bc
    links += bl
    cl, forces = external_couplings(cfg, rotors, shaft_p)
    angles = tuple(float(f[2][0]) / c.stiffness for f, c in zip(forces, cfg.couplings))
    teeth = cfg.gears[cfg.gear_index(cfg.meshes[0].gear_a, "")].teeth if cfg.meshes else 1
    orders = torque_order_forcing(cfg, rotors, shaft_p)
    forces += gravity_load(cfg.gravity, rotors)
    links += cl
    for k, g in enumerate(cfg.gears):
        if g.free and g.drag_torque:
            s = cfg.shaft_index(g.shaft, "")
            sense = -np.sign(gear_p[k] - shaft_p[s])      # opposes the relative spin
            forces.append((s, [free_dof[k]], [sense * g.drag_torque]))
    static_force = PhysicalVector.of(*forces)
    t_couple = time.perf_counter()
    level = master_level or ("count" if master_counts is not None else cfg.master_modes)
    correct = next((c for c in (static_correction, cfg.static_correction) if c is not None),
                   level == "frequency")
    f_exc = excitation_frequencies_hz(cfg, highest_speed(scene)) \
        if level == "frequency" else None
    for i, (sh, rotor) in enumerate(zip(cfg.shafts, rotors)):
        cutoff = None if f_exc is None else cfg.frequency_factor * max(f_exc[i], 1e-3)
        loads = coupling_loads(i, rotor.n_dofs, [c.vector for c in contacts]
                               + [l_.vector for l_ in links]
                               + [v for b in blocks for v in b.vectors]
                               + [static_force]) if correct else None
        count = sh.master_count if master_counts is None else int(master_counts[i])
        mm = shaft_master_modes(sh, rotor, count=count, cutoff_hz=cutoff, loads=loads,
                                cap_hz=cutoff)
        subsystems.append(_shaft_subsystem(sh, rotor, mm, shaft_p[i]))
    if housing_sub is not None:
        subsystems.append(housing_sub)
    t_modes = time.perf_counter() - t_couple
    inertia = _rigid_inertia(cfg, subsystems, rotors, shaft_p, gear_p, free_dof)
    reduced = synthesize(subsystems, contacts, links, static_force, omega_ref=OMEGA_REF,
                         omega_per_param=teeth * RPM / OMEGA_REF, spin_per_param=RPM,
                         monitor=0, name=cfg.name, param_name=RPM_PARAMETER.name, blocks=blocks,
                         order_forcing=[o[:3] for o in orders],
                         mesh_orders=[float(o) for o in slot_orders],
                         period_limit=cfg.period_limit())
    t_end = time.perf_counter()
    return GearboxModel(reduced=reduced, subsystems=tuple(subsystems), contacts=tuple(contacts),
                        links=tuple(links), static_force=static_force,
                        shaft_ratios=tuple(shaft_p), rotors=tuple(rotors), mesh_teeth=teeth,
                        housing=hm, timings={"shafts_s": t_shafts - t0 + t_modes,
                                             "housing_s": t_housing - t_shafts,
                                             "synthesis_s": t_end - t_housing - t_modes},
                        blocks=tuple(blocks), mesh_stiffness=tuple(records),
                        rigid_inertia=inertia, torque_orders=tuple(o[3] for o in orders),
                        coupling_angles=angles)


def _rigid_inertia(cfg, subsystems, rotors, shaft_p, gear_p, free_dof) -> np.ndarray:
    """Phi^T M r (:attr:`GearboxModel.rigid_inertia`) from the shafts' M and master modes."""
    forces = {}
    for i, rotor in enumerate(rotors):
        r = np.zeros(rotor.n_dofs)
        r[[rotor.dof(n, "psi") for n in range(rotor.n_nodes)]] = shaft_p[i]
        for k, g in enumerate(cfg.gears):
            if g.free and cfg.shaft_index(g.shaft, "") == i:
                r[free_dof[k]] = gear_p[k]
        forces[i] = rotor.M @ r
    return modal_projection(subsystems, forces)


def check_layout(scene) -> None:
    """The gearbox checks that need no FE model (shaft axes, mesh planes and centre
    distances, ISO 6336 mesh stiffness, the speed range of master_modes = "frequency", the
    common excitation period of the analyses that shoot), run by the scene's validation so
    that ``vibrogear check`` reports them."""
    cfg = scene.gearbox
    _, gear_p = cfg.speed_ratios()
    axes = [shaft_axis(scene, sh, i) for i, sh in enumerate(cfg.shafts)]
    if cfg.master_modes == "frequency":
        highest_speed(scene)                 # the criterion needs the scene's speed range
    for i, m in enumerate(cfg.meshes):
        mesh_geometry(cfg, i, axes, gear_p)
        if m.iso6336 or m.stiffness_levels:
            _mesh_law(cfg, i)
    # shooting needs a common excitation period (the analyses this run does: a verb alone
    # for `vibrogear sweep` etc., so a scene listing continuation still sweeps)
    map_ = getattr(scene, "map", None)
    cfg.check_common_period([a for a in scene.scene.analyses if a == "continuation" or (
        a == "map" and map_ is not None and map_.curves)], "gearbox")


def external_couplings(cfg, rotors, shaft_p):
    """The external torsional couplings: (links, forces), the links' springs and dampers and
    the constant torques of their static twists (stiffness x twist, the load), per shaft."""
    links, forces = [], []
    for c in cfg.couplings:
        s = cfg.shaft_index(c.shaft, "")
        dof = rotors[s].dof(rotors[s].node_at(c.position), "psi")
        sense = 1.0 if shaft_p[s] > 0 else -1.0
        disc_angle = sense * c.static_twist * (1.0 if c.role == "motor" else -1.0)
        links.append(LinearLink(c.name, PhysicalVector.of((s, [dof], [1.0])), c.stiffness,
                                c.damping))
        forces.append((s, [dof], [c.stiffness * disc_angle]))
    return links, forces


def torque_order_forcing(cfg, rotors, shaft_p) -> tuple:
    """The couplings' torque orders as harmonic slots of the excitation: (n, cos force,
    sin force, record) each, n = order p_s / z (:func:`torque_order_ratios`), the forces
    PhysicalVectors on the coupling's torsional DOF: A cos(n W t + phi) = A cos(phi)
    cos(n W t) - A sin(phi) sin(n W t), in the sense of the coupling's static torque (a
    motor drives, a load brakes)."""
    out = []
    for i, order, amp, phase_deg, n in torque_order_ratios(cfg):
        c = cfg.couplings[i]
        s = cfg.shaft_index(c.shaft, "")
        dof = rotors[s].dof(rotors[s].node_at(c.position), "psi")
        sign = (1.0 if shaft_p[s] > 0 else -1.0) * (1.0 if c.role == "motor" else -1.0)
        phi = math.radians(phase_deg)
        out.append((float(n), PhysicalVector.of((s, [dof], [sign * amp * math.cos(phi)])),
                    PhysicalVector.of((s, [dof], [-sign * amp * math.sin(phi)])),
                    {"coupling": c.name, "order": float(order), "amplitude_Nm": amp,
                     "phase_deg": phase_deg, "per_mesh_frequency": float(n),
                     "fraction_of_mesh_frequency": f"{n.numerator}/{n.denominator}"}))
    return tuple(out)
