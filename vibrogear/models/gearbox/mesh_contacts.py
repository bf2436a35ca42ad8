"""The gear meshes of a gearbox as contacts of the model (:mod:`.model` builds the rest):
each mesh's geometry from the shaft axes and gear data (:func:`mesh_geometry`: mesh
plane, working pitch radii of profile-shifted pairs, helix hand, centre-distance check),
the harmonic slots that let every mesh excite at its own mesh frequency
(:func:`mesh_slots`) and the mesh contacts with their laws laid out over those slots
(:func:`gear_mesh_contacts`).
"""
from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from ...config.base import ConfigError
from .couplings import gear_mesh_geometry, mesh_contact_parameters
from .iso6336 import involute, inverse_involute
from .mesh_law import mesh_law as _mesh_law
from .supports import housing_to_rotor
from .synthesis import ContactLaw, PhysicalVector

__all__ = ["mesh_geometry", "mesh_slots", "gear_mesh_contacts"]


def _gear_psi(rotor, node, k, free_dof) -> int:
    return free_dof[k] if k in free_dof else rotor.dof(node, "psi")


def mesh_geometry(cfg, i, axes, gear_p):
    """(geometry, (shaft, gear index) of gear_a and of gear_b) of ``meshes[i]``; a
    ConfigError where the gears lie in different planes or the centre distance does not
    match the pitch radii."""
    m, path = cfg.meshes[i], f"gearbox.meshes[{i}]"
    ka, kb = cfg.gear_index(m.gear_a, ""), cfg.gear_index(m.gear_b, "")
    ga, gb = cfg.gears[ka], cfg.gears[kb]
    sa, sb = cfg.shaft_index(ga.shaft, ""), cfg.shaft_index(gb.shaft, "")
    ya, yb = cfg.shafts[sa].y0 + ga.position, cfg.shafts[sb].y0 + gb.position
    # faces of unequal width need not share a centre: the mesh's face width must fit in
    # their axial overlap
    overlap = min(ya + ga.width / 2, yb + gb.width / 2) - max(ya - ga.width / 2, yb - gb.width / 2)
    if abs(ya - yb) > 1e-3 * max(ga.width, gb.width) and \
            overlap < (m.face_width or min(ga.width, gb.width)) - 1e-9:
        raise ConfigError(f"{path}.gear_b", f"gears of the mesh lie in different planes: "
                          f"housing y = {ya:.6g} m (gear_a) and {yb:.6g} m (gear_b), their "
                          f"faces overlap over {max(overlap, 0.0):.6g} m, less than the mesh's "
                          "face width; adjust the shafts' y0 or the gear positions, or set "
                          "face_width to the overlap")
    ca = housing_to_rotor([axes[sa][0], 0.0, axes[sa][1]])[:2]
    cb = housing_to_rotor([axes[sb][0], 0.0, axes[sb][1]])[:2]
    r_a, r_b = ga.pitch_diameter / 2, gb.pitch_diameter / 2
    alpha_n, beta = math.radians(m.pressure_angle), math.radians(ga.helix_angle)
    shift = m.profile_shift_a + m.profile_shift_b
    if shift:       # profile-shifted pair: the working pitch cylinders (zero backlash)
        alpha_t = math.atan(math.tan(alpha_n) / math.cos(beta))
        alpha_wt = inverse_involute(float(involute(alpha_t)) + 2 * math.tan(alpha_n) * shift
                                    / (ga.teeth + gb.teeth))
        scale = math.cos(alpha_t) / math.cos(alpha_wt)
        r_a, r_b = scale * r_a, scale * r_b
        beta = math.atan(math.tan(beta) * scale)             # same lead, radius r_w
        alpha_n = math.atan(math.tan(alpha_wt) * math.cos(beta))
    # the axial thrust of a helical tooth reverses with the torque: ``hand`` is the helix
    # hand of gear_a, while the couplings' ``hand`` signs the normal's axial component
    # relative to +z, so a gear_a turning about -z (an intermediate shaft) flips it
    sense = 1 if gear_p[ka] > 0 else -1
    # faces of unequal width: the mesh acts at the centre of their overlap (rotor z =
    # housing y), each gear's node at its own centre
    y_mesh = 0.5 * (max(ya - ga.width / 2, yb - gb.width / 2)
                    + min(ya + ga.width / 2, yb + gb.width / 2)) if ya != yb else ya
    try:
        geom = gear_mesh_geometry(ca, cb, r_a, r_b, alpha_n, helix_angle=beta,
                                  hand=m.hand * sense, drive_sense=sense,
                                  axial_offset_a=y_mesh - ya, axial_offset_b=y_mesh - yb)
    except ValueError as exc:
        raise ConfigError(path, str(exc) + ("" if not shift else " (profile-shifted pair: "
                          "the working pitch radii)")) from None
    return geom, (sa, ka), (sb, kb)


