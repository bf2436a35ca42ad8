"""The Hertz point-contact chain of ``bearing_hertz`` against a published bearing: Harris &
Mindel (1973), Fig. 15.

Source.  T. A. Harris and M. H. Mindel, "Rolling element bearing dynamics", Wear 23 (1973)
311-337, Fig. 15: the printed sample output of SKF's bearing program for an angular-contact
ball bearing (values as transcribed, with the figure's page and a re-read of the scan, in a
public Rust bearing solver on GitHub, tests/contact_level_b3.rs).

Printed inputs: Z = 21 balls of D = 0.8125 in on a pitch diameter of 6.2008 in, groove
conformities f_i = f_o = 0.5200, ring modulus 2.96e7 psi, Poisson's ratio 0.25 (the ball's
modulus is not printed).  Printed results for the ball at azimuth 0 (24 000 rpm: the ball's
centrifugal force splits the two contact angles):

    contact  angle [deg]  Q [lbf]     a [in]      b [in]      delta [in]   p_max [psi]
    inner    29.762       2.8776e2    7.8504e-2   8.9653e-3   4.0335e-4    1.9522e5
    outer    14.475       5.7107e2    9.6824e-2   1.2801e-2   (not legible) 2.1999e5

What we take as given: the printed angle and load of each contact; our curvature sums and
differences (``ball_contact``), exact Hertz ellipticity and delta* (``ellipticity``,
``delta_star``) and approach coefficient then give a, b, delta and p_max.  With an
effective contact modulus of E = 2.90e7 psi on both bodies (nu = 0.25) every legible size
agrees to its printed digits (half a unit in the fifth) except the inner minor axis b_i,
2 units off in the fifth digit.  Two facts make both points more than a fit:

* the modulus is the only free number, and it enters a and b as E^(-1/3), delta as
  E^(-2/3), p_max as E^(2/3): with the printed ring modulus 2.96e7 psi every a and b is low
  by exactly (2.90/2.96)^(1/3) and delta_i by its square, the signature of the elastic
  constant and of nothing in the geometry (a curvature-sum error would move a and delta in
  opposite directions);
* quantities free of the modulus (a/b, delta/a^2) agree with no number chosen at all.

b_i: the printed p_max_i is 3 Q / (2 pi a b) of the program's own a and b; with the
printed a_i it implies b_i = 8.9651e-3 in, which is ours, whereas the printed 8.9653e-3
misses p_max_i by 2e-5 (the transcription itself reports another misread digit).  So b_i is
asserted to 2.5 units of its fifth digit and through p_max_i to half a unit.

The designation path is not part of this check: the bearing (4.93 x 7.48 x 1.28 in, an
angular-contact bearing of ISO dimension series 10) is outside the built-in ISO table, and
its internal geometry differs from the element-set rule of ``bearing_catalogue``.
"""
import math

import pytest
from scipy.special import ellipe

from vibrogear.config.bearing_catalogue import ElementSet
from vibrogear.models.gearbox.bearing_hertz import (_approach_coefficient, ball_contact,
                                                    contact_constant, ellipticity)

IN, LBF = 0.0254, 4.4482216152605           # [m], [N] (exact / NIST)
PSI = LBF / IN ** 2                          # [Pa]
Z, D_IN, DM_IN, CONFORMITY, NU = 21, 0.8125, 6.2008, 0.52, 0.25
E_CONTACT_PSI, E_RING_PRINTED_PSI = 2.90e7, 2.96e7

# (contact angle [deg], Q [lbf], a [in], b [in], delta [in] or None, p_max [psi])
INNER = (29.762, 2.8776e2, 7.8504e-2, 8.9653e-3, 4.0335e-4, 1.9522e5)
OUTER = (14.475, 5.7107e2, 9.6824e-2, 1.2801e-2, None, 2.1999e5)


def half_unit(printed: float, digits: int = 5) -> float:
    """Half a unit in the last of ``digits`` significant digits, relative to ``printed``."""
    return 0.5 * 10.0 ** (math.floor(math.log10(abs(printed))) - digits + 1) / abs(printed)


def contact(which: str, e_psi: float = E_CONTACT_PSI):
    """(a, b, delta, p_max) [in, in, in, psi] and kappa of one contact by our formulas."""
    alpha, q_lbf = (INNER if which == "inner" else OUTER)[:2]
    si, Fi, so, Fo = ball_contact(D_IN * IN, DM_IN * IN, alpha, CONFORMITY, CONFORMITY)
    srho, F = (si, Fi) if which == "inner" else (so, Fo)
    E, Q = e_psi * PSI, q_lbf * LBF
    kappa = ellipticity(F)
    a_star = (2.0 * kappa ** 2 * ellipe(1.0 - 1.0 / kappa ** 2) / math.pi) ** (1.0 / 3.0)
    scale = (3.0 * Q / (2.0 * srho) * 2.0 * (1.0 - NU ** 2) / E) ** (1.0 / 3.0)
    a, b = a_star * scale, a_star / kappa * scale
    delta = _approach_coefficient(srho, F, E, NU) * Q ** (2.0 / 3.0)
    p_max = 3.0 * Q / (2.0 * math.pi * a * b)
    return a / IN, b / IN, delta / IN, p_max / PSI, kappa


