"""Discrete couplings of a gearbox in physical coordinates: pure functions, value AND Jacobian.

Conventions (fixed; the modal-synthesis assembly relies on them):

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
  ``W`` the mesh frequency in rad/s); the deformation in the force law is ``delta - e(t)``.
* force law: dead zone of width ``backlash`` with mesh interruption on both flanks and mesh
  stiffness ``k(t) = stiffness (1 + sum_h a_h cos(h W t) + b_h sin(h W t))``:
  ``f = k delta + damping delta'`` for ``delta > 0`` (working flank), ``f = 0`` for
  ``-backlash <= delta <= 0``, ``f = k (delta + backlash) + damping delta'`` for
  ``delta < -backlash`` (back flank, f < 0).  Damping acts only in contact.

Rolling-element bearing (rolling neglected: elements at fixed angles):

* element k at angle ``a_k`` in the lateral plane (from ``+x`` toward ``+y``), radial unit
  vector ``e_k = (cos a_k, sin a_k, 0)``.  Compression
  ``delta_k = e_k . (d_j - d_h,k) - clearance`` with ``d_j`` the journal node displacement (no
  offset, so rotations do not enter) and ``d_h,k`` the displacement of bore point k (rotor frame).
  A negative clearance is a preload (interference).
* ``f_k = stiffness delta_k^exponent (+ damping delta_k')`` for ``delta_k > 0``, else 0;
  ``-f_k e_k`` acts on the journal and ``+f_k e_k`` on bore point k.
* the optional axial spring acts between the journal ``w`` and the bore-centre axial
  displacement ``w_h`` (a given scalar, not a DOF of the returned ``K``): it adds
  ``-axial_stiffness (w - w_h)`` to ``F_j[2]`` (the only contribution to ``F_j[2]``, so the
  reaction on the housing is ``-F_j[2]``), ``axial_stiffness`` to ``K[2, 2]``, and
  ``dF_j[2]/dw_h = +axial_stiffness``.

External torsional coupling: torque on the node ``stiffness (twist - psi) - damping psi'``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["GearMeshGeometry", "gear_mesh_geometry", "mesh_force", "transmission_error",
           "gear_mesh_forces", "static_mesh_stiffness", "BearingGeometry", "bearing_geometry",
           "rolling_contact_force", "linearised_stiffness", "bearing_forces",
           "torsional_coupling"]

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


def _scalar_out(arr):
    return arr[()] if isinstance(arr, np.ndarray) and arr.ndim == 0 else arr


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
    c_a: np.ndarray                     # (6,) [n, (P - A) x n]
    c_b: np.ndarray                     # (6,) -[n, (P - B) x n]
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
                       drive_sense=+1) -> GearMeshGeometry:
    """Contact point, normal and coupling vectors of an external spur/helical pair."""
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
    c_a = np.concatenate([n, np.cross(P - A, n)])
    c_b = -np.concatenate([n, np.cross(P - B, n)])
    return GearMeshGeometry(point=_frozen(P), normal=_frozen(n), c_a=_frozen(c_a),
                            c_b=_frozen(c_b), base_radius_a=ra * float(np.cos(alpha_t)),
                            base_radius_b=rb * float(np.cos(alpha_t)),
                            transverse_pressure_angle=alpha_t, base_helix_angle=beta_b,
                            ratio=-ra / rb)


def _harmonics(t, amplitudes_cos, amplitudes_sin, frequency):
    """``s(t) = sum_h a_h cos(h W t) + b_h sin(h W t)`` and ``s'(t)``, vectorised over ``t``."""
    a = np.atleast_1d(np.asarray(amplitudes_cos, dtype=float))
    b = np.atleast_1d(np.asarray(amplitudes_sin, dtype=float))
    _require(a.ndim == 1 and b.ndim == 1, "harmonic amplitudes must be 1-D sequences")
    _require(bool(np.all(np.isfinite(a)) and np.all(np.isfinite(b))),
             "harmonic amplitudes must be finite")
    H = max(a.size, b.size)
    a = np.pad(a, (0, H - a.size))
    b = np.pad(b, (0, H - b.size))
    hw = np.arange(1, H + 1) * _finite("mesh_frequency", frequency)
    phase = np.multiply.outer(np.asarray(t, dtype=float), hw)
    cos, sin = np.cos(phase), np.sin(phase)
    return cos @ a + sin @ b, (cos @ (hw * b)) - (sin @ (hw * a))


