"""ISO 6336-1:2006 method B against published and independently computed values.

References:

* ISO/TR 6336-30:2017, calculation example 1 (helical pair m_n = 8 mm, alpha_n = 20 deg,
  z = 17 / 103, b = 100 mm, x = 0.145 / 0, beta = 15.8 deg, a = 500 mm, basic rack profile
  D: h_aP = 1.0 m_n, h_fP = 1.4 m_n, solid blanks, line load 1273 N/mm > 100 N/mm).  Its
  published results (as tabulated in the ISO/TR and reproduced in gfsReboucas/Drivetrain,
  MATISO_6336.example_01): z_n = 18.905 / 114.543, c'_th = 17.85584, c' = 12.37047,
  c_gamma_alpha = 17.46485, c_gamma_beta = 14.84512 N/(mm um), Z_eps = 0.803.
* the textbook transverse contact ratio of a standard 20/20-tooth spur pair (20 deg,
  h_a = m): eps_alpha = 1.557 (e.g. Niemann/Winter, Maschinenelemente II), and the same
  closed form written out here.
* the limit z_n -> infinity, x = 0 of the flexibility polynomial: c'_th = 1 / C1.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from vibrogear.models.gearbox.iso6336 import (C_COEFFICIENTS, N_PER_MM_UM, contact_harmonics,
                                      contact_ratios, mesh_stiffness, theoretical_single_stiffness)

DEG = math.pi / 180.0


def _example_1(**kw):
    return mesh_stiffness(17, 103, 0.008, 0.100, alpha_n=20 * DEG, beta=15.8 * DEG, x1=0.145,
                          x2=0.0, addendum=1.0, dedendum=1.4, **kw)


def test_iso_tr_6336_30_example_1_stiffness():
    r = _example_1()
    assert r.zn1 == pytest.approx(18.905, abs=6e-4)
    assert r.zn2 == pytest.approx(114.543, abs=6e-4)
    # c'_th and c' are published to 7 significant digits
    assert r.c_th / N_PER_MM_UM == pytest.approx(17.85584, rel=1e-6)
    assert r.c_prime / N_PER_MM_UM == pytest.approx(12.37047, rel=1e-6)
    assert r.C_B == pytest.approx(0.9, rel=1e-14) and r.C_R == 1.0


def test_iso_tr_6336_30_example_1_contact_ratio_and_mesh_stiffness():
    """The example's centre distance a = 500 mm follows from x1 + x2 = 0.145 (zero
    backlash): our working centre distance must reproduce it.  The published c_gamma_alpha
    / c' gives eps_alpha = 1.54909; with a = 500 mm and d_a = d + 2 m_n (1 + x) we get
    1.54934: 1.6e-4 apart (the TR's tip diameters are given to 0.01 mm, not exactly
    d + 2 m_n (1 + x)), so the tolerance is 3e-4."""
    r = _example_1()
    assert r.working_centre_distance == pytest.approx(0.500, rel=1e-5)
    r500 = _example_1(centre_distance=0.500)
    eps_ref = (17.46485 / 12.37047 - 0.25) / 0.75
    assert r500.eps_alpha == pytest.approx(eps_ref, rel=3e-4)
    assert r500.c_gamma_alpha / N_PER_MM_UM == pytest.approx(17.46485, rel=3e-4)
    assert r500.c_gamma_beta / N_PER_MM_UM == pytest.approx(14.84512, rel=3e-4)
    # Z_eps = sqrt(1 / eps_alpha) for eps_beta >= 1, published 0.803
    assert r500.eps_beta == pytest.approx(100 * math.sin(15.8 * DEG) / (math.pi * 8), rel=1e-14)
    assert r500.eps_beta >= 1.0
    assert math.sqrt(1.0 / r500.eps_alpha) == pytest.approx(0.803, abs=5e-4)


def test_flexibility_polynomial_limit_is_one_over_c1():
    """z_n -> infinity, x = 0: q' = C1, c'_th = 1 / C1 = 21.17 N/(mm um); with C_M = 0.8
    and C_R = C_B = cos(beta) = 1 (h_fP = 1.2 m_n), c' = 0.8 / C1 = 16.94 N/(mm um)."""
    big = 1e12
    assert theoretical_single_stiffness(big, big) / N_PER_MM_UM == \
        pytest.approx(1.0 / 0.04723, rel=1e-9)
    r = mesh_stiffness(10**9, 10**9, 0.002, 0.02, dedendum=1.2)
    assert r.c_prime / N_PER_MM_UM == pytest.approx(0.8 / 0.04723, rel=1e-8)
    assert C_COEFFICIENTS[0] == 0.04723


