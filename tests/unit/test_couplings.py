"""Unit tier: discrete couplings (gear mesh, rolling bearing, torsional) against closed forms,
invariances and central finite differences of their Jacobians."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from vibrogear.models.couplings import (bearing_forces, bearing_geometry, gear_mesh_forces,
                                        gear_mesh_geometry, linearised_stiffness, mesh_force,
                                        rolling_contact_force, static_mesh_stiffness,
                                        torsional_coupling, transmission_error)

RA, RB = 0.05, 0.08
ALPHA = np.radians(20.0)
BETA = np.radians(15.0)
A_XY = np.array([0.01, -0.02])
PHI_AB = 0.7                                  # direction of the centre line
B_XY = A_XY + (RA + RB) * np.array([np.cos(PHI_AB), np.sin(PHI_AB)])
LAW = dict(stiffness=4e8, backlash=2e-5, damping=1.5e3, stiffness_cos=(0.15, 0.03),
           stiffness_sin=(-0.05,), mesh_frequency=900.0, te_cos=(3e-6,), te_sin=(1e-6, 5e-7))
CASES = list(itertools.product([0.0, BETA, -BETA], [1, -1], [1, -1]))   # helix, hand, sense


def geometry(helix=0.0, hand=1, sense=1):
    return gear_mesh_geometry(A_XY, B_XY, RA, RB, ALPHA, helix, hand, sense)


def fd_jacobian(fun, x, h):
    """Central differences of a vector function, column by column."""
    x = np.asarray(x, float)
    cols = []
    for k in range(x.size):
        step = np.zeros_like(x)
        step[k] = h
        cols.append((np.ravel(fun(x + step)) - np.ravel(fun(x - step))) / (2.0 * h))
    return np.column_stack(cols)


def assert_jacobian(J, J_fd):
    scale = max(np.abs(J_fd).max(), np.abs(J).max(), 1e-300)
    np.testing.assert_allclose(J, J_fd, rtol=1e-6, atol=1e-6 * scale)


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


def test_mesh_force_closed_form():
    k, b, c = 2e8, 1e-5, 700.0
    delta = np.array([3e-6, 0.0, -4e-6, -b, -b - 2e-6])
    vel = np.array([0.1, 0.2, -0.3, 0.4, 0.5])
    f, df, dfd = mesh_force(delta, vel, 0.0, stiffness=k, backlash=b, damping=c)
    np.testing.assert_allclose(f, [k * 3e-6 + c * 0.1, 0, 0, 0, -k * 2e-6 + c * 0.5], rtol=1e-12)
    np.testing.assert_array_equal(df, [k, 0, 0, 0, k])
    np.testing.assert_array_equal(dfd, [c, 0, 0, 0, c])
    np.testing.assert_array_equal(static_mesh_stiffness(delta, k, b), [k, 0, 0, 0, k])
    # scalar in, scalar out
    f1, df1, _ = mesh_force(1e-6, 0.0, 0.0, stiffness=k, backlash=b)
    assert np.ndim(f1) == 0 and f1 == pytest.approx(k * 1e-6) and df1 == k


def test_mesh_stiffness_harmonics_closed_form():
    k, W, a, s = 1e8, 1000.0, (0.2, 0.1), (0.05, -0.02)
    # W t = 0: 1 + a1 + a2; W t = pi/2: cos(pi) = -1 for h = 2, sin(pi/2) = 1 for h = 1
    law = dict(stiffness=k, backlash=0.0, stiffness_cos=a, stiffness_sin=s, mesh_frequency=W)
    assert mesh_force(1.0, 0.0, 0.0, **law)[1] == pytest.approx(k * 1.3)
    assert mesh_force(1.0, 0.0, np.pi / (2 * W), **law)[1] == pytest.approx(k * (1 - 0.1 + 0.05))


@pytest.mark.parametrize("delta", [4e-6, -3e-5, -1e-5])
def test_mesh_force_finite_differences(delta):
    law = {k: v for k, v in LAW.items() if not k.startswith("te_")}
    t, v = 1.3e-3, 0.02
    f, df, dfd = mesh_force(delta, v, t, **law)
    F = lambda x: np.array([mesh_force(x[0], x[1], t, **law)[0]])      # noqa: E731
    assert_jacobian(np.array([[df, dfd]]), np.hstack([fd_jacobian(F, [delta, v], 1e-9)[:, :1],
                                                      fd_jacobian(F, [delta, v], 1e-3)[:, 1:]]))
    assert (df > 0) == (delta > 0 or delta < -law["backlash"])


def test_transmission_error():
    W, a, b = 500.0, (2e-6, 1e-6), (-1e-6,)
    t = np.linspace(0.0, 0.03, 7)
    e, e_dot = transmission_error(t, a, b, W)
    np.testing.assert_allclose(e, 2e-6 * np.cos(W * t) + 1e-6 * np.cos(2 * W * t)
                               - 1e-6 * np.sin(W * t), rtol=1e-12, atol=1e-20)
    h = 1e-7
    fd = (transmission_error(t + h, a, b, W)[0] - transmission_error(t - h, a, b, W)[0]) / (2 * h)
    np.testing.assert_allclose(e_dot, fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())
    assert transmission_error(0.3, (), (), W) == (0.0, 0.0)


@pytest.mark.parametrize("bad,match", [(dict(stiffness=0.0), "stiffness"),
                                       (dict(backlash=-1e-6), "backlash"),
                                       (dict(damping=-1.0), "damping"),
                                       (dict(mesh_frequency=np.nan), "mesh_frequency")])
def test_mesh_force_rejects_bad_input(bad, match):
    law = dict(stiffness=1e8, backlash=1e-5)
    law.update(bad)
    with pytest.raises(ValueError, match=match):
        mesh_force(1e-6, 0.0, 0.0, **law)


def state_with_delta(g, target, t, law, rng):
    """Random state whose deformation (with the TE) equals ``target``, set through psi_a."""
    q = rng.normal(scale=1e-5, size=12)
    qd = rng.normal(scale=1e-2, size=12)
    e, _ = transmission_error(t, law.get("te_cos", ()), law.get("te_sin", ()),
                              law.get("mesh_frequency", 0.0))
    q[5] += (target - (g.c @ q - e)) / g.c_a[5]
    return q, qd


@pytest.mark.parametrize("helix,hand,sense", CASES)
@pytest.mark.parametrize("target", [6e-6, -1e-5, -3.5e-5])       # front, gap, back flank
@pytest.mark.parametrize("variant", ["full", "plain"])
def test_gear_mesh_forces_finite_differences(helix, hand, sense, target, variant):
    g = geometry(helix, hand, sense)
    law = dict(LAW) if variant == "full" else dict(stiffness=LAW["stiffness"],
                                                   backlash=LAW["backlash"])
    t = 2.1e-3
    q, qd = state_with_delta(g, target, t, law, np.random.default_rng(4))
    F, K, D = gear_mesh_forces(g, q[:6], q[6:], qd[:6], qd[6:], t, **law)
    in_contact = target > 0 or target < -law["backlash"]
    assert bool(np.any(F != 0)) == in_contact
    if in_contact:
        assert_jacobian(K, -fd_jacobian(
            lambda x: gear_mesh_forces(g, x[:6], x[6:], qd[:6], qd[6:], t, **law)[0], q, 1e-9))
        # rank one, symmetric: K = k(t) c c^T
        assert np.linalg.matrix_rank(K, tol=1e-9 * np.abs(K).max()) == 1
        np.testing.assert_allclose(K, K.T, rtol=0, atol=1e-12 * np.abs(K).max())
    else:
        assert not K.any() and not D.any()
    if in_contact and law.get("damping", 0.0) > 0:
        assert_jacobian(D, -fd_jacobian(
            lambda x: gear_mesh_forces(g, q[:6], q[6:], x[:6], x[6:], t, **law)[0], qd, 1e-4))
    else:
        assert not D.any()


@pytest.mark.parametrize("helix,hand,sense", CASES)
def test_gear_mesh_forces_action_reaction(helix, hand, sense):
    g = geometry(helix, hand, sense)
    law = dict(stiffness=3e8, backlash=1e-5)
    q, qd = state_with_delta(g, 2e-6, 0.0, law, np.random.default_rng(5))
    F, _, _ = gear_mesh_forces(g, q[:6], q[6:], qd[:6], qd[6:], 0.0, **law)
    f = 3e8 * 2e-6
    np.testing.assert_allclose(F[6:9], f * g.normal, rtol=1e-9)       # on gear b along n
    np.testing.assert_allclose(F[0:3], -f * g.normal, rtol=1e-9)
    # both forces act at P: total moment about the origin vanishes
    A, B = np.array([*A_XY, 0.0]), np.array([*B_XY, 0.0])
    moment = F[3:6] + np.cross(A, F[0:3]) + F[9:12] + np.cross(B, F[6:9])
    assert np.abs(moment).max() < 1e-12 * f
    # the driven gear is pushed in its own sense of rotation (-sense), the driver braked
    assert np.sign(F[11]) == -sense and np.sign(F[5]) == -sense


def test_gear_mesh_forces_transmission_error_shifts_delta():
    g = geometry(BETA)
    law = dict(stiffness=2e8, backlash=1e-5, te_cos=(4e-6,), mesh_frequency=100.0)
    z = np.zeros(6)
    F, K, _ = gear_mesh_forces(g, z, z, z, z, 0.0, **law)             # delta = -e(0) = -4e-6
    assert not F.any() and not K.any()
    q_a = np.zeros(6)
    q_a[5] = 7e-6 / g.c_a[5]                                          # c.q = 7e-6, delta = 3e-6
    F, _, _ = gear_mesh_forces(g, q_a, z, z, z, 0.0, **law)
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


@pytest.mark.parametrize("n", [3, 4, 5, 8, 13])
@pytest.mark.parametrize("direction", [0.0, 0.4, 2.0])
def test_bearing_preloaded_linear_radial_stiffness(n, direction):
    """All elements in contact (preload): radial stiffness sum k cos^2 = n k / 2, any direction."""
    k, pre, d = 1e8, 1e-5, 3e-6
    g = bearing_geometry(even(n, 0.1))
    u = np.array([np.cos(direction), np.sin(direction), 0.0])
    q_j = np.concatenate([d * u, np.zeros(3)])
    z = np.zeros((n, 3))
    F_j, F_h, K = bearing_forces(g, q_j, z, np.zeros(6), z, clearance=-pre, stiffness=k,
                                 exponent=1.0)
    np.testing.assert_allclose(F_j[:3], -n * k / 2 * d * u, rtol=1e-9, atol=1e-9 * k * d)
    np.testing.assert_allclose(K[:2, :2], n * k / 2 * np.eye(2), rtol=1e-12, atol=1e-6)


@pytest.mark.parametrize("n", [3, 4, 8])
def test_bearing_zero_clearance_loaded_half(n):
    """Zero clearance, contact loss: only elements with e_k . d > 0 carry load."""
    k, d = 1e8, 2e-6
    a = even(n, 0.2)
    g = bearing_geometry(a)
    z = np.zeros((n, 3))
    F_j, F_h, K = bearing_forces(g, [d, 0, 0, 0, 0, 0], z, np.zeros(6), z, clearance=0.0,
                                 stiffness=k, exponent=1.0)
    c = np.cos(a)
    loaded = c > 0
    assert F_j[0] == pytest.approx(-k * d * np.sum(c[loaded] ** 2))
    assert K[0, 0] == pytest.approx(k * np.sum(c[loaded] ** 2))
    assert not F_h[~loaded].any()


def test_bearing_contact_loss_and_single_element():
    n, c, k = 8, 1e-5, 5e9
    g = bearing_geometry(even(n))
    z = np.zeros((n, 3))
    rng = np.random.default_rng(7)
    for _ in range(5):                                   # |d| < c: no force at all
        v = rng.normal(size=2)
        q_j = np.concatenate([0.9 * c * v / np.linalg.norm(v), [3e-6], rng.normal(size=3)])
        F_j, F_h, K = bearing_forces(g, q_j, z, np.zeros(6), z, clearance=c, stiffness=k,
                                     exponent=1.5)
        assert not F_j.any() and not F_h.any() and not K.any()
    s = 2e-6                                             # c + s < c / cos(45 deg)
    F_j, F_h, K = bearing_forces(g, [c + s, 0, 0, 0, 0, 0], z, np.zeros(6), z, clearance=c,
                                 stiffness=k, exponent=1.5)
    np.testing.assert_allclose(F_j, [-k * s ** 1.5, 0, 0, 0, 0, 0], rtol=1e-12, atol=0)
    np.testing.assert_allclose(F_h[0], [k * s ** 1.5, 0, 0], rtol=1e-12, atol=0)
    assert not F_h[1:].any()
    assert K[0, 0] == pytest.approx(1.5 * k * s ** 0.5)


@pytest.mark.parametrize("exponent", [1.0, 1.5, 10 / 9])
@pytest.mark.parametrize("damping,axial", [(0.0, 0.0), (2e3, 3e7)])
@pytest.mark.parametrize("clearance", [-2e-6, 0.0, 3e-6])
def test_bearing_forces_finite_differences(exponent, damping, axial, clearance):
    n = 7
    g = bearing_geometry(even(n, 0.3))
    rng = np.random.default_rng(8)
    q_j = np.concatenate([[6e-6, -2e-6, 1e-6], rng.normal(scale=1e-3, size=3)])
    d_h = rng.normal(scale=1e-6, size=(n, 3))
    qd_j, dd_h = rng.normal(scale=1e-3, size=6), rng.normal(scale=1e-3, size=(n, 3))
    law = dict(clearance=clearance, stiffness=1e9, exponent=exponent, damping=damping,
               axial_stiffness=axial, w_h=-4e-6)
    delta = g.journal @ q_j + np.einsum("kj,kj->k", g.housing, d_h) - clearance
    assert np.abs(delta).min() > 1e-7                   # away from the contact kinks
    assert 0 < np.sum(delta > 0) < n                    # partial contact

    def forces(x):
        F_j, F_h, _ = bearing_forces(g, x[:6], x[6:].reshape(n, 3), qd_j, dd_h, **law)
        return np.concatenate([F_j, F_h.ravel()])

    x = np.concatenate([q_j, d_h.ravel()])
    F_j, F_h, K = bearing_forces(g, q_j, d_h, qd_j, dd_h, **law)
    assert_jacobian(K, -fd_jacobian(forces, x, 1e-10))
    # the axial spring alone: F_j[2] = -k_a (w - w_h); the radial forces balance
    assert F_j[2] == pytest.approx(-axial * (q_j[2] + 4e-6), abs=1e-12)
    np.testing.assert_allclose(F_j[:2] + F_h[:, :2].sum(0), 0.0, atol=1e-12 * np.abs(F_h).max())
    assert not F_j[3:].any()
    # damping only in loaded elements: f_k = k delta^p + c delta'
    d_dot = g.journal @ qd_j + np.einsum("kj,kj->k", g.housing, dd_h)
    f = np.where(delta > 0, 1e9 * np.clip(delta, 0, None) ** exponent + damping * d_dot, 0.0)
    np.testing.assert_allclose(F_h, g.directions * f[:, None], rtol=1e-12, atol=1e-15)


def test_rolling_contact_force_and_linearisation():
    d = np.array([-1e-6, 0.0, 2e-6, 5e-6])
    for p in (1.0, 1.5, 10 / 9):
        f, df, dfd = rolling_contact_force(d, stiffness=2e9, exponent=p, damping=10.0,
                                           delta_dot=0.5)
        np.testing.assert_allclose(f, np.where(d > 0, 2e9 * np.abs(d) ** p + 5.0, 0.0),
                                   rtol=1e-12)
        np.testing.assert_array_equal(dfd, np.where(d > 0, 10.0, 0.0))
        lin = linearised_stiffness(d, 2e9, p)
        np.testing.assert_array_equal(lin, df)
        h = 1e-11
        fd = (rolling_contact_force(d[2:] + h, stiffness=2e9, exponent=p)[0]
              - rolling_contact_force(d[2:] - h, stiffness=2e9, exponent=p)[0]) / (2 * h)
        np.testing.assert_allclose(lin[2:], fd, rtol=1e-6)
        assert not lin[:2].any()
    assert linearised_stiffness(4e-6, 1e9, 1.5) == pytest.approx(1.5e9 * 2e-3)


def _bearing(n_h=4, q_j=np.zeros(6), **kw):
    law = dict(clearance=0.0, stiffness=1e9, exponent=1.5)
    law.update(kw)
    return bearing_forces(bearing_geometry(even(4)), q_j, np.zeros((n_h, 3)), np.zeros(6),
                          np.zeros((4, 3)), **law)


@pytest.mark.parametrize("call,match", [
    (lambda: rolling_contact_force(1e-6, stiffness=1e9, exponent=0.5), "exponent"),
    (lambda: rolling_contact_force(1e-6, stiffness=-1.0, exponent=1.5), "stiffness"),
    (lambda: rolling_contact_force(1e-6, stiffness=1e9, exponent=1.5, damping=-1), "damping"),
    (lambda: bearing_geometry([]), "angles"), (lambda: bearing_geometry([[0.0, 1.0]]), "angles"),
    (lambda: _bearing(n_h=3), "d_h"), (lambda: _bearing(q_j=np.zeros(5)), "q_j"),
    (lambda: _bearing(axial_stiffness=-1.0), "axial_stiffness"),
    (lambda: _bearing(clearance=np.inf), "clearance"),
    (lambda: torsional_coupling(-1.0, 0.1, 0.0), "stiffness"),
    (lambda: torsional_coupling(1.0, 0.1, 0.0, damping=-2.0), "damping")])
def test_bearing_and_torsion_reject_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_torsional_coupling():
    k, c, twist = 2e4, 15.0, 0.03
    T, dT, dTd = torsional_coupling(k, twist, 0.01, 2.0, c)
    assert T == pytest.approx(k * 0.02 - c * 2.0)
    fd = fd_jacobian(lambda x: torsional_coupling(k, twist, x[0], x[1], c)[0], [0.01, 2.0], 1e-6)
    assert_jacobian(np.array([[dT, dTd]]), fd)
    # static load set by the twist: zero torque at psi = twist, and vectorised over psi
    np.testing.assert_allclose(torsional_coupling(k, twist, np.array([twist, 0.0]))[0],
                               [0.0, k * twist])