def transmission_error(t, amplitudes_cos, amplitudes_sin, mesh_frequency):
    """Kinematic transmission error ``(e(t), e'(t))``, vectorised over ``t``."""
    e, e_dot = _harmonics(t, amplitudes_cos, amplitudes_sin, mesh_frequency)
    return _scalar_out(e), _scalar_out(e_dot)


def _check_mesh_law(stiffness, backlash, damping):
    _require(_finite("stiffness", stiffness) > 0.0, f"stiffness must be > 0, got {stiffness}")
    _require(_finite("backlash", backlash) >= 0.0, f"backlash must be >= 0, got {backlash}")
    _require(_finite("damping", damping) >= 0.0, f"damping must be >= 0, got {damping}")


def mesh_force(delta, delta_dot, t, *, stiffness, backlash, damping=0.0, stiffness_cos=(),
               stiffness_sin=(), mesh_frequency=0.0):
    """Dead-zone mesh force ``(f, df/ddelta, df/ddelta_dot)``, vectorised (module docstring)."""
    _check_mesh_law(stiffness, backlash, damping)
    delta = np.asarray(delta, dtype=float)
    delta_dot = np.asarray(delta_dot, dtype=float)
    modulation, _ = _harmonics(t, stiffness_cos, stiffness_sin, mesh_frequency)
    k = float(stiffness) * (1.0 + modulation)
    front = delta > 0.0
    back = delta < -float(backlash)
    active = front | back
    gap = np.where(front, delta, np.where(back, delta + float(backlash), 0.0))
    f = np.where(active, k * gap + float(damping) * delta_dot, 0.0)
    df = np.where(active, k, 0.0) + np.zeros_like(f)
    df_dot = np.where(active, float(damping), 0.0) + np.zeros_like(f)
    return _scalar_out(f), _scalar_out(df), _scalar_out(df_dot)


def static_mesh_stiffness(delta0, stiffness, backlash):
    """Tangent stiffness of the dead zone at a static deformation (k in contact, else 0)."""
    _check_mesh_law(stiffness, backlash, 0.0)
    delta0 = np.asarray(delta0, dtype=float)
    active = (delta0 > 0.0) | (delta0 < -float(backlash))
    return _scalar_out(np.where(active, float(stiffness), 0.0))


def gear_mesh_forces(geom: GearMeshGeometry, q_a, q_b, qd_a, qd_b, t, *, stiffness, backlash,
                     damping=0.0, stiffness_cos=(), stiffness_sin=(), mesh_frequency=0.0,
                     te_cos=(), te_sin=()):
    """Generalised mesh forces on ``[q_a, q_b]``: ``(F (12,), K (12, 12), D (12, 12))``.

    ``delta = c . q - e(t)`` with the transmission error ``e`` of amplitudes ``te_cos, te_sin``
    at the mesh frequency; ``F = -c f``, ``K = -dF/dq = c c^T df/ddelta``,
    ``D = -dF/dq' = c c^T df/ddelta_dot``.
    """
    c = geom.c
    q = np.concatenate([_vector("q_a", q_a, 6), _vector("q_b", q_b, 6)])
    qd = np.concatenate([_vector("qd_a", qd_a, 6), _vector("qd_b", qd_b, 6)])
    e, e_dot = transmission_error(t, te_cos, te_sin, mesh_frequency)
    f, df, df_dot = mesh_force(c @ q - e, c @ qd - e_dot, t, stiffness=stiffness,
                               backlash=backlash, damping=damping, stiffness_cos=stiffness_cos,
                               stiffness_sin=stiffness_sin, mesh_frequency=mesh_frequency)
    cc = np.outer(c, c)
    return -c * float(f), float(df) * cc, float(df_dot) * cc


# ------------------------------------------------------------------------------------ bearing


@dataclass(frozen=True)
class BearingGeometry:
    """Rolling elements at fixed angles; ``delta_k = journal_k . q_j + housing_k . d_h,k - c``."""
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


def _check_rolling_law(stiffness, exponent, damping):
    _require(_finite("stiffness", stiffness) > 0.0, f"stiffness must be > 0, got {stiffness}")
    _require(_finite("exponent", exponent) >= 1.0,
             f"exponent must be >= 1 (1 linear, 1.5 balls, 10/9 rollers), got {exponent}")
    _require(_finite("damping", damping) >= 0.0, f"damping must be >= 0, got {damping}")


