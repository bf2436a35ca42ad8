"""Unit tier: the coupling builders (gear mesh, rolling bearing) against closed forms and
invariances: contact point, normal and coupling vectors, element rows, and the contact-law
parameters they produce; the physical statements (force along the normal at the pitch
point, no net moment, the driven gear pushed forward, bearing radial stiffness n k / 2,
contact loss) checked with the one contact law (models/contact_law.py) on those
parameters."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from vibrogear.models.contact_law import evaluate, harmonic_series
from vibrogear.models.gearbox.couplings import (bearing_contact_parameters, bearing_geometry,
                                        gear_mesh_geometry, mesh_contact_parameters)

RA, RB = 0.05, 0.08
ALPHA = np.radians(20.0)
BETA = np.radians(15.0)
A_XY = np.array([0.01, -0.02])
PHI_AB = 0.7                                  # direction of the centre line
B_XY = A_XY + (RA + RB) * np.array([np.cos(PHI_AB), np.sin(PHI_AB)])
LAW_KEYS = ("k_hi", "k_lo", "gap_hi", "gap_lo", "exponent", "damping")
CASES = list(itertools.product([0.0, BETA, -BETA], [1, -1], [1, -1]))   # helix, hand, sense


def geometry(helix=0.0, hand=1, sense=1):
    return gear_mesh_geometry(A_XY, B_XY, RA, RB, ALPHA, helix, hand, sense)


def rigid_motion(center_xy, translation, rotation):
    """Node DOF of a point of one rigid body moving by ``translation + rotation x X``."""
    X = np.array([center_xy[0], center_xy[1], 0.0])
    return np.concatenate([translation + np.cross(rotation, X), rotation])


def test_spur_closed_forms():
    g = geometry()
    e = (B_XY - A_XY) / (RA + RB)
    np.testing.assert_allclose(g.point, [*(A_XY + RA * e), 0.0], atol=1e-15)
    assert np.linalg.norm(g.normal) == pytest.approx(1.0)
    assert g.normal[2] == 0.0
    assert g.c_a[5] == pytest.approx(RA * np.cos(ALPHA))
    assert g.c_b[5] == pytest.approx(RB * np.cos(ALPHA))
    assert g.base_radius_a == pytest.approx(RA * np.cos(ALPHA))
    assert g.base_radius_b == pytest.approx(RB * np.cos(ALPHA))
    assert g.transverse_pressure_angle == pytest.approx(ALPHA)
    assert g.base_helix_angle == 0.0
    assert g.ratio == pytest.approx(-RA / RB)
    gear_mesh_geometry(A_XY, A_XY + 1.0005 * (B_XY - A_XY), RA, RB, ALPHA)   # within 1e-3
    # the normal makes the pressure angle with the common tangent, and leans toward B
    assert g.normal @ np.array([*e, 0.0]) == pytest.approx(np.sin(ALPHA))


@pytest.mark.parametrize("helix,hand,sense", CASES)
def test_mesh_geometry_general(helix, hand, sense):
    g = geometry(helix, hand, sense)
    A, B = np.array([*A_XY, 0.0]), np.array([*B_XY, 0.0])
    assert np.linalg.norm(g.point - A) == pytest.approx(RA)
    assert np.linalg.norm(g.point - B) == pytest.approx(RB)
    assert np.linalg.norm(g.normal) == pytest.approx(1.0)
    at, bb = g.transverse_pressure_angle, g.base_helix_angle
    # textbook: tan(beta_b) = tan(beta) cos(alpha_t), tan(alpha_n) = tan(alpha_t) cos(beta)
    assert np.tan(bb) == pytest.approx(np.tan(helix) * np.cos(at), abs=1e-15)
    assert np.tan(ALPHA) == pytest.approx(np.tan(at) * np.cos(helix))
    assert g.normal[2] == pytest.approx(hand * np.sin(bb), abs=1e-15)
    # torsional lever arms: base radius times cos(beta_b), signed by the drive sense
    assert g.c_a[5] == pytest.approx(sense * RA * np.cos(at) * np.cos(bb))
    assert g.c_b[5] == pytest.approx(sense * RB * np.cos(at) * np.cos(bb))
    # delta = n . (d_a(P) - d_b(P)) for random motions
    rng = np.random.default_rng(1)
    q_a, q_b = rng.normal(size=6), rng.normal(size=6)
    d_a = q_a[:3] + np.cross(q_a[3:], g.point - A)
    d_b = q_b[:3] + np.cross(q_b[3:], g.point - B)
    assert g.c_a @ q_a + g.c_b @ q_b == pytest.approx(g.normal @ (d_a - d_b))
    np.testing.assert_array_equal(g.c, np.concatenate([g.c_a, g.c_b]))


@pytest.mark.parametrize("helix,hand,sense", CASES)
def test_mesh_invariances(helix, hand, sense):
    g = geometry(helix, hand, sense)
    rng = np.random.default_rng(2)
    for _ in range(5):
        d0 = rng.normal(size=3)
        # rigid translation of both gears along any direction
        q = np.concatenate([d0, np.zeros(3)])
        assert abs(g.c_a @ q + g.c_b @ q) < 1e-14 * np.linalg.norm(d0) + 1e-15
        # any rigid-body motion of the pair (translation + rotation about any axis)
        w = rng.normal(size=3)
        delta = g.c_a @ rigid_motion(A_XY, d0, w) + g.c_b @ rigid_motion(B_XY, d0, w)
        assert abs(delta) < 1e-14 * (np.linalg.norm(d0) + np.linalg.norm(w))
        # meshing rotation psi_b = -(r_a / r_b) psi_a
        psi = rng.normal()
        q_a, q_b = np.zeros(6), np.zeros(6)
        q_a[5], q_b[5] = psi, g.ratio * psi
        assert abs(g.c_a @ q_a + g.c_b @ q_b) < 1e-15 * abs(psi)
        # the driver turning in its drive sense (gear b held) closes the mesh
        assert g.c_a @ (sense * 1e-3 * np.eye(6)[5]) > 0.0


def test_spur_axial_and_equal_tilt_invariance():
    g = geometry()
    rng = np.random.default_rng(3)
    for _ in range(5):
        w_a, w_b = rng.normal(size=2)
        tilt = np.array([0.0, 0.0, 0.0, *rng.normal(size=2), 0.0])
        assert g.c_a[2] * w_a + g.c_b[2] * w_b == 0.0
        assert abs(g.c_a @ tilt + g.c_b @ tilt) < 1e-15
    # a helical pair does respond to the same equal tilt (the check above is not vacuous)
    h = geometry(BETA)
    tilt = np.array([0.0, 0.0, 0.0, 1e-3, -2e-3, 0.0])
    assert abs(h.c_a @ tilt + h.c_b @ tilt) > 1e-6


@pytest.mark.parametrize("bad,match", [
    (dict(pitch_radius_a=0.0), "pitch_radius_a"), (dict(pitch_radius_b=-0.1), "pitch_radius_b"),
    (dict(normal_pressure_angle=0.0), "normal_pressure_angle"),
    (dict(normal_pressure_angle=np.pi / 2), "normal_pressure_angle"),
    (dict(helix_angle=np.pi / 2), "helix_angle"), (dict(helix_angle=-2.0), "helix_angle"),
    (dict(hand=0), "hand"), (dict(hand=2), "hand"), (dict(drive_sense=0), "drive_sense"),
    (dict(center_b=A_XY + [0.1, 0.0]), "centre distance"), (dict(center_b=A_XY), "centre distance"),
    (dict(center_b=A_XY + 1.002 * (B_XY - A_XY)), "centre distance"),
    (dict(center_a=[0.0, 0.0, 0.0]), "center_a")])
def test_mesh_geometry_rejects_bad_input(bad, match):
    args = dict(center_a=A_XY, center_b=B_XY, pitch_radius_a=RA, pitch_radius_b=RB,
                normal_pressure_angle=ALPHA)
    args.update(bad)
    with pytest.raises(ValueError, match=match):
        gear_mesh_geometry(**args)


def test_mesh_contact_parameters_closed_form():
    law = mesh_contact_parameters(4e8, 2e-5, 1.5e3, (0.15, 0.03), [-0.05], (3e-6,), ())
    assert law == dict(k_hi=4e8, k_lo=4e8, gap_hi=0.0, gap_lo=-2e-5, exponent=1.0,
                       damping=1.5e3, stiffness_cos=(0.15, 0.03), stiffness_sin=(-0.05,),
                       error_cos=(3e-6,), error_sin=())
    assert mesh_contact_parameters(1e8, 0.0)["gap_lo"] == 0.0        # no backlash


@pytest.mark.parametrize("bad,match", [(dict(stiffness=0.0), "stiffness"),
                                       (dict(stiffness=np.inf), "stiffness"),
                                       (dict(backlash=-1e-6), "backlash"),
                                       (dict(damping=-1.0), "damping"),
                                       (dict(te_cos=(np.nan,)), "te_cos"),
                                       (dict(stiffness_sin=[[0.1]]), "stiffness_sin")])
def test_mesh_contact_parameters_reject_bad_input(bad, match):
    args = dict(stiffness=1e8, backlash=1e-5)
    args.update(bad)
    with pytest.raises(ValueError, match=match):
        mesh_contact_parameters(**args)


def mesh_forces(g, law, q, qd, t, W):
    """Generalised forces F = -c f on [q_a, q_b] and the tangent K = c c^T df/ddelta of
    the contact law on the mesh's parameters, delta = c . q - e(t), k(t) = k mu(t)."""
    e, e_dot = harmonic_series(law["error_cos"], law["error_sin"], W, t)
    mu = 1.0 + harmonic_series(law["stiffness_cos"], law["stiffness_sin"], W, t)[0]
    r = evaluate(g.c @ q - e[0], g.c @ qd - e_dot[0], modulation=mu[0],
                 **{k: law[k] for k in LAW_KEYS})
    return -g.c * float(r.force), float(r.stiffness) * np.outer(g.c, g.c)


