"""The Hertz point-contact chain of ``bearing_hertz`` against published numbers: a specific
bearing (Harris & Mindel 1973, Fig. 15) and Harris's table of the dimensionless contact
(Harris & Kotzalas, Table 6.1).

Source.  T. A. Harris and M. H. Mindel, "Rolling element bearing dynamics", Wear 23 (1973)
311-337, Fig. 15: the printed sample output of SKF's bearing program for an angular-contact
ball bearing (values as transcribed, with the figure's pages 330-331 and a re-read of the
scan, in a public Rust bearing solver: github.com/CHOICHOI-KIMM/AI_Seminar,
BB-main/src-tauri/tests/contact_level_b3.rs).

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
2 units off in the fifth digit.  That modulus is inferred, not printed; two facts show
that it, and not the geometry, is what differs:

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
from scipy.special import ellipe, ellipk

from vibrogear.config.model.bearing_catalogue import ElementSet
from vibrogear.models.gearbox.bearing_hertz import (_approach_coefficient, ball_contact,
                                                    contact_constant, delta_star, ellipticity)

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


# Harris & Kotzalas, Rolling Bearing Analysis, 5th ed. (Essential Concepts of Bearing
# Technology, 2007), Table 6.1, p. 128: F(rho), a*, b*, delta* as printed (the row F = 1,
# a* infinite, left out); transcribed in the same public repository,
# BB-main/src-tauri/tests/contact_level_b.rs.
HARRIS_TABLE_6_1 = """
0.1075 1.0760 0.9318 0.9974 | 0.3204 1.2623 0.8114 0.9761 | 0.4795 1.4556 0.7278 0.9429
0.5916 1.6440 0.6687 0.9077 | 0.6716 1.8258 0.6245 0.8733 | 0.7332 2.011 0.5881 0.8394
0.7948 2.265 0.5480 0.7961 | 0.83495 2.494 0.5186 0.7602 | 0.87366 2.800 0.4863 0.7169
0.90999 3.233 0.4499 0.6636 | 0.93657 3.738 0.4166 0.6112 | 0.95738 4.395 0.3830 0.5551
0.97290 5.267 0.3490 0.4960 | 0.983797 6.448 0.3150 0.4352 | 0.990902 8.062 0.2814 0.3745
0.995112 10.222 0.2497 0.3176 | 0.997300 12.789 0.2232 0.2705 | 0.9981847 14.839 0.2072 0.2427
0.9989156 17.974 0.18822 0.2106 | 0.9994785 23.55 0.16442 0.17167 | 0.9998527 37.38 0.13050 0.11995
"""


def _dimensionless(F: float):
    kappa = ellipticity(F)
    a_star = (2.0 * kappa ** 2 * ellipe(1.0 - 1.0 / kappa ** 2) / math.pi) ** (1.0 / 3.0)
    return a_star, a_star / kappa, delta_star(F)


def _half_unit_abs(printed: str) -> float:
    return 0.5 * 10.0 ** -len(printed.split(".")[1])


def test_harris_table_6_1_dimensionless_contact():
    """a*, b*, delta* over the whole table: within half a unit of each printed last digit,
    widened by what the rounding of the printed F moves them.  One printed entry is not
    reproduced: delta* = 0.9429 at F = 0.4795, which also disagrees with its own row, since
    delta* = 2 K(kappa) / (pi a*) with kappa = a*/b* gives 0.9432 from the printed a*, b*;
    that entry is checked against the row's own a*, b* instead."""
    rows = [r.split() for line in HARRIS_TABLE_6_1.strip().splitlines()
            for r in line.split("|")]
    assert len(rows) == 21
    for F_s, *printed in rows:
        F, hF = float(F_s), _half_unit_abs(F_s)
        ours, lo, hi = _dimensionless(F), _dimensionless(F - hF), _dimensionless(F + hF)
        for k, p in enumerate(printed):
            allow = _half_unit_abs(p) + abs(hi[k] - lo[k]) / 2.0
            if (F_s, k) == ("0.4795", 2):   # delta* of the row's own a*, b* (+- half units)
                ha, hb = _half_unit_abs(printed[0]), _half_unit_abs(printed[1])
                row = [2.0 * ellipk(1.0 - (b / a) ** 2) / (math.pi * a)
                       for a in (float(printed[0]) - ha, float(printed[0]) + ha)
                       for b in (float(printed[1]) - hb, float(printed[1]) + hb)]
                assert min(row) <= ours[k] <= max(row)
                assert abs(ours[k] - float(p)) > 2 * _half_unit_abs(p)   # printed entry off
                continue
            assert ours[k] == pytest.approx(float(p), abs=allow), (F_s, k)