@pytest.mark.parametrize("which", ["inner", "outer"])
def test_printed_sizes_to_their_digits(which):
    """a, delta, p_max (and b of the outer contact) within half a unit of the 5th digit."""
    a, b, delta, p_max, _ = contact(which)
    _, _, a_pr, b_pr, delta_pr, p_pr = INNER if which == "inner" else OUTER
    assert a / a_pr - 1 == pytest.approx(0.0, abs=half_unit(a_pr))
    assert p_max / p_pr - 1 == pytest.approx(0.0, abs=half_unit(p_pr))
    if delta_pr is not None:
        assert delta / delta_pr - 1 == pytest.approx(0.0, abs=half_unit(delta_pr))
    if which == "outer":
        assert b / b_pr - 1 == pytest.approx(0.0, abs=half_unit(b_pr))


def test_inner_minor_axis_through_printed_peak_pressure():
    """b_i: 2 units off the printed 8.9653e-3 in; the b_i that the printed Q, a_i and p_max_i
    imply (p_max = 3 Q / (2 pi a b)) is ours to the printed digits of Q, a_i and p_max_i."""
    _, b, _, _, _ = contact("inner")
    _, q, a_pr, b_pr, _, p_pr = INNER
    assert abs(b / b_pr - 1) < 5 * half_unit(b_pr)          # 2.5 units of the 5th digit
    b_implied = 3.0 * q / (2.0 * math.pi * a_pr * p_pr)
    assert b / b_implied - 1 == pytest.approx(
        0.0, abs=half_unit(q) + half_unit(a_pr) + half_unit(p_pr))


def test_quantities_free_of_the_modulus():
    """No number chosen: delta_i / a_i^2 = delta* Sum rho / a*^2 and kappa_o = a_o / b_o
    depend on the geometry only (tolerance: the printed digits of each factor)."""
    a, _, delta, _, _ = contact("inner")
    _, _, a_pr, _, d_pr, _ = INNER
    assert (delta / a ** 2) / (d_pr / a_pr ** 2) - 1 == pytest.approx(
        0.0, abs=half_unit(d_pr) + 2 * half_unit(a_pr))
    _, _, _, _, kappa = contact("outer")
    _, _, a_pr, b_pr, _, _ = OUTER
    assert kappa / (a_pr / b_pr) - 1 == pytest.approx(
        0.0, abs=half_unit(a_pr) + half_unit(b_pr))


def test_printed_ring_modulus_offsets_every_size_by_the_modulus_only():
    """With the printed ring modulus 2.96e7 psi on both bodies, a and b of both contacts are
    low by (2.90/2.96)^(1/3) and delta_i by (2.90/2.96)^(2/3): the offset is elastic."""
    r = E_CONTACT_PSI / E_RING_PRINTED_PSI
    for which in ("inner", "outer"):
        a, b, delta, _, _ = contact(which, E_RING_PRINTED_PSI)
        _, _, a_pr, b_pr, d_pr, _ = INNER if which == "inner" else OUTER
        assert a / a_pr == pytest.approx(r ** (1 / 3), abs=half_unit(a_pr))
        assert b / b_pr == pytest.approx(r ** (1 / 3), abs=5 * half_unit(b_pr))  # b_i: above
        if d_pr is not None:
            assert delta / d_pr == pytest.approx(r ** (2 / 3), abs=half_unit(d_pr))


def test_contact_constant_of_the_inner_contact():
    """The published load-deflection constant of the inner contact, K_i = Q_i / delta_i^1.5
    from the printed load and approach (tolerance: their printed digits), is ours; and
    ``contact_constant`` is the series of the two contacts, K_n = (c_i + c_o)^(-3/2),
    K = K_n cos(alpha)^(5/2)."""
    alpha, q, _, _, d_pr, _ = INNER
    k_published = q * LBF / (d_pr * IN) ** 1.5                       # [N/m^1.5]
    E = E_CONTACT_PSI * PSI
    si, Fi, so, Fo = ball_contact(D_IN * IN, DM_IN * IN, alpha, CONFORMITY, CONFORMITY)
    c_i, c_o = _approach_coefficient(si, Fi, E, NU), _approach_coefficient(so, Fo, E, NU)
    tol = 1.5 * half_unit(d_pr) + half_unit(q)
    assert c_i ** -1.5 / k_published - 1 == pytest.approx(0.0, abs=tol)
    es = ElementSet("ball", Z, D_IN * IN, DM_IN * IN, 0.0, alpha, CONFORMITY, CONFORMITY)
    k = contact_constant(es, E_mod=E, nu=NU)
    assert k.normal_stiffness == pytest.approx((c_i + c_o) ** -1.5, rel=1e-12)
    assert k.stiffness == pytest.approx(k.normal_stiffness
                                        * math.cos(math.radians(alpha)) ** 2.5, rel=1e-12)
