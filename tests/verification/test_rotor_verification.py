"""Verification tier: closed forms, observed convergence orders, published rotordynamics.

Published values: Friswell, Penny, Garvey & Lees, *Dynamics of Rotating Machines*, Cambridge
University Press (2010), chapter 5 worked examples, as tabulated (in rad/s) by the ROSS test
suite, petrobras/ross ``ross/tests/test_examples.py`` (rotor_example1..4), which checks them
at rtol 1e-3 (1e-2 for the damped example).  The book's models use six Timoshenko elements
(48 for Example 5.9.2) and 4 lateral DOFs per node; ours also carries axial and torsional
DOFs, which are decoupled, so the lateral modes are compared.
"""
from __future__ import annotations

import numpy as np
import pytest

from rotor_fixtures import friswell_overhung, friswell_two_disc, rotor_from_dict
from vibrogear.models.rotor.model import assemble_rotor, master_modes
from vibrogear.solvers.rotor.modes import rotor_modes

E, NU, RHO = 2.1e11, 0.3, 7800.0
G = E / (2 * (1 + NU))


def shaft(length, d, elements, **extra):
    return rotor_from_dict({"material": {"E": E, "nu": NU, "rho": RHO},
                            "sections": [{"length": length, "outer_diameter": d,
                                          "elements": elements}], **extra})


def lateral(res, n):
    idx = [i for i, t in enumerate(res.mode_type) if t == "lateral"][:n]
    return res.frequencies_hz[idx] * 2 * np.pi, [res.whirl[i] for i in idx], idx


def plane_modes(model, pinned: bool, n: int):
    """Lowest bending frequencies [Hz] of the (u, theta) plane, pinned-pinned or free-free."""
    import scipy.linalg as sla
    idx = np.concatenate([6 * np.arange(model.n_nodes), 6 * np.arange(model.n_nodes) + 4])
    if pinned:
        idx = idx[~np.isin(idx, [0, 6 * (model.n_nodes - 1)])]
    k = model.K.toarray()[np.ix_(idx, idx)]
    m = model.M.toarray()[np.ix_(idx, idx)]
    lam = sla.eigh(k, m, eigvals_only=True)
    f = np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)
    return f[f > 1.0][:n]


def timoshenko_pinned_hz(n, length, d):
    """Exact simply supported Timoshenko beam: EI k^4 - rho A w^2 - rho I (1 + E/(kappa G))
    k^2 w^2 + rho^2 I/(kappa G) w^4 = 0, k = n pi / L (lower root)."""
    A, I = np.pi * d ** 2 / 4, np.pi * d ** 4 / 64
    kappa = 6 * (1 + NU) / (7 + 6 * NU)
    k = n * np.pi / length
    a = RHO ** 2 * I / (kappa * G)
    b = -(RHO * A + RHO * I * (1 + E / (kappa * G)) * k ** 2)
    c = E * I * k ** 4
    w2 = (-b - np.sqrt(b * b - 4 * a * c)) / (2 * a)
    return np.sqrt(w2) / (2 * np.pi)


def euler_free_free_hz(length, d, n):
    beta_l = np.array([4.730040745, 7.853204624, 10.995607838, 14.137165491])[:n]
    A, I = np.pi * d ** 2 / 4, np.pi * d ** 4 / 64
    return beta_l ** 2 / (2 * np.pi * length ** 2) * np.sqrt(E * I / (RHO * A))


def slope(h, err):
    return np.polyfit(np.log(h), np.log(err), 1)[0]


def test_stocky_pinned_pinned_timoshenko_closed_form_and_order():
    """L/d = 5: shear and rotary inertia matter (Euler would be off by ~10 %).  The element's
    shear strain is constant per element, so frequencies converge at order 2 here."""
    L, d = 0.5, 0.1
    exact = np.array([timoshenko_pinned_hz(n, L, d) for n in (1, 2, 3)])
    errs, hs = [], []
    for ne in (8, 16, 32):
        f = plane_modes(shaft(L, d, ne), True, 3)
        errs.append(np.abs(f / exact - 1))
        hs.append(L / ne)
    errs = np.array(errs)
    assert errs[-1].max() < 1.5e-3
    for k in range(3):
        assert 1.9 < slope(hs, errs[:, k]) < 2.1