def test_mesh_law_branches_and_stiffness_harmonics():
    """On the mesh parameters: f = k delta + c delta' (working flank), 0 in the backlash,
    k (delta + b) + c delta' (back flank); k(t) = k (1 + sum a_h cos + b_h sin)."""
    k, b, c = 2e8, 1e-5, 700.0
    law = mesh_contact_parameters(k, b, c)
    delta = np.array([3e-6, 0.0, -4e-6, -b, -b - 2e-6])
    vel = np.array([0.1, 0.2, -0.3, 0.4, 0.5])
    r = evaluate(delta, vel, **{key: law[key] for key in LAW_KEYS})
    np.testing.assert_allclose(r.force, [k * 3e-6 + c * 0.1, 0, 0, 0, -k * 2e-6 + c * 0.5],
                               rtol=1e-12)
    np.testing.assert_array_equal(r.stiffness, [k, 0, 0, 0, k])
    np.testing.assert_array_equal(r.damping, [c, 0, 0, 0, c])
    # W t = 0: 1 + a1 + a2; W t = pi/2: cos(pi) = -1 for h = 2, sin(pi/2) = 1 for h = 1
    W = 1000.0
    law = mesh_contact_parameters(1e8, 0.0, 0.0, (0.2, 0.1), (0.05, -0.02))
    g = geometry()
    q = np.zeros(12)
    q[5] = 1e-6 / g.c_a[5]                                      # delta = 1e-6
    for t, factor in ((0.0, 1.3), (np.pi / (2 * W), 1 - 0.1 + 0.05)):
        F, K = mesh_forces(g, law, q, np.zeros(12), t, W)
        np.testing.assert_allclose(K, 1e8 * factor * np.outer(g.c, g.c), rtol=1e-12)
        np.testing.assert_allclose(F, -g.c * 1e8 * factor * 1e-6, rtol=1e-12)


