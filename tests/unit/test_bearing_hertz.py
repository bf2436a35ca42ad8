"""Bearings by geometry: ISO boundary dimensions of a designation, the element-set rule and
the Hertz contact constant (Harris point contact, Palmgren line contact), checked against
closed forms and published values."""
import math

import numpy as np
import pytest
from scipy.special import ellipe, ellipk

from vibrogear.config import ConfigError
from vibrogear.config.model.bearing_catalogue import boundary_dimensions, element_set
from vibrogear.models.gearbox.bearing_hertz import (PALMGREN_LINE, STEEL_E, STEEL_NU,
                                                    contact_constant, delta_star, ellipticity)


@pytest.mark.parametrize("designation, kind, dDB", [
    ("6210-2Z", "ball", (50, 90, 20)), ("6204", "ball", (20, 47, 14)),
    ("6305/C3", "ball", (25, 62, 17)), ("33014", "tapered", (70, 110, 31)),
    ("33012", "tapered", (60, 95, 27)), ("30205", "tapered", (25, 52, 16.25)),
    ("NU 210 E", "cylindrical", (50, 90, 20)), ("6000", "ball", (10, 26, 8))])
def test_iso_boundary_dimensions(designation, kind, dDB):
    """ISO 15 (6000, 6204, 6210, 6305, NU 210) and ISO 355 (30205, 33012, 33014) as the
    standards print them, in mm."""
    bd = boundary_dimensions(designation)
    assert bd.kind == kind
    assert (bd.d * 1e3, bd.D * 1e3, bd.B * 1e3) == pytest.approx(dDB, rel=1e-12)


def test_unknown_designation_names_the_field():
    with pytest.raises(ConfigError) as exc:
        boundary_dimensions("7210-B", "gearbox.bearings[0].designation")
    assert exc.value.path == "gearbox.bearings[0].designation"
    assert "boundary dimensions" in str(exc.value)


def test_sphere_on_plane_is_hertz_closed_form():
    """F = 0 (a sphere on a plane): kappa = 1, delta* = 1, and the approach of one contact
    equals Hertz's delta = (9 Q^2 / (16 E*^2 R))^(1/3), E* = E / (2 (1 - nu^2))."""
    assert ellipticity(0.0) == 1.0 and delta_star(0.0) == 1.0
    from vibrogear.models.gearbox.bearing_hertz import _approach_coefficient
    R, Q = 0.01, 500.0
    c = _approach_coefficient(2.0 / R, 0.0, STEEL_E, STEEL_NU)
    Es = STEEL_E / (2 * (1 - STEEL_NU ** 2))
    assert c * Q ** (2 / 3) == pytest.approx((9 * Q ** 2 / (16 * Es ** 2 * R)) ** (1 / 3),
                                             rel=1e-13)


@pytest.mark.parametrize("F", [0.3, 0.8, 0.9, 0.95])
def test_ellipticity_solves_the_curvature_equation(F):
    kappa = ellipticity(F)
    m = 1 - 1 / kappa ** 2
    assert ((kappa ** 2 + 1) * ellipe(m) - 2 * ellipk(m)) / ((kappa ** 2 - 1) * ellipe(m)) == \
        pytest.approx(F, abs=1e-12)


def test_harris_steel_coefficient_printed_digits():
    """Harris prints delta = 2.79e-4 delta* Q^(2/3) sum_rho^(1/3) [mm, N] for bearing steel
    (E = 2.075e5 N/mm^2, nu = 0.3); the general Hertz approach gives the same to the 3
    printed digits."""
    coef = 0.5 * (1.5 * 2 * (1 - STEEL_NU ** 2) / (STEEL_E / 1e6)) ** (2 / 3)
    assert f"{coef:.2e}" == "2.79e-04"


def test_palmgren_per_contact_constant_printed_digits():
    """Harris prints the line-contact constant of one contact as K = 8.06e4 l^(8/9)
    [N/mm^(10/9)] (from Palmgren's delta = 3.84e-5 Q^0.9 / l^0.8); two contacts in series
    give 8.06e4 / 2^(10/9)."""
    es = element_set("cylindrical", 0.0, 0.0, 0.0, count=12, element_diameter=0.01,
                     pitch_diameter=0.07, element_length=0.01, contact_angle=0.0)
    k = contact_constant(es)
    per_contact_mm = k.normal_stiffness / 1e3 ** (10 / 9) * 2 ** (10 / 9) / 10.0 ** (8 / 9)
    assert f"{per_contact_mm:.2e}" == "8.06e+04"
    assert (1 / PALMGREN_LINE) ** (10 / 9) == pytest.approx(per_contact_mm, rel=1e-12)


def test_delta_star_against_brewe_hamrock():
    """Brewe and Hamrock's (1977) fit of the Hertz ellipticity, kappa ~ 1.0339
    (Ry/Rx)^0.636 (error < 3 % for Ry/Rx in 1..100), with the curvature difference of
    radii ratio Ry/Rx: F = (Ry/Rx - 1) / (Ry/Rx + 1)."""
    for ratio in (2.0, 5.0, 10.0, 30.0):
        F = (ratio - 1) / (ratio + 1)
        assert ellipticity(F) == pytest.approx(1.0339 * ratio ** 0.636, rel=0.03)


def test_6210_contact_constant_and_rule():
    """6210: d = 50, D = 90, B = 20 mm; rule: D_w = 12 mm, d_m = 70 mm, Z = 10 (Conrad fill
    186 deg); Harris point contact with f_i = 0.52, f_o = 0.53."""
    bd = boundary_dimensions("6210-2Z")
    es = element_set(bd.kind, bd.d, bd.D, bd.B)
    assert es.count == 10 and es.element_diameter == pytest.approx(0.012)
    k = contact_constant(es)
    # independent evaluation of the same formulas in mm (Harris's unit system)
    dw, dm = 12.0, 70.0
    g = dw / dm
    def c(srho, F):
        return 2.79e-4 * delta_star(F) * srho ** (1 / 3)
    si = (4 - 1 / 0.52 + 2 * g / (1 - g)) / dw
    so = (4 - 1 / 0.53 - 2 * g / (1 + g)) / dw
    Fi = (1 / 0.52 + 2 * g / (1 - g)) / (4 - 1 / 0.52 + 2 * g / (1 - g))
    Fo = (1 / 0.53 - 2 * g / (1 + g)) / (4 - 1 / 0.53 - 2 * g / (1 + g))
    kn_mm = (c(si, Fi) + c(so, Fo)) ** -1.5
    assert k.stiffness == pytest.approx(kn_mm * 1e3 ** 1.5, rel=5e-3)   # 2.79e-4 is rounded
    assert k.exponent == 1.5


def test_tapered_contact_angle_reduces_radial_constant():
    """K = K_n cos(alpha)^(p + 1)."""
    es0 = element_set("tapered", 0.07, 0.11, 0.031, contact_angle=0.0)
    es12 = element_set("tapered", 0.07, 0.11, 0.031)
    k0, k12 = contact_constant(es0), contact_constant(es12)
    assert k12.stiffness == pytest.approx(k0.stiffness * math.cos(math.radians(12)) ** (19 / 9),
                                          rel=1e-12)
