"""Unit tier: element and assembled matrices of the rotor (exact properties, hand totals)."""
from __future__ import annotations

import numpy as np
import pytest

from rotor_fixtures import rotor_from_dict
from vibrogear.models.rotor.model import dof_groups, master_modes
from vibrogear.models.rotor.elements import (cowper_shear_coefficient, rotation_generator,
                                             shaft_element_matrices)

STEEL = {"E": 2.1e11, "nu": 0.3, "rho": 7800.0}


def stepped_rotor(free_gear_k=0.0):
    """Stepped, partly hollow shaft with a disc, a free gear and two bearings."""
    return rotor_from_dict({
        "material": STEEL,
        "sections": [{"length": 0.2, "outer_diameter": 0.04, "elements": 3},
                     {"length": 0.5, "outer_diameter": 0.06, "inner_diameter": 0.03,
                      "elements": 5},
                     {"length": 0.3, "outer_diameter": 0.05, "elements": 4,
                      "material": {"E": 1.1e11, "nu": 0.34, "rho": 8900.0}}],
        "discs": [{"position": 0.7, "mass": 12.0, "Id": 0.05, "Ip": 0.09}],
        "free_gears": [{"position": 0.2, "outer_diameter": 0.15, "inner_diameter": 0.04,
                        "width": 0.03, "torsional_stiffness": free_gear_k}],
        "bearings": [{"position": 0.0, "kxx": 1e8, "kyy": 1e8},
                     {"position": 1.0, "kxx": 1e8, "kyy": 2e8, "kxy": 1e7, "kyx": -1e7}]})


def rigid_modes(model):
    """Analytic rigid-body motions: 3 translations, rotations about x, y, z (about z = 0)."""
    n, z = model.n_dofs, model.node_z
    idx = 6 * np.arange(z.size)
    r = np.zeros((n, 6))
    for k in range(3):
        r[idx + k, k] = 1.0
    r[idx + 1, 3], r[idx + 3, 3] = -z, 1.0          # about x: v = -z, phi = 1
    r[idx + 0, 4], r[idx + 4, 4] = z, 1.0           # about y: u = z, theta = 1
    r[idx + 5, 5] = 1.0                             # about z: psi = 1
    for j in model.free_gear_dofs:                  # free gears turn with the shaft
        r[j, 5] = 1.0
    return r


def test_element_symmetry_and_skew():
    el = shaft_element_matrices([0.1, 0.3], [0.05, 0.08], [0.0, 0.06], 2.1e11, 8.1e10, 7800,
                                0.3, internal_damping=1e-4)
    for a in (el.mass, el.stiffness, el.internal_damping):
        assert np.abs(a - a.transpose(0, 2, 1)).max() <= 1e-12 * np.abs(a).max()
    for a in (el.gyroscopic, el.circulatory):
        assert np.abs(a + a.transpose(0, 2, 1)).max() <= 1e-12 * np.abs(a).max()
        assert np.abs(a).max() > 0
    assert np.all(np.linalg.eigvalsh(el.mass) > 0)