def test_shear_rigid_limit_rayleigh_beam_order_four():
    """G -> infinity: the element is the Hermite (Rayleigh) beam; simply supported closed
    form w^2 = E I k^4 / (rho A + rho I k^2) and frequency convergence of order 4."""
    L, d = 1.0, 0.05
    A, I = np.pi * d ** 2 / 4, np.pi * d ** 4 / 64
    k = np.arange(1, 4) * np.pi / L
    exact = np.sqrt(E * I * k ** 4 / (RHO * A + RHO * I * k ** 2)) / (2 * np.pi)
    errs, hs = [], []
    for ne in (4, 8, 16):
        model = assemble_rotor(node_z=np.linspace(0, L, ne + 1), elem_outer_d=d, elem_inner_d=0.0,
                               elem_E=E, elem_G=1e30, elem_rho=RHO, elem_nu=NU)
        errs.append(np.abs(plane_modes(model, True, 3) / exact - 1))
        hs.append(L / ne)
    errs = np.array(errs)
    assert errs[-1].max() < 1e-4
    for k in range(3):
        assert 3.7 < slope(hs, errs[:, k]) < 4.3


def test_slender_free_free_euler_limit():
    """L/d = 100: the Timoshenko element tends to the Euler-Bernoulli closed form."""
    L, d = 2.0, 0.02
    f = plane_modes(shaft(L, d, 40), False, 3)
    rel = np.abs(f / euler_free_free_hz(L, d, 3) - 1)
    assert rel.max() < 2e-3           # shear + rotary inertia ~ (n pi r / L)^2 ~ 1e-3


def test_axial_and_torsional_bar_frequencies_order_two():
    L, d = 1.0, 0.05
    c_ax, c_t = np.sqrt(E / RHO), np.sqrt(G / RHO)
    errs_a, errs_t, hs = [], [], []
    for ne in (20, 40, 80):
        mm = master_modes(shaft(L, d, ne), count=60)
        f = mm.frequencies_hz
        fa = f[np.argmin(np.abs(f - c_ax / (2 * L)))]
        ft = f[np.argmin(np.abs(f - c_t / (2 * L)))]
        errs_a.append(abs(fa / (c_ax / (2 * L)) - 1))
        errs_t.append(abs(ft / (c_t / (2 * L)) - 1))
        hs.append(L / ne)
    assert errs_a[-1] < 1e-4 and errs_t[-1] < 1e-4
    assert 1.8 < slope(hs, errs_a) < 2.2
    assert 1.8 < slope(hs, errs_t) < 2.2


# Friswell et al. (2010) Example 5.9.1 (p. 206), 6 elements, via ROSS test_examples.py [rad/s]
EX591_0 = [86.66, 86.66, 274.31, 274.31, 716.78, 716.78]
EX591_4000 = [85.39, 87.80, 251.78, 294.71, 600.18, 827.08]


@pytest.mark.parametrize("rpm, published", [(0.0, EX591_0), (4000.0, EX591_4000)])
def test_friswell_5_9_1_isotropic_bearings(rpm, published):
    res = rotor_modes(friswell_two_disc(6), rpm, count=10)
    w, whirl, _ = lateral(res, 6)
    np.testing.assert_allclose(w, published, rtol=1e-3)
    if rpm > 0:
        assert whirl == ["backward", "forward"] * 3


def test_friswell_5_9_2_anisotropic_bearings():
    """Example 5.9.2 (p. 208): kxx = 1 MN/m, kyy = 0.8 MN/m, discs at L/3 and 2L/3, 48 elements."""
    m = friswell_two_disc(48, kyy=8e5)
    w0, _, _ = lateral(rotor_modes(m, 0.0, count=10), 6)
    np.testing.assert_allclose(w0, [82.65, 86.66, 254.52, 274.31, 679.49, 716.79], rtol=1e-3)
    w4, _, _ = lateral(rotor_modes(m, 4000.0, count=10), 6)
    np.testing.assert_allclose(w4, [82.33, 86.86, 239.64, 287.25, 583.49, 806.89], rtol=1e-3)


def test_friswell_5_9_5_damped_bearings():
    """Example 5.9.5 (p. 212): 5.9.1 with 3 kNs/m bearing damping; published to 1e-2."""
    m = friswell_two_disc(6, c=3e3)
    res = rotor_modes(m, 0.0, count=10)
    _, _, idx = lateral(res, 6)
    np.testing.assert_allclose(res.natural_frequencies_hz[idx],
                               [13.91, 13.91, 48.18, 48.18, 137.06, 137.06], rtol=1e-2)
    np.testing.assert_allclose(res.frequencies_hz[idx],
                               [13.89, 13.89, 46.54, 46.54, 103.22, 103.22], rtol=1e-2)


@pytest.mark.parametrize("rpm, published", [
    (0.0, [90.14, 90.14, 630.73, 630.73, 830.43, 830.43]),
    (4000.0, [76.19, 103.91, 565.99, 634.23, 647.75, 1174.2])])
def test_friswell_5_9_9_overhung_rotor(rpm, published):
    """Example 5.9.9 (p. 218): overhung disc, bearings 10 MN/m at 0 and 1 m; 6 elements."""
    w, _, _ = lateral(rotor_modes(friswell_overhung(6), rpm, count=12), 6)
    np.testing.assert_allclose(w, published, rtol=1e-3)