def test_standard_spur_gears_give_the_isos_typical_14():
    """ISO 6336-1 method C takes c' = 14 N/(mm um) for solid steel spur gears with the
    standard basic rack; method B for a typical pair (20 / 100 teeth, x = 0,
    h_fP = 1.2 m_n) lands within 1 % of it."""
    r = mesh_stiffness(20, 100, 0.003, 0.03, dedendum=1.2)
    assert r.c_prime / N_PER_MM_UM == pytest.approx(14.0, rel=0.01)


def _eps_alpha_standard_spur(z1, z2, alpha):
    """Closed form for x = 0, h_a = m, module 1: the path of contact over the base pitch."""
    rb1, rb2 = 0.5 * z1 * math.cos(alpha), 0.5 * z2 * math.cos(alpha)
    ra1, ra2 = 0.5 * z1 + 1.0, 0.5 * z2 + 1.0
    g = math.sqrt(ra1**2 - rb1**2) + math.sqrt(ra2**2 - rb2**2) - 0.5 * (z1 + z2) * math.sin(alpha)
    return g / (math.pi * math.cos(alpha))


def test_transverse_contact_ratio_textbook_and_closed_form():
    eps, eps_b, alpha_wt, a_w = contact_ratios(20, 20, 0.004, 20 * DEG)
    assert eps == pytest.approx(1.557, abs=5e-4)
    assert eps_b == 0.0 and alpha_wt == pytest.approx(20 * DEG, rel=1e-14)
    assert a_w == pytest.approx(0.080, rel=1e-14)
    for z1, z2, a in ((17, 53, 20.0), (31, 97, 25.0), (40, 80, 14.5)):
        got = contact_ratios(z1, z2, 0.002, a * DEG)[0]
        assert got == pytest.approx(_eps_alpha_standard_spur(z1, z2, a * DEG), rel=1e-12)


def _rect_wave(eps_alpha, n):
    """k(t)/k_mean sampled at t_j = (j + 1/2)/n periods: double contact (1.75 c') on
    [0, eps_alpha - 1), single (c') after; the mean is c' (0.75 eps_alpha + 0.25)."""
    t = (np.arange(n) + 0.5) / n
    level = np.where(t < eps_alpha - 1.0, 1.75, 1.0)
    return t, level / (0.75 * eps_alpha + 0.25)


def _fft_harmonics(signal, count):
    X = np.fft.rfft(signal) / signal.size
    return 2 * X.real[1:count + 1], -2 * X.imag[1:count + 1]


@pytest.mark.parametrize("eps_alpha", [1.2, 1.4437, 1.65, 1.9])
def test_spur_harmonics_equal_the_fft_of_the_rectangular_wave(eps_alpha):
    n = 2**18
    t, wave = _rect_wave(eps_alpha, n)
    assert wave.mean() == pytest.approx(1.0, abs=2.0 / n)
    a_ref, b_ref = _fft_harmonics(wave, 6)
    a, b = contact_harmonics(eps_alpha, 0.0, 6)
    np.testing.assert_allclose(a, a_ref, atol=1e-5)
    np.testing.assert_allclose(b, b_ref, atol=1e-5)


@pytest.mark.parametrize("eps_alpha, eps_beta", [(1.55, 0.4), (1.7, 1.3), (1.3, 2.0)])
def test_helical_harmonics_equal_the_face_averaged_wave(eps_alpha, eps_beta):
    """Average over 400 face slices, slice s lagging by s eps_beta periods, then FFT."""
    n, slices = 2**14, 400
    _, wave = _rect_wave(eps_alpha, n)
    shifts = (np.arange(slices) + 0.5) / slices * eps_beta
    t = (np.arange(n) + 0.5) / n
    avg = np.zeros(n)
    for s in shifts:
        avg += np.interp((t - s) % 1.0, t, wave, period=1.0)
    avg /= slices
    a_ref, b_ref = _fft_harmonics(avg, 4)
    a, b = contact_harmonics(eps_alpha, eps_beta, 4)
    np.testing.assert_allclose(a, a_ref, atol=2e-3)
    np.testing.assert_allclose(b, b_ref, atol=2e-3)
    if float(eps_beta).is_integer():          # constant total contact-line length
        assert max(map(abs, a + b)) < 1e-15