def test_euler_bernoulli_limit_matches_hermite_matrices():
    """Phi -> 0 (G -> infinity): the element reduces to the textbook Hermite beam."""
    L, d, E, rho = 0.4, 0.03, 2e11, 7800.0
    el = shaft_element_matrices(L, d, 0.0, E, 1e30, rho, 0.3)
    A, I = np.pi * d ** 2 / 4, np.pi * d ** 4 / 64
    k = E * I / L ** 3 * np.array([[12, 6 * L, -12, 6 * L], [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                                   [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L * L, -6 * L, 4 * L * L]])
    mt = rho * A * L / 420 * np.array([[156, 22 * L, 54, -13 * L], [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                                       [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    mr = rho * I / (30 * L) * np.array([[36, 3 * L, -36, 3 * L], [3 * L, 4 * L * L, -3 * L, -L * L],
                                        [-36, -3 * L, 36, -3 * L], [3 * L, -L * L, -3 * L, 4 * L * L]])
    xz = np.ix_([0, 4, 6, 10], [0, 4, 6, 10])       # (u, theta) plane: slope du/dz = theta
    np.testing.assert_allclose(el.stiffness[0][xz], k, rtol=1e-12, atol=1e-9 * np.abs(k).max())
    np.testing.assert_allclose(el.mass[0][xz], mt + mr, rtol=1e-12, atol=1e-12 * np.abs(mt).max())
    # gyroscopic block (phi rows, theta columns) = polar rotary inertia matrix = 2 M_r (Friswell 5.9)
    t = np.array([1.0, -1.0, 1.0, -1.0])
    g = el.gyroscopic[0][np.ix_([1, 3, 7, 9], [0, 4, 6, 10])]
    np.testing.assert_allclose(g, -t[:, None] * 2 * mr, atol=1e-12 * np.abs(mr).max())


def test_cowper_shear_coefficient_solid_and_thin():
    assert cowper_shear_coefficient(1.0, 0.0, 0.3) == pytest.approx(6 * 1.3 / (7 + 1.8))
    assert cowper_shear_coefficient(1.0, 0.999999, 0.3) == pytest.approx(2 * 1.3 / (4 + 3 * 0.3),
                                                                         rel=1e-5)


def test_assembled_symmetry_and_skew():
    m = stepped_rotor()
    for a in (m.M, m.K, m.B):                      # bearings may be cross-coupled (kxy != kyx)
        d = a.toarray()
        assert np.abs(d - d.T).max() <= 1e-12 * max(np.abs(d).max(), 1)
    for a in (m.G, m.C):
        d = a.toarray()
        assert np.abs(d + d.T).max() <= 1e-12 * max(np.abs(d).max(), 1)


def test_rigid_body_null_space_free_shaft():
    m = stepped_rotor(free_gear_k=2e4)
    r = rigid_modes(m)
    kr = m.K @ r
    assert np.abs(kr).max() <= 1e-9 * np.abs(m.K).max()
    modes = master_modes(m, count=12)
    assert modes.n_rigid == 6
    assert modes.frequencies_hz[6] > 1.0
    v = modes.vectors
    n = v.shape[1]
    assert n in (12, 13)                                # 13: the 12th mode's pair is kept
    np.testing.assert_allclose(v.T @ (m.M @ v), np.eye(n), atol=1e-9)
    # the six rigid modes span the analytic rigid-body motions
    rb = v[:, :6]
    proj = rb @ (rb.T @ (m.M @ r))
    assert np.abs(proj - r).max() < 1e-8 * np.abs(r).max()


def test_free_gear_adds_one_torsional_dof_and_rigid_mode():
    m = stepped_rotor(free_gear_k=0.0)
    assert m.n_dofs == 6 * m.n_nodes + 1
    assert m.free_gear_dofs == (6 * m.n_nodes,)
    assert dof_groups(m)["torsional"][m.free_gear_dofs[0]]
    assert master_modes(m, count=10).n_rigid == 7     # decoupled gear rotation


def test_mass_and_inertia_sums_equal_hand_totals():
    m = stepped_rotor()
    r = rigid_modes(m)
    mass = r.T @ (m.M @ r)
    rho1, rho3 = 7800.0, 8900.0
    A = np.pi / 4 * np.array([0.04 ** 2, 0.06 ** 2 - 0.03 ** 2, 0.05 ** 2])
    I = np.pi / 64 * np.array([0.04 ** 4, 0.06 ** 4 - 0.03 ** 4, 0.05 ** 4])
    rho = np.array([rho1, rho1, rho3])
    z0, z1 = np.array([0.0, 0.2, 0.7]), np.array([0.2, 0.7, 1.0])
    gear_m = rho1 * np.pi / 4 * (0.15 ** 2 - 0.04 ** 2) * 0.03
    gear_ip = gear_m * (0.15 ** 2 + 0.04 ** 2) / 8
    gear_id = gear_ip / 2 + gear_m * 0.03 ** 2 / 12
    total = np.sum(rho * A * (z1 - z0)) + 12.0 + gear_m
    for k in range(3):
        assert mass[k, k] == pytest.approx(total, rel=1e-12)
    polar = np.sum(rho * 2 * I * (z1 - z0)) + 0.09 + gear_ip
    assert mass[5, 5] == pytest.approx(polar, rel=1e-12)
    # diametral inertia about the left end (z = 0): int rho (I + A z^2) dz + sum (Id + m z^2)
    diam = (np.sum(rho * (I * (z1 - z0) + A * (z1 ** 3 - z0 ** 3) / 3))
            + 0.05 + 12.0 * 0.7 ** 2 + gear_id + gear_m * 0.2 ** 2)
    assert mass[3, 3] == pytest.approx(diam, rel=1e-12)
    assert mass[4, 4] == pytest.approx(diam, rel=1e-12)


def test_circulatory_matrix_is_minus_eta_K_S():
    el = shaft_element_matrices(0.2, 0.05, 0.0, 2e11, 8e10, 7800, 0.3, internal_damping=3e-4)
    s = rotation_generator()
    k = el.stiffness[0]
    lat = np.zeros(12, bool)
    lat[[0, 1, 3, 4, 6, 7, 9, 10]] = True
    k_lat = k * np.outer(lat, lat)
    np.testing.assert_allclose(el.circulatory[0], -3e-4 * k_lat @ s, atol=1e-9)
    # isotropic lateral stiffness commutes with the rotation about the axis
    np.testing.assert_allclose(k_lat @ s, s @ k_lat, atol=1e-6 * np.abs(k_lat).max())


def test_master_modes_keep_whole_degenerate_pairs_in_a_reproducible_basis():
    """An axisymmetric shaft's bending modes come in pairs (two planes, one frequency).  A
    count that cuts a pair is raised by one: one plane alone would make the shaft
    anisotropic, and which combination of the planes survived was chosen by round-off (on
    gear_pair it changed with the BLAS thread count and moved frequencies by 0.5 %).  The
    basis of each degenerate cluster depends on the subspace only: a rotated basis of the
    same subspaces gives the same vectors."""
    from vibrogear.models.rotor.model import _canonical_basis, _cluster_bounds, lowest_modes
    m = stepped_rotor(free_gear_k=2e4)
    f_all, _ = lowest_modes(m.K, m.M, 30)
    f_all = np.where(f_all < 1e-3, 0.0, f_all)
    bounds = _cluster_bounds(f_all)
    pair = next((a, b) for a, b in bounds if b - a == 2 and a >= 6)
    cut = master_modes(m, count=pair[0] + 1)                # would keep one plane only
    assert cut.vectors.shape[1] == pair[1]
    assert cut.frequencies_hz[-1] == pytest.approx(cut.frequencies_hz[-2], rel=1e-7)
    exact = master_modes(m, count=pair[1])
    assert exact.vectors.shape[1] == pair[1]
    np.testing.assert_allclose(cut.vectors, exact.vectors, atol=1e-10 * np.abs(exact.vectors).max())
    # any orthogonal rotation inside each cluster (and any sign) maps to the same basis
    v = exact.vectors
    b = _cluster_bounds(exact.frequencies_hz)
    rng = np.random.default_rng(1)
    rotated = v.copy()
    for a, e in b:
        q, _ = np.linalg.qr(rng.standard_normal((e - a, e - a)))
        rotated[:, a:e] = v[:, a:e] @ q
    np.testing.assert_allclose(_canonical_basis(rotated, m.M, b), v,
                               atol=1e-9 * np.abs(v).max())
