"""Gearbox supports: the housing-to-rotor frame map, bearings (rolling elements, axial
springs, isotropic and anisotropic linear spring bearings) and the weight of the shafts.

A linear (``spring``) bearing with radial stiffness K = ((kxx, kxy), (kyx, kyy)) and damping
C (rotor frame X = -x, Y = z of the housing) acts between the journal node and the bore
centre (or ground): force -K d - C d' on the journal, d = journal minus bore-centre
displacement.  Its symmetric parts become springs/dampers along their eigenvectors (along X
and Y when diagonal: exactly the isotropic bearing's two links), its skew part
(kxy - kyx) / 2 one :class:`~vibrogear.models.gearbox.synthesis.LinearBlock` of two rows.
"""
from __future__ import annotations

import math
import re

import numpy as np

from ...config.base import ConfigError
from .bearing_hertz import contact_constant
from .couplings import bearing_contact_parameters, bearing_geometry
from .synthesis import ContactLaw, LinearBlock, LinearLink, PhysicalVector

__all__ = ["housing_to_rotor", "bearings", "gravity_load", "contact_stiffness"]


def housing_to_rotor(v) -> np.ndarray:
    """Housing frame (x, y, z) -> rotor frame (X, Y, Z) = (-x, z, y); the map is its own
    inverse."""
    v = np.asarray(v, dtype=float)
    return np.stack([-v[..., 0], v[..., 2], v[..., 1]], axis=-1)


def gravity_load(gravity, rotors) -> list:
    """Weight of every shaft with its discs and gears: ``M g`` over the translational DOF
    (``gravity`` in the housing frame [m/s^2]); [] when g = 0.  The housing's own weight is
    not included (its mode set carries no modal participation factors)."""
    g = housing_to_rotor(gravity)
    if not np.any(g):
        return []
    out = []
    for s, rotor in enumerate(rotors):
        acc = np.zeros(rotor.n_dofs)
        acc[:6 * rotor.n_nodes].reshape(-1, 6)[:, :3] = g
        out.append((s, np.arange(rotor.n_dofs), rotor.M @ acc))
    return out


def _bore_of(hm, bore: str, y) -> int:
    """Index of the bore of the shaft axis ``bore`` nearest to housing y: among its front,
    inner-wall (``<bore>/inner<k>``) and back bores."""
    cand = [b for b, n in enumerate(hm.bore_names) if n.rpartition("/")[0] == bore
            and re.fullmatch(r"front|back|inner\d+", n.rpartition("/")[2])]
    return min(cand, key=lambda b: abs(hm.bore_centers[b, 1] - y))


def _spring_links(name, centre, K, C):
    """Links (and a block for the skew part) of a linear bearing with radial stiffness K and
    damping C (2 x 2, rotor frame): the symmetric parts as springs/dampers along their
    eigenvectors (along x and y when diagonal), the skew parts as one LinearBlock."""
    K, C = np.asarray(K, float), np.asarray(C, float)
    Ks, Cs = 0.5 * (K + K.T), 0.5 * (C + C.T)
    ex, ey = np.eye(3)[:2]
    links, blocks = [], []
    if Ks[0, 1] == 0.0 and Cs[0, 1] == 0.0:
        for lab, e, j in (("x", ex, 0), ("y", ey, 1)):
            links.append(LinearLink(f"{name}:{lab}", centre(e), Ks[j, j], Cs[j, j]))
    else:
        for kind, A in (("stiffness", Ks), ("damping", Cs)):
            lam, vec = np.linalg.eigh(A)
            for j in range(2):
                if lam[j]:
                    e = vec[0, j] * ex + vec[1, j] * ey
                    k, c = (lam[j], 0.0) if kind == "stiffness" else (0.0, lam[j])
                    links.append(LinearLink(f"{name}:{kind} {j}", centre(e), k, c))
    skew_k, skew_c = 0.5 * (K[0, 1] - K[1, 0]), 0.5 * (C[0, 1] - C[1, 0])
    if skew_k or skew_c:
        J = np.array([[0.0, 1.0], [-1.0, 0.0]])
        blocks.append(LinearBlock(f"{name}:cross-coupled", (centre(ex), centre(ey)),
                                  skew_k * J, skew_c * J))
    return links, blocks


def contact_stiffness(b, es) -> float:
    """The contact constant of one element of bearing ``b`` [N/m^p]: its ``stiffness``
    override, else the Hertz constant of its element set ``es``
    (:mod:`~vibrogear.models.gearbox.bearing_hertz`)."""
    if b.stiffness is not None or es is None:
        return b.stiffness
    return contact_constant(es).stiffness