def test_gyroscopic_splitting_forward_rises_backward_falls():
    m = friswell_overhung(6)
    lines = [lateral(rotor_modes(m, rpm, count=6), 2) for rpm in (1000, 2000, 3000, 4000)]
    back = [w[0] for w, wl, _ in lines]
    fwd = [w[1] for w, wl, _ in lines]
    assert all(wl == ["backward", "forward"] for _, wl, _ in lines)
    assert np.all(np.diff(fwd) > 0) and np.all(np.diff(back) < 0)


def test_rigid_rotor_conical_whirl_closed_form():
    """Disc (m, Id, Ip) at the middle of a rigid, massless shaft of length 2a on isotropic
    bearings k: cylindrical w^2 = 2k/m; conical w = +-Ip W/(2 Id) + sqrt((Ip W/(2 Id))^2
    + 2 k a^2 / Id), the + root forward."""
    a, k, mass, i_d, i_p = 0.3, 1e6, 20.0, 0.3, 0.5
    m = rotor_from_dict({
        "material": {"E": 2.1e13, "nu": 0.3, "rho": 1e-2},     # rigid and (almost) massless
        "sections": [{"length": 2 * a, "outer_diameter": 0.1, "elements": 2}],
        "discs": [{"position": a, "mass": mass, "Id": i_d, "Ip": i_p}],
        "bearings": [{"position": z, "kxx": k, "kyy": k} for z in (0.0, 2 * a)]})
    for rpm in (0.0, 3000.0, 12000.0):
        W = rpm * np.pi / 30
        res = rotor_modes(m, rpm, count=4, method="full")
        w, whirl, _ = lateral(res, 4)
        h = i_p * W / (2 * i_d)
        root = np.sqrt(h * h + 2 * k * a * a / i_d)
        expected = np.sort([np.sqrt(2 * k / mass)] * 2 + [root - h, root + h])
        np.testing.assert_allclose(w, expected, rtol=1e-4)
        if rpm > 0:
            labels = dict(zip(np.round(w, 6), whirl))
            assert labels[np.round(w[np.argmin(np.abs(w - (root + h)))], 6)] == "forward"
            assert labels[np.round(w[np.argmin(np.abs(w - (root - h)))], 6)] == "backward"


def test_internal_damping_instability_threshold_jeffcott():
    """Disc (no inertia) at mid-span of a massless shaft on rigid bearings, internal damping
    eta and external damping c_e at the disc: unstable above W = w_n (1 + c_e / (eta k))."""
    L, d, eta, mass, c_e = 1.0, 0.03, 2e-4, 50.0, 40.0
    I = np.pi * d ** 4 / 64
    kappa = 6 * (1 + NU) / (7 + 6 * NU)
    k_shaft = 1 / (L ** 3 / (48 * E * I) + L / (4 * kappa * G * np.pi * d ** 2 / 4))
    m = rotor_from_dict({
        "material": {"E": E, "nu": NU, "rho": 1e-2, "internal_damping": eta},
        "sections": [{"length": L, "outer_diameter": d, "elements": 4}],
        "discs": [{"position": L / 2, "mass": mass, "Id": 0.0, "Ip": 0.0}],
        "bearings": [{"position": 0.0, "kxx": 1e11, "kyy": 1e11, "kzz": 1e9},
                     {"position": L / 2, "cxx": c_e, "cyy": c_e},
                     {"position": L, "kxx": 1e11, "kyy": 1e11}]})
    wn = np.sqrt(k_shaft / mass)
    expected_rpm = wn * (1 + c_e / (eta * k_shaft)) * 30 / np.pi

    def growth(rpm):
        res = rotor_modes(m, rpm, count=2, method="full")
        return -np.min(res.damping_ratios)

    lo, hi = 0.5 * expected_rpm, 2.0 * expected_rpm
    assert growth(lo) < 0 < growth(hi)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if growth(mid) < 0 else (lo, mid)
    assert 0.5 * (lo + hi) == pytest.approx(expected_rpm, rel=1e-4)


def test_reduced_method_matches_full_eigensolution():
    m = friswell_two_disc(24, kyy=8e5, kxy=2e5, c=500.0)
    a = rotor_modes(m, 6000.0, count=10, method="full")
    b = rotor_modes(m, 6000.0, count=10)
    np.testing.assert_allclose(b.frequencies_hz, a.frequencies_hz, rtol=1e-5)
    np.testing.assert_allclose(b.damping_ratios, a.damping_ratios, atol=2e-6)
    assert b.status == "ok"
    true_err = np.max(np.abs(b.eigenvalues - a.eigenvalues) / np.abs(a.eigenvalues))
    assert true_err <= b.error_estimate < 1e-4        # the estimate is conservative