@pytest.mark.parametrize("helix,hand,sense", CASES)
def test_mesh_force_along_the_normal_at_the_pitch_point(helix, hand, sense):
    g = geometry(helix, hand, sense)
    law = mesh_contact_parameters(3e8, 1e-5)
    rng = np.random.default_rng(5)
    q, qd = rng.normal(scale=1e-5, size=12), rng.normal(scale=1e-2, size=12)
    q[5] += (2e-6 - g.c @ q) / g.c_a[5]                         # delta = 2e-6
    F, _ = mesh_forces(g, law, q, qd, 0.0, 1.0)
    f = 3e8 * 2e-6
    np.testing.assert_allclose(F[6:9], f * g.normal, rtol=1e-9)       # on gear b along n
    np.testing.assert_allclose(F[0:3], -f * g.normal, rtol=1e-9)
    # both forces act at P: total moment about the origin vanishes
    A, B = np.array([*A_XY, 0.0]), np.array([*B_XY, 0.0])
    moment = F[3:6] + np.cross(A, F[0:3]) + F[9:12] + np.cross(B, F[6:9])
    assert np.abs(moment).max() < 1e-12 * f
    # the driven gear is pushed in its own sense of rotation (-sense), the driver braked
    assert np.sign(F[11]) == -sense and np.sign(F[5]) == -sense


