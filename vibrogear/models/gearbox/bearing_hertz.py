"""The Hertz contact constant of one rolling element from the bearing's geometry.

The contact law of a rolling element is Q = K delta^p (``models/contact_law.py``), Q the
element's radial force [N], delta its radial compression [m], p = 3/2 for balls (point
contact) and 10/9 for rollers (line contact).  K [N/m^p] follows from the element set
(:class:`vibrogear.config.model.bearing_catalogue.ElementSet`) by the standard formulas of
T. A. Harris, *Rolling Bearing Analysis* (ch. "Contact stress and deformation" and
"Distributed loads and deflections"):

Point contact (balls).  With gamma = D_w cos(alpha) / d_m and the groove conformities
f = r / D_w, the curvature sums and differences of the inner and outer contact are

    sum_rho_i = (4 - 1/f_i + 2 gamma / (1 - gamma)) / D_w,
    F_i = (1/f_i + 2 gamma / (1 - gamma)) / (4 - 1/f_i + 2 gamma / (1 - gamma)),
    sum_rho_o = (4 - 1/f_o - 2 gamma / (1 + gamma)) / D_w,
    F_o = (1/f_o - 2 gamma / (1 + gamma)) / (4 - 1/f_o - 2 gamma / (1 + gamma)).

The ellipticity kappa = a / b solves F = ((kappa^2 + 1) E - 2 K) / ((kappa^2 - 1) E), K and
E the complete elliptic integrals of modulus e^2 = 1 - 1/kappa^2, and the dimensionless
approach is delta* = (2 K / pi) (pi / (2 kappa^2 E))^(1/3) (1 for a sphere on a plane).
The approach of one contact is

    delta = (delta* / 2) (3 Q / (2 sum_rho) * 2 (1 - nu^2) / E_mod)^(2/3) sum_rho,

which for bearing steel (E_mod = 207.5 GPa, nu = 0.3) is Harris's
delta = 2.79e-4 delta* Q^(2/3) sum_rho^(1/3) [mm, N].  The two contacts act in series along
the contact normal: delta_n = (c_i + c_o) Q^(2/3), so K_n = (c_i + c_o)^(-3/2).

Line contact (rollers), Palmgren's formula for steel: delta = 3.84e-5 Q^0.9 / l^0.8 per
contact [mm, N], l the effective roller length [mm]; both contacts in series give
K_n = (l^0.8 / 7.68e-5)^(10/9) [N/mm^(10/9)] (per contact: 8.06e4 l^(8/9)).

Radial constant.  A contact angle alpha (tapered rollers, angular-contact balls) shares the
radial compression delta_r as delta_n = delta_r cos(alpha) and the force's radial part is
Q cos(alpha): K = K_n cos(alpha)^(p + 1).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

__all__ = ["HertzConstant", "contact_constant", "ball_contact", "ellipticity", "delta_star",
           "STEEL_E", "STEEL_NU", "PALMGREN_LINE"]

#: bearing steel (Harris's values) [Pa], [-]
STEEL_E, STEEL_NU = 2.075e11, 0.3
#: Palmgren's line-contact approach per contact, delta = c Q^0.9 / l^0.8 [mm, N]
PALMGREN_LINE = 3.84e-5


def _F_of_kappa(kappa: float) -> float:
    m = 1.0 - 1.0 / kappa ** 2
    K, E = ellipk(m), ellipe(m)
    return ((kappa ** 2 + 1.0) * E - 2.0 * K) / ((kappa ** 2 - 1.0) * E)


def ellipticity(F: float) -> float:
    """kappa = a / b of a Hertz point contact with curvature difference F (0 <= F < 1)."""
    if not 0.0 <= F < 1.0:
        raise ValueError(f"curvature difference F must lie in [0, 1), got {F}")
    if F < 1e-12:
        return 1.0
    return brentq(lambda k: _F_of_kappa(k) - F, 1.0 + 1e-9, 1e4, xtol=1e-14, rtol=1e-14)


def delta_star(F: float) -> float:
    """Harris's dimensionless contact approach delta* of curvature difference F."""
    kappa = ellipticity(F)
    if kappa == 1.0:
        return 1.0
    m = 1.0 - 1.0 / kappa ** 2
    K, E = ellipk(m), ellipe(m)
    return float(2.0 * K / math.pi * (math.pi / (2.0 * kappa ** 2 * E)) ** (1.0 / 3.0))


def _approach_coefficient(sum_rho: float, F: float, E_mod: float, nu: float) -> float:
    """c of delta = c Q^(2/3) for one point contact [m / N^(2/3)], SI units."""
    return (0.5 * delta_star(F) * (1.5 / sum_rho * 2.0 * (1.0 - nu ** 2) / E_mod) ** (2.0 / 3.0)
            * sum_rho)


def ball_contact(dw: float, dm: float, alpha_deg: float, fi: float, fo: float):
    """(sum_rho_i, F_i, sum_rho_o, F_o) of a ball in its grooves, SI units [1/m]."""
    g = dw * math.cos(math.radians(alpha_deg)) / dm
    a_i, a_o = 2 * g / (1 - g), 2 * g / (1 + g)
    den_i, den_o = 4 - 1 / fi + a_i, 4 - 1 / fo - a_o
    return den_i / dw, (1 / fi + a_i) / den_i, den_o / dw, (1 / fo - a_o) / den_o


@dataclass(frozen=True)
class HertzConstant:
    """K [N/m^p] of one element along the radial direction, its exponent and what set it."""
    stiffness: float
    exponent: float
    normal_stiffness: float       # K_n along the contact normal [N/m^p]
    method: str                   # the formula in words


def contact_constant(es, E_mod: float = STEEL_E, nu: float = STEEL_NU) -> HertzConstant:
    """The radial contact constant of one element of the element set ``es`` (an
    :class:`~vibrogear.config.model.bearing_catalogue.ElementSet`, SI units)."""
    cos_a = math.cos(math.radians(es.contact_angle))
    if es.kind == "ball":
        si, Fi, so, Fo = ball_contact(es.element_diameter, es.pitch_diameter, es.contact_angle,
                                      es.inner_conformity, es.outer_conformity)
        c = _approach_coefficient(si, Fi, E_mod, nu) + _approach_coefficient(so, Fo, E_mod, nu)
        kn, p = c ** -1.5, 1.5
        method = (f"Hertz point contact (Harris): F_i = {Fi:.4f}, F_o = {Fo:.4f}, "
                  f"delta*_i = {delta_star(Fi):.4f}, delta*_o = {delta_star(Fo):.4f}")
    else:
        l_mm = es.element_length * 1e3
        kn_mm = (l_mm ** 0.8 / (2.0 * PALMGREN_LINE)) ** (10.0 / 9.0)
        p = 10.0 / 9.0
        kn = kn_mm * 1e3 ** p
        method = f"Palmgren line contact: l = {l_mm:.4g} mm"
    return HertzConstant(float(kn * cos_a ** (p + 1.0)), p, float(kn),
                         method + (f", contact angle {es.contact_angle:g} deg"
                                   if es.contact_angle else ""))