def bearings(scene, cfg, rotors, hm):
    """(contacts, links, blocks) of ``gearbox.bearings``: rolling elements (one-sided
    contacts journal -> bore point or ground), axial springs, radial damping, spring
    bearings (isotropic or anisotropic)."""
    contacts, links, blocks = [], [], []
    used: dict[int, str] = {}
    for i, b in enumerate(cfg.bearings):
        path = f"gearbox.bearings[{i}]"
        s = cfg.shaft_index(b.shaft, "")
        sh, rotor = cfg.shafts[s], rotors[s]
        jd = rotor.node_dofs(rotor.node_at(b.position))
        ring = outer = None
        es = b.element_set(path)
        if b.outer_shaft:                       # a shaft running in another
            so = cfg.shaft_index(b.outer_shaft, f"{path}.outer_shaft")
            outer = (so, rotors[so].node_dofs(rotors[so].node_at(b.outer_position)))
            n = b.elements or (es.count if es is not None else 0)
            if not n and b.type != "spring":
                raise ConfigError(f"{path}.elements", "a bearing between two shafts needs "
                                  "its number of rolling elements (3..200) or its geometry")
            angles = math.radians(b.angle_offset) + 2 * np.pi * np.arange(n) / max(n, 1)
        elif hm is not None:
            bore = _bore_of(hm, sh.bore, sh.y0 + b.position)
            if bore in used:
                raise ConfigError(f"{path}.position", f"bore {hm.bore_names[bore]!r} already "
                                  f"carries bearing {used[bore]!r}")
            used[bore] = b.name
            n = hm.bore_n_points[bore]
            if b.elements is not None and b.elements != n:
                raise ConfigError(f"{path}.elements", f"the housing bore has {n} coupling "
                                  f"points (housing.bores rolling_elements); got {b.elements}")
            radial = housing_to_rotor(hm.bore_points[bore, :n] - hm.bore_centers[bore])
            angles = np.arctan2(radial[:, 1], radial[:, 0])
            P = hm.bore_values.shape[1]
            ring = [(bore * P + k) * 3 for k in range(n)]          # first housing index
        else:
            n = b.elements or (es.count if es is not None else 0)
            if not n and b.type != "spring":
                raise ConfigError(f"{path}.elements", "without a housing give the number of "
                                  "rolling elements (3..200) or the bearing's geometry")
            angles = math.radians(b.angle_offset) + 2 * np.pi * np.arange(n) / max(n, 1)

        def centre(direction_rotor):
            """Journal minus bore-centre displacement along a rotor-frame unit vector."""
            parts = [(s, jd[:3], direction_rotor)]
            if outer is not None:
                parts.append((outer[0], outer[1][:3], -np.asarray(direction_rotor, float)))
            if ring is not None:
                h = housing_to_rotor(direction_rotor)           # same map back
                idx = [r0 + c for r0 in ring for c in range(3)]
                parts.append((len(rotors), idx, -np.tile(h, len(ring)) / len(ring)))
            return PhysicalVector.of(*parts)

        ex, ey, ez = np.eye(3)
        if b.axial_stiffness:
            links.append(LinearLink(f"{b.name}:axial", centre(ez), b.axial_stiffness, b.damping))
        if b.type == "spring":
            sl, sb = _spring_links(b.name, centre, *b.radial_matrices())
            links += sl
            blocks += sb
            continue
        if b.damping:
            for lab, e in (("x", ex), ("y", ey)):
                links.append(LinearLink(f"{b.name}:damping {lab}", centre(e), 0.0, b.damping))
        geom = bearing_geometry(angles)
        law = bearing_contact_parameters(contact_stiffness(b, es), b.clearance, b.exponent,
                                         b.contact_damping)
        for k in range(n):
            parts = [(s, jd, geom.journal[k])]
            if outer is not None:               # the outer ring moves with the outer shaft
                parts.append((outer[0], outer[1], -geom.journal[k]))
            if ring is not None:
                parts.append((len(rotors), [ring[k] + c for c in range(3)],
                              housing_to_rotor(geom.housing[k])))
            contacts.append(ContactLaw(name=f"{b.name}:{k}", vector=PhysicalVector.of(*parts),
                                       **law, kind="bearing", group=b.name))
    return contacts, links, blocks