def test_mesh_transmission_error_shifts_delta():
    g = geometry(BETA)
    law = mesh_contact_parameters(2e8, 1e-5, te_cos=(4e-6,))
    z = np.zeros(12)
    F, K = mesh_forces(g, law, z, z, 0.0, 100.0)                # delta = -e(0) = -4e-6
    assert not F.any() and not K.any()
    q = np.zeros(12)
    q[5] = 7e-6 / g.c_a[5]                                      # c.q = 7e-6, delta = 3e-6
    F, _ = mesh_forces(g, law, q, z, 0.0, 100.0)
    np.testing.assert_allclose(F, -g.c * 2e8 * 3e-6, rtol=1e-9)


def even(n, offset=0.0):
    return offset + 2 * np.pi * np.arange(n) / n


def test_bearing_geometry_rows():
    a = np.array([0.3, 1.9, 4.0])
    g = bearing_geometry(a)
    rng = np.random.default_rng(6)
    q_j, d_h = rng.normal(size=6), rng.normal(size=(3, 3))
    e = np.column_stack([np.cos(a), np.sin(a), np.zeros(3)])
    np.testing.assert_allclose(g.journal @ q_j + np.sum(g.housing * d_h, 1),
                               np.sum(e * (q_j[:3] - d_h), 1), rtol=1e-13)
    assert not g.journal[:, 2:].any() and not g.housing[:, 2].any()


def test_bearing_contact_parameters_closed_form():
    law = bearing_contact_parameters(8e9, 5e-6, 1.5, 20.0)
    assert law == dict(k_hi=8e9, k_lo=0.0, gap_hi=5e-6, gap_lo=-np.inf, exponent=1.5,
                       damping=20.0)
    assert bearing_contact_parameters(1e8, -2e-6, 1.0)["gap_hi"] == -2e-6   # preload


@pytest.mark.parametrize("bad,match", [(dict(exponent=0.5), "exponent"),
                                       (dict(stiffness=-1.0), "stiffness"),
                                       (dict(damping=-1.0), "damping"),
                                       (dict(clearance=np.inf), "clearance")])
def test_bearing_contact_parameters_reject_bad_input(bad, match):
    args = dict(stiffness=1e9, clearance=0.0, exponent=1.5)
    args.update(bad)
    with pytest.raises(ValueError, match=match):
        bearing_contact_parameters(**args)


def test_bearing_geometry_rejects_bad_input():
    for angles in ([], [[0.0, 1.0]], [0.0, np.nan]):
        with pytest.raises(ValueError, match="angles"):
            bearing_geometry(angles)


def bearing_forces(g, law, q_j, d_h=None):
    """Journal force F_j = -sum_k f_k journal_k, bore-point forces F_h[k] = -f_k housing_k
    and the journal tangent K = sum_k df_k/ddelta journal_k journal_k^T of the contact law
    on the element parameters (no velocities)."""
    d_h = np.zeros((g.n, 3)) if d_h is None else d_h
    delta = g.journal @ np.asarray(q_j, float) + np.einsum("kj,kj->k", g.housing, d_h)
    r = evaluate(delta, **law)
    return -g.journal.T @ r.force, -g.housing * r.force[:, None], \
        g.journal.T @ (r.stiffness[:, None] * g.journal)