def mesh_slots(cfg, laws) -> tuple[tuple, tuple]:
    """(orders, per mesh its slot indices): the harmonic slots of the meshes' excitation,
    as multiples of meshes[0]'s mesh frequency (exact fractions): 1 .. H_0 (meshes[0]'s
    harmonics, at least one slot), then each further mesh's harmonics h r_j (r_j its mesh
    frequency over meshes[0]'s) where no slot has that order yet.  ``laws``: per mesh
    (stiffness_cos, stiffness_sin, te_cos, te_sin) as it excites."""
    ratios = cfg.mesh_frequency_ratios()
    counts = [max(map(len, law)) for law in laws]
    orders = [Fraction(h) for h in range(1, max(counts[:1] + [1]) + 1)]
    where = {o: k for k, o in enumerate(orders)}
    slots = []
    for r, n in zip(ratios, counts):
        idx = []
        for h in range(1, n + 1):
            o = h * r
            if o not in where:
                where[o] = len(orders)
                orders.append(o)
            idx.append(where[o])
        slots.append(tuple(idx))
    return tuple(orders), tuple(slots)


def gear_mesh_contacts(cfg, axes, shaft_p, gear_p, rotors, free_dof):
    """The mesh contacts with their harmonics laid out over the mesh slots
    (:func:`mesh_slots`: each mesh at its own mesh frequency), the records, the slots'
    orders."""
    out, records, laws = [], [], []
    for i, m in enumerate(cfg.meshes):
        k_mesh, hc, hs, rec = _mesh_law(cfg, i)
        records.append(rec)
        laws.append((k_mesh, (hc, hs) + ((m.te_cos, m.te_sin) if m.excite else ((), ()))))
    orders, slots = mesh_slots(cfg, [law for _, law in laws])

    def spread(values, idx):        # up to the last slot given (meshes[0]: as given)
        row = np.zeros(idx[len(values) - 1] + 1 if len(values) else 0)
        row[list(idx[:len(values)])] = values
        return tuple(float(v) for v in row)

    for i, (m, (k_mesh, law), idx) in enumerate(zip(cfg.meshes, laws, slots)):
        geom, (sa, ka), (sb, kb) = mesh_geometry(cfg, i, axes, gear_p)
        ga, gb = cfg.gears[ka], cfg.gears[kb]
        parts = []
        for s, g, k, c in ((sa, ga, ka, geom.c_a), (sb, gb, kb, geom.c_b)):
            rotor = rotors[s]
            node = rotor.node_at(g.position)
            idx_ = list(rotor.node_dofs(node)[:5]) + [_gear_psi(rotor, node, k, free_dof)]
            parts.append((s, idx_, c))
        hc, hs, tc, ts = (spread(v, idx) for v in law)
        law_ = mesh_contact_parameters(k_mesh, m.backlash, m.damping, hc, hs, tc, ts)
        out.append(ContactLaw(name=m.name, vector=PhysicalVector.of(*parts), **law_,
                              kind="mesh", group=m.name))
    return out, records, orders
