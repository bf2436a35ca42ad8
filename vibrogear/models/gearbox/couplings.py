"""Discrete couplings of a gearbox in physical coordinates: geometry and contact-law parameters.

The builders here turn gear and bearing data into coupling vectors (the deformation
``delta = c . q``) and the parameters of the one contact law,
:mod:`vibrogear.models.contact_law` (which evaluates every force, its derivatives and the
contact mode).  Conventions (fixed; the modal-synthesis assembly relies on them):

* Rotor frame: every shaft is parallel to ``z``.  A shaft node has 6 DOF in the order
  ``q = [u, v, w, phi, theta, psi]`` (displacements along x, y, z; small rotations about x, y, z).
  A material point at offset ``r`` (3-vector from the node) of a rigid gear or journal moves by
  ``d = (u, v, w) + (phi, theta, psi) x r``.  A freely rotating gear has its own rotation DOF;
  here ``psi`` is always the rotation of the gear body about ``z`` (the caller maps it).
* Generalised forces ``F`` are the forces ON the DOF (right-hand side of ``M q'' + ... = F``);
  tangent matrices are ``K = -dF/dq`` and ``D = -dF/dq'`` (they add to the structure's own).

Gear mesh (concentrated at the pitch point on the normal pressure line):

* centres ``A, B`` of the two shaft axes are 2-vectors ``(x, y)`` taken at ``z = 0`` (the plane of
  the gear nodes); ``e`` = unit vector ``A -> B``; contact point ``P = A + r_a e``;
  ``z_hat = (0, 0, 1)``.
* transverse pressure angle ``alpha_t = atan(tan(alpha_n) / cos(beta))``, base helix angle
  ``beta_b = asin(sin(beta) cos(alpha_n))``, base radii ``r cos(alpha_t)``.
* ``t = drive_sense (z_hat x e)``; unit normal
  ``n = cos(beta_b) (cos(alpha_t) t + sin(alpha_t) e) + hand sin(beta_b) z_hat``.
  ``drive_sense = +1``: gear a drives while rotating about ``+z``; ``hand = +-1`` flips the
  axial component of ``n``.
* mesh deformation (tooth compression, positive = in contact on the working flank)
  ``delta = n . (d_a(P) - d_b(P)) = c_a . q_a + c_b . q_b`` with ``c_a = [n, (P - A) x n]`` and
  ``c_b = -[n, (P - B) x n]``.  The force ``f n`` acts on gear b at P, ``-f n`` on gear a, so
  the generalised forces on ``[q_a, q_b]`` are ``F = -c f`` with ``c = [c_a, c_b]``.
* speed ratio of the external pair ``omega_b / omega_a = -r_a / r_b``: rigid rotations
  ``psi_b = -(r_a / r_b) psi_a`` give ``delta = 0``; so does any rigid-body motion of the pair.
* kinematic transmission error ``e(t) = sum_h a_h cos(h W t) + b_h sin(h W t)`` (``h = 1..H``,
  ``W`` the mesh frequency in rad/s); the contact law acts on ``delta - e(t)``.
* law parameters (:func:`mesh_contact_parameters`): a dead zone of width ``backlash``,
  ``gap_hi = 0``, ``gap_lo = -backlash``, ``k_hi = k_lo = stiffness``, exponent 1, the
  relative mesh-stiffness harmonics as the law's stiffness modulation: f > 0 on the working
  flank (``delta > 0``), f < 0 on the back flank (``delta < -backlash``), 0 in between;
  damping only in contact.

Rolling-element bearing (rolling neglected: elements at fixed angles):

* element k at angle ``a_k`` in the lateral plane (from ``+x`` toward ``+y``), radial unit
  vector ``e_k = (cos a_k, sin a_k, 0)``.  Deformation
  ``delta_k = e_k . (d_j - d_h,k) = journal_k . q_j + housing_k . d_h,k`` with ``d_j`` the
  journal node displacement (no offset, so rotations do not enter) and ``d_h,k`` the
  displacement of bore point k (rotor frame).
* law parameters (:func:`bearing_contact_parameters`): one-sided, ``gap_hi = clearance``
  (a negative clearance is a preload, an interference), ``gap_lo = -inf``, ``k_lo = 0``:
  a force ``f_k >= 0`` beyond the clearance, ``-f_k e_k`` on the journal and ``+f_k e_k``
  on bore point k.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["GearMeshGeometry", "gear_mesh_geometry", "mesh_contact_parameters",
           "BearingGeometry", "bearing_geometry", "bearing_contact_parameters"]

_Z = np.array([0.0, 0.0, 1.0])
_CENTRE_TOL = 1e-3


def _require(ok, message):
    if not ok:
        raise ValueError(message)


def _finite(name, value):
    value = float(value)
    _require(np.isfinite(value), f"{name} must be finite, got {value}")
    return value


def _vector(name, value, size):
    arr = np.asarray(value, dtype=float)
    _require(arr.shape == (size,), f"{name} must have shape ({size},), got {arr.shape}")
    _require(bool(np.all(np.isfinite(arr))), f"{name} must be finite")
    return arr


def _frozen(arr):
    arr = np.array(arr, dtype=float)
    arr.setflags(write=False)
    return arr


# --------------------------------------------------------------------------------- gear mesh


@dataclass(frozen=True)
class GearMeshGeometry:
    """Geometry of one gear mesh; ``delta = c_a . q_a + c_b . q_b`` (module docstring)."""
    point: np.ndarray                   # (3,) contact point P (z = 0)
    normal: np.ndarray                  # (3,) unit normal n, direction of the force on gear b
    c_a: np.ndarray                     # (6,) [n, (P + offset_a z - A) x n]
    c_b: np.ndarray                     # (6,) -[n, (P + offset_b z - B) x n]
    base_radius_a: float
    base_radius_b: float
    transverse_pressure_angle: float    # alpha_t [rad]
    base_helix_angle: float             # beta_b [rad]
    ratio: float                        # omega_b / omega_a = -r_a / r_b

    @property
    def c(self) -> np.ndarray:
        """(12,) coupling vector over ``[q_a, q_b]``."""
        return np.concatenate([self.c_a, self.c_b])


def gear_mesh_geometry(center_a, center_b, pitch_radius_a, pitch_radius_b,
                       normal_pressure_angle, helix_angle=0.0, hand=+1,
                       drive_sense=+1, axial_offset_a=0.0,
                       axial_offset_b=0.0) -> GearMeshGeometry:
    """Contact point, normal and coupling vectors of an external spur/helical pair.
    ``axial_offset_a`` / ``_b``: where the mesh acts along z from each gear's node (the
    centre of the faces' overlap minus the gear's centre, for faces of unequal width that
    do not share a centre; 0: the mesh acts in the gears' common plane): the lever arm
    enters the coupling vectors' rotational part, so that a rigid motion of the pair still
    deforms nothing."""
    a2 = _vector("center_a", center_a, 2)
    b2 = _vector("center_b", center_b, 2)
    ra = _finite("pitch_radius_a", pitch_radius_a)
    rb = _finite("pitch_radius_b", pitch_radius_b)
    alpha_n = _finite("normal_pressure_angle", normal_pressure_angle)
    beta = _finite("helix_angle", helix_angle)
    _require(ra > 0.0, f"pitch_radius_a must be > 0, got {ra}")
    _require(rb > 0.0, f"pitch_radius_b must be > 0, got {rb}")
    _require(0.0 < alpha_n < 0.5 * np.pi,
             f"normal_pressure_angle must lie in (0, pi/2) rad, got {alpha_n}")
    _require(abs(beta) < 0.5 * np.pi, f"|helix_angle| must be < pi/2 rad, got {beta}")
    _require(hand in (1, -1), f"hand must be +1 or -1, got {hand}")
    _require(drive_sense in (1, -1), f"drive_sense must be +1 or -1, got {drive_sense}")
    distance = float(np.hypot(*(b2 - a2)))
    _require(abs(distance - (ra + rb)) <= _CENTRE_TOL * (ra + rb),
             f"centre distance |center_b - center_a| = {distance} differs from "
             f"pitch_radius_a + pitch_radius_b = {ra + rb} by more than {_CENTRE_TOL:g} relative")

    A = np.array([a2[0], a2[1], 0.0])
    B = np.array([b2[0], b2[1], 0.0])
    e = (B - A) / distance
    P = A + ra * e
    t = drive_sense * np.cross(_Z, e)
    alpha_t = float(np.arctan(np.tan(alpha_n) / np.cos(beta)))
    beta_b = float(np.arcsin(np.sin(beta) * np.cos(alpha_n)))
    n = (np.cos(beta_b) * (np.cos(alpha_t) * t + np.sin(alpha_t) * e)
         + hand * np.sin(beta_b) * _Z)
    off_a = _finite("axial_offset_a", axial_offset_a) * _Z
    off_b = _finite("axial_offset_b", axial_offset_b) * _Z
    c_a = np.concatenate([n, np.cross(P + off_a - A, n)])
    c_b = -np.concatenate([n, np.cross(P + off_b - B, n)])
    return GearMeshGeometry(point=_frozen(P), normal=_frozen(n), c_a=_frozen(c_a),
                            c_b=_frozen(c_b), base_radius_a=ra * float(np.cos(alpha_t)),
                            base_radius_b=rb * float(np.cos(alpha_t)),
                            transverse_pressure_angle=alpha_t, base_helix_angle=beta_b,
                            ratio=-ra / rb)


def _harmonic_amplitudes(name, values):
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    _require(arr.ndim == 1, f"{name} must be a 1-D sequence")
    _require(bool(np.all(np.isfinite(arr))), f"{name} must be finite")
    return tuple(float(v) for v in arr)


def mesh_contact_parameters(stiffness, backlash, damping=0.0, stiffness_cos=(),
                            stiffness_sin=(), te_cos=(), te_sin=()) -> dict:
    """Contact-law parameters of a gear mesh (module docstring): the keyword arguments of
    :class:`~vibrogear.models.gearbox.synthesis.ContactLaw` (stiffness harmonics relative, the
    transmission error in length units)."""
    _require(_finite("stiffness", stiffness) > 0.0, f"stiffness must be > 0, got {stiffness}")
    _require(_finite("backlash", backlash) >= 0.0, f"backlash must be >= 0, got {backlash}")
    _require(_finite("damping", damping) >= 0.0, f"damping must be >= 0, got {damping}")
    k = float(stiffness)
    return dict(k_hi=k, k_lo=k, gap_hi=0.0, gap_lo=-float(backlash), exponent=1.0,
                damping=float(damping),
                stiffness_cos=_harmonic_amplitudes("stiffness_cos", stiffness_cos),
                stiffness_sin=_harmonic_amplitudes("stiffness_sin", stiffness_sin),
                error_cos=_harmonic_amplitudes("te_cos", te_cos),
                error_sin=_harmonic_amplitudes("te_sin", te_sin))


# ------------------------------------------------------------------------------------ bearing


@dataclass(frozen=True)
class BearingGeometry:
    """Rolling elements at fixed angles; ``delta_k = journal_k . q_j + housing_k . d_h,k``."""
    angles: np.ndarray      # (n,) [rad], from +x toward +y
    directions: np.ndarray  # (n, 3) e_k = (cos a_k, sin a_k, 0)
    journal: np.ndarray     # (n, 6) [e_k, 0, 0, 0]
    housing: np.ndarray     # (n, 3) -e_k

    @property
    def n(self) -> int:
        return int(self.angles.size)


def bearing_geometry(angles) -> BearingGeometry:
    """Rows of the element compressions over the journal DOF and the bore-point displacements."""
    a = np.asarray(angles, dtype=float)
    _require(a.ndim == 1 and a.size >= 1, f"angles must be a non-empty 1-D array, got {a.shape}")
    _require(bool(np.all(np.isfinite(a))), "angles must be finite")
    e = np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)])
    return BearingGeometry(angles=_frozen(a), directions=_frozen(e),
                           journal=_frozen(np.hstack([e, np.zeros_like(e)])),
                           housing=_frozen(-e))


def bearing_contact_parameters(stiffness, clearance, exponent, damping=0.0) -> dict:
    """Contact-law parameters of one rolling element (module docstring): the keyword
    arguments of :class:`~vibrogear.models.gearbox.synthesis.ContactLaw`."""
    _require(_finite("stiffness", stiffness) > 0.0, f"stiffness must be > 0, got {stiffness}")
    _require(_finite("exponent", exponent) >= 1.0,
             f"exponent must be >= 1 (1 linear, 1.5 balls, 10/9 rollers), got {exponent}")
    _require(_finite("damping", damping) >= 0.0, f"damping must be >= 0, got {damping}")
    return dict(k_hi=float(stiffness), k_lo=0.0, gap_hi=_finite("clearance", clearance),
                gap_lo=-np.inf, exponent=float(exponent), damping=float(damping))