@pytest.mark.parametrize("n", [3, 4, 5, 8, 13])
@pytest.mark.parametrize("direction", [0.0, 0.4, 2.0])
def test_bearing_preloaded_linear_radial_stiffness(n, direction):
    """All elements in contact (preload): radial stiffness sum k cos^2 = n k / 2, any direction."""
    k, pre, d = 1e8, 1e-5, 3e-6
    g = bearing_geometry(even(n, 0.1))
    u = np.array([np.cos(direction), np.sin(direction), 0.0])
    F_j, _, K = bearing_forces(g, bearing_contact_parameters(k, -pre, 1.0),
                               np.concatenate([d * u, np.zeros(3)]))
    np.testing.assert_allclose(F_j[:3], -n * k / 2 * d * u, rtol=1e-9, atol=1e-9 * k * d)
    np.testing.assert_allclose(K[:2, :2], n * k / 2 * np.eye(2), rtol=1e-12, atol=1e-6)
    assert not F_j[3:].any() and not K[2:].any()          # rotations and w do not enter


@pytest.mark.parametrize("n", [3, 4, 8])
def test_bearing_zero_clearance_loaded_half(n):
    """Zero clearance, contact loss: only elements with e_k . d > 0 carry load."""
    k, d = 1e8, 2e-6
    a = even(n, 0.2)
    g = bearing_geometry(a)
    F_j, F_h, K = bearing_forces(g, bearing_contact_parameters(k, 0.0, 1.0), [d, 0, 0, 0, 0, 0])
    c = np.cos(a)
    loaded = c > 0
    assert F_j[0] == pytest.approx(-k * d * np.sum(c[loaded] ** 2))
    assert K[0, 0] == pytest.approx(k * np.sum(c[loaded] ** 2))
    assert not F_h[~loaded].any()


def test_bearing_contact_loss_and_single_element():
    n, c, k = 8, 1e-5, 5e9
    g = bearing_geometry(even(n))
    law = bearing_contact_parameters(k, c, 1.5)
    rng = np.random.default_rng(7)
    for _ in range(5):                                   # |d| < c: no force at all
        v = rng.normal(size=2)
        q_j = np.concatenate([0.9 * c * v / np.linalg.norm(v), [3e-6], rng.normal(size=3)])
        F_j, F_h, K = bearing_forces(g, law, q_j, rng.normal(scale=1e-7, size=(n, 3)))
        assert not F_j.any() and not F_h.any() and not K.any()
    s = 2e-6                                             # c + s < c / cos(45 deg)
    F_j, F_h, K = bearing_forces(g, law, [c + s, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(F_j, [-k * s ** 1.5, 0, 0, 0, 0, 0], rtol=1e-12, atol=0)
    np.testing.assert_allclose(F_h[0], [k * s ** 1.5, 0, 0], rtol=1e-12, atol=0)
    assert not F_h[1:].any()
    assert K[0, 0] == pytest.approx(1.5 * k * s ** 0.5)


@pytest.mark.parametrize("helix,hand,sense", CASES)
def test_unequal_faces_mesh_at_the_overlap_centre_rigid_motion_deforms_nothing(helix, hand,
                                                                               sense):
    """Faces of unequal width whose centres differ: gear a's node at z = 0, gear b's at
    z = 0.012 m, the mesh at the overlap centre z = 0.005 m (offsets 0.005 and -0.007).  A
    small rigid rotation of the whole pair about a transverse axis through the origin
    (u = theta x r at each node, the same theta) and a rigid translation give no mesh
    deformation; without the offsets the rotation does (the contact point is then two
    different physical points)."""
    za, zb, zm = 0.0, 0.012, 0.005
    theta = np.array([1.3e-4, -0.7e-4, 0.4e-4])
    A = np.array([A_XY[0], A_XY[1], za])
    B = np.array([B_XY[0], B_XY[1], zb])

    def delta(g):
        qa = np.concatenate([np.cross(theta, A), theta])
        qb = np.concatenate([np.cross(theta, B), theta])
        return g.c_a @ qa + g.c_b @ qb

    g = gear_mesh_geometry(A_XY, B_XY, RA, RB, ALPHA, helix, hand, sense,
                           axial_offset_a=zm - za, axial_offset_b=zm - zb)
    assert abs(delta(g)) < 1e-15
    shift = np.array([3e-5, -2e-5, 1e-5])
    assert abs(g.c_a @ np.concatenate([shift, 0 * shift])
               + g.c_b @ np.concatenate([shift, 0 * shift])) < 1e-18
    plain = gear_mesh_geometry(A_XY, B_XY, RA, RB, ALPHA, helix, hand, sense)
    assert abs(delta(plain)) > 1e-7 * abs(theta).max()