def rolling_contact_force(delta, *, stiffness, exponent, damping=0.0, delta_dot=0.0):
    """``(f, df/ddelta, df/ddelta_dot)`` of ``k delta^p (+ c delta')`` for delta > 0, else 0."""
    _check_rolling_law(stiffness, exponent, damping)
    delta = np.asarray(delta, dtype=float)
    delta_dot = np.asarray(delta_dot, dtype=float)
    pos = delta > 0.0
    d = np.where(pos, delta, 0.0)
    k, p, c = float(stiffness), float(exponent), float(damping)
    f = np.where(pos, k * d ** p + c * delta_dot, 0.0)
    df = np.where(pos, p * k * d ** (p - 1.0), 0.0) + np.zeros_like(f)
    df_dot = np.where(pos, c, 0.0) + np.zeros_like(f)
    return _scalar_out(f), _scalar_out(df), _scalar_out(df_dot)


def linearised_stiffness(delta0, stiffness, exponent):
    """``exponent * stiffness * delta0^(exponent - 1)`` for delta0 > 0, else 0 (vectorised)."""
    _check_rolling_law(stiffness, exponent, 0.0)
    return _scalar_out(rolling_contact_force(delta0, stiffness=stiffness, exponent=exponent)[1])


def bearing_forces(geom: BearingGeometry, q_j, d_h, qd_j, dd_h, *, clearance, stiffness,
                   exponent, damping=0.0, axial_stiffness=0.0, w_h=0.0):
    """Bearing forces ``(F_j (6,), F_h (n, 3), K (6 + 3n, 6 + 3n))``.

    ``F_j`` acts on the journal node, ``F_h[k]`` on bore point k; ``K = -dF/dx`` over
    ``x = [q_j, d_h.ravel()]`` (row-major: point by point, x y z).  Damping enters ``F``
    only (``delta_k'`` from ``qd_j`` and ``dd_h``); ``w_h`` is a given scalar (docstring).
    """
    n = geom.n
    q_j = _vector("q_j", q_j, 6)
    qd_j = _vector("qd_j", qd_j, 6)
    d_h = np.asarray(d_h, dtype=float)
    dd_h = np.asarray(dd_h, dtype=float)
    _require(d_h.shape == (n, 3), f"d_h must have shape ({n}, 3), got {d_h.shape}")
    _require(dd_h.shape == (n, 3), f"dd_h must have shape ({n}, 3), got {dd_h.shape}")
    clearance = _finite("clearance", clearance)
    ka = _finite("axial_stiffness", axial_stiffness)
    _require(ka >= 0.0, f"axial_stiffness must be >= 0, got {ka}")
    w_h = _finite("w_h", w_h)

    delta = geom.journal @ q_j + np.einsum("kj,kj->k", geom.housing, d_h) - clearance
    delta_dot = geom.journal @ qd_j + np.einsum("kj,kj->k", geom.housing, dd_h)
    f, df, _ = rolling_contact_force(delta, stiffness=stiffness, exponent=exponent,
                                     damping=damping, delta_dot=delta_dot)
    f = np.atleast_1d(f)
    df = np.atleast_1d(df)
    F_j = -geom.journal.T @ f
    F_j[2] -= ka * (q_j[2] - w_h)
    F_h = -geom.housing * f[:, None]

    rows = np.zeros((n, 6 + 3 * n))
    rows[:, :6] = geom.journal
    for k in range(n):
        rows[k, 6 + 3 * k:9 + 3 * k] = geom.housing[k]
    K = rows.T @ (df[:, None] * rows)
    K[2, 2] += ka
    return F_j, F_h, K


# ---------------------------------------------------------------------------- torsional coupling


def torsional_coupling(stiffness, twist, psi, psi_dot=0.0, damping=0.0):
    """Torque on the node ``k (twist - psi) - c psi'`` and its derivatives (vectorised)."""
    k = _finite("stiffness", stiffness)
    c = _finite("damping", damping)
    _require(k >= 0.0, f"stiffness must be >= 0, got {k}")
    _require(c >= 0.0, f"damping must be >= 0, got {c}")
    torque = k * (np.asarray(twist, dtype=float) - np.asarray(psi, dtype=float)) \
        - c * np.asarray(psi_dot, dtype=float)
    return _scalar_out(torque), -k, -c
