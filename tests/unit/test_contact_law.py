"""Unit tier: the one contact law (models/contact_law.py) that the kernels inline and every
numpy caller runs: closed forms for p = 1, 3/2 and 10/9, central finite differences of
df/ddelta and df/ddelta', continuity at the gap for p > 1, zero force in the dead zone,
damping only in contact, the mode rules (held modes, smooth contacts from the sign), the
compiled scalar law against the numpy wrapper, and the compiled right-hand side against
the wrapper on a one-mode model."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from vibrogear.models.contact_law import (contact_force, contact_mode, evaluate, evaluate_set,
                                          flank, harmonic_series, smooth_contacts)
from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel

#: a two-flank dead zone (mesh-like, unequal flanks) and its parameters
LAW = dict(k_hi=3.0e8, k_lo=2.0e8, gap_hi=1.0e-6, gap_lo=-4.0e-5, damping=600.0)
EXPONENTS = (1.0, 1.5, 10 / 9)


def law(delta, delta_dot=0.0, p=1.0, mu=1.0, mode=None, **over):
    args = dict(LAW, exponent=p)
    args.update(over)
    return evaluate(delta, delta_dot, modulation=mu, mode=mode, **args)


@pytest.mark.parametrize("p", EXPONENTS)
def test_closed_forms_on_both_flanks(p):
    """f = k mu s^p + c delta' beyond the upper gap, -k mu s^p + c delta' beyond the lower
    gap (s: the penetration), df/ddelta = p k mu s^(p-1), df/ddelta' = c."""
    k1, k2, g1, g2, c = (LAW[k] for k in ("k_hi", "k_lo", "gap_hi", "gap_lo", "damping"))
    mu, v = 1.17, 0.03
    s = np.array([1e-7, 2.5e-6, 3e-5])       # (g -+ s) -+ g = s to |g| / s round-offs: rtol 1e-12
    up = law(g1 + s, v, p, mu)
    np.testing.assert_allclose(up.force, k1 * mu * s ** p + c * v, rtol=1e-12)
    np.testing.assert_allclose(up.stiffness, p * k1 * mu * s ** (p - 1), rtol=1e-12)
    np.testing.assert_array_equal(up.damping, c)
    np.testing.assert_array_equal(up.mode, 1)
    lo = law(g2 - s, v, p, mu)
    np.testing.assert_allclose(lo.force, -k2 * mu * s ** p + c * v, rtol=1e-12)
    np.testing.assert_allclose(lo.stiffness, p * k2 * mu * s ** (p - 1), rtol=1e-12)
    np.testing.assert_array_equal(lo.mode, -1)


def test_linear_and_hertz_textbook_values():
    """p = 1: a spring k (delta - g); p = 3/2: Hertz k s sqrt(s), stiffness 3/2 k sqrt(s)."""
    r = law(1.0e-6 + 4e-6)
    assert r.force == pytest.approx(3.0e8 * 4e-6, rel=1e-14) and r.stiffness == 3.0e8
    r = law(-4.0e-5 - 9e-6, p=1.5)
    assert r.force == pytest.approx(-2.0e8 * 9e-6 * 3e-3, rel=1e-14)   # sqrt(9e-6) = 3e-3
    assert r.stiffness == pytest.approx(1.5 * 2.0e8 * 3e-3, rel=1e-14)
    # a one-sided rolling element: nothing beyond the (absent) lower gap
    r = evaluate(np.array([-1.0, 1e-5]), k_hi=1e10, k_lo=0.0, gap_hi=0.0, gap_lo=-np.inf,
                 exponent=10 / 9)
    np.testing.assert_array_equal(r.mode, [0, 1])
    assert r.force[1] == pytest.approx(1e10 * 1e-5 ** (10 / 9), rel=1e-13)


@pytest.mark.parametrize("p,mode,mu", list(itertools.product(EXPONENTS, (1, -1), (1.0, 0.83))))
def test_finite_differences_of_both_derivatives(p, mode, mu):
    rng = np.random.default_rng(11)
    gap = LAW["gap_hi"] if mode > 0 else LAW["gap_lo"]
    s = rng.uniform(1e-7, 2e-5, 6)
    delta = gap + mode * s
    v = rng.normal(scale=0.05, size=6)
    r = law(delta, v, p, mu)
    h = 1e-10
    fd = (law(delta + h, v, p, mu).force - law(delta - h, v, p, mu).force) / (2 * h)
    np.testing.assert_allclose(r.stiffness, fd, rtol=2e-6)
    fd_v = (law(delta, v + 1e-3, p, mu).force - law(delta, v - 1e-3, p, mu).force) / 2e-3
    np.testing.assert_allclose(r.damping, fd_v, rtol=1e-9)


def test_zero_force_in_the_dead_zone_and_damping_only_in_contact():
    delta = np.linspace(LAW["gap_lo"], LAW["gap_hi"], 41)      # gaps included: no contact
    for p in EXPONENTS:
        r = law(delta, np.full(41, 0.7), p, 1.3)
        assert not r.force.any() and not r.stiffness.any() and not r.damping.any()
        assert not r.mode.any()
    inside = law(np.array([LAW["gap_hi"] + 1e-9, LAW["gap_lo"] - 1e-9]), 0.7)
    np.testing.assert_array_equal(inside.damping, LAW["damping"])
    assert law(0.0, 0.0, damping=0.0).damping == 0.0


@pytest.mark.parametrize("p", (1.5, 10 / 9))
def test_hertz_force_and_stiffness_continuous_at_the_gap(p):
    """p > 1 (undamped): f and df/ddelta tend to 0 at the gap, as s^p and s^(p-1)."""
    for eps in (1e-9, 1e-12, 1e-15):
        r = law(LAW["gap_hi"] + eps, p=p, damping=0.0)
        assert 0.0 < r.force <= 1.0000001 * LAW["k_hi"] * eps ** p
        assert 0.0 < r.stiffness <= 1.0000001 * p * LAW["k_hi"] * eps ** (p - 1)
    # p = 1 keeps the stiffness jump (why such contacts switch at located events)
    assert law(LAW["gap_hi"] + 1e-15).stiffness == LAW["k_hi"]


def test_mode_rules():
    """A held mode runs its branch beyond the gap (p = 1: the linear extension; p > 1: no
    stiffness force, damping on); smooth contacts (p > 1, undamped) take the sign's mode."""
    d = LAW["gap_hi"] - 2e-6                                  # in the dead zone
    r = law(d, 0.1, mode=1)
    assert r.mode == 1 and r.force == pytest.approx(LAW["k_hi"] * -2e-6 + 60.0, rel=1e-12)
    r = law(d, 0.1, p=1.5, mode=1)
    assert r.force == pytest.approx(60.0) and r.stiffness == 0.0
    r = law(d, 0.1, p=1.5, mode=1, damping=0.0)                # smooth: the held mode is ignored
    assert r.mode == 0 and r.force == 0.0
    np.testing.assert_array_equal(smooth_contacts([1.0, 1.5, 1.5, 10 / 9], [0.0, 0.0, 1.0, 0.0]),
                                  [False, True, False, True])
    np.testing.assert_array_equal(flank([-5e-5, -4e-5, 0.0, 1e-6, 2e-6], LAW["gap_hi"],
                                        LAW["gap_lo"]), [-1, 0, 0, 0, 1])
    assert contact_mode(2e-6, 1e-6, -4e-5) == 1 and contact_mode(-5e-5, 1e-6, -4e-5) == -1


def test_compiled_scalar_law_equals_numpy_wrapper():
    rng = np.random.default_rng(5)
    n = 400
    delta = rng.uniform(-6e-5, 2e-5, n)
    v = rng.normal(scale=0.1, size=n)
    p = rng.choice(EXPONENTS, n)
    c = rng.choice([0.0, 600.0], n)
    mu = rng.uniform(0.7, 1.3, n)
    held = rng.integers(-1, 2, n)
    r = evaluate(delta, v, k_hi=LAW["k_hi"], k_lo=LAW["k_lo"], gap_hi=LAW["gap_hi"],
                 gap_lo=LAW["gap_lo"], exponent=p, damping=c, modulation=mu, mode=held)
    for i in range(n):
        md = contact_mode(delta[i], LAW["gap_hi"], LAW["gap_lo"]) if (p[i] > 1 and c[i] == 0) \
            else held[i]
        f, kd, cd = contact_force(md, delta[i], v[i], LAW["k_hi"], LAW["k_lo"], LAW["gap_hi"],
                                  LAW["gap_lo"], p[i], c[i], mu[i])
        assert (f, kd, cd, md) == (r.force[i], r.stiffness[i], r.damping[i], r.mode[i])


def test_harmonic_series_closed_form_and_rate():
    W, a, b = 500.0, (2e-6, 1e-6), (-1e-6,)
    t = np.linspace(0.0, 0.03, 7)
    e, e_dot = harmonic_series(a, b, W, t)
    np.testing.assert_allclose(e, 2e-6 * np.cos(W * t) + 1e-6 * np.cos(2 * W * t)
                               - 1e-6 * np.sin(W * t), rtol=1e-12, atol=1e-20)
    np.testing.assert_allclose(e_dot, -2e-6 * W * np.sin(W * t) - 2e-6 * W * np.sin(2 * W * t)
                               - 1e-6 * W * np.cos(W * t), rtol=1e-12, atol=1e-20)
    # per contact (rows), and an empty series
    rows = harmonic_series(np.array([[0.2, 0.1], [0.0, 0.0]]), np.array([[0.05, -0.02]] * 2),
                           1000.0, [0.0, np.pi / 2000.0])[0]
    np.testing.assert_allclose(rows, [[0.3, -0.1 + 0.05], [0.0, 0.05]], atol=1e-15)
    np.testing.assert_array_equal(harmonic_series((), (), W, t)[0], 0.0)


def _one_mode_model(p, damping):
    """x'' + d x' + w2 x + f(x - e(t)) = F0 + Fc cos(W t), one contact on x."""
    H = 2
    ct = ContactSet(directions=np.ones((1, 1)), k_hi=np.array([3.0]), k_lo=np.array([2.0]),
                    gap_hi=np.array([0.05]), gap_lo=np.array([-0.1]), exponent=np.array([p]),
                    damping=np.array([damping]), stiffness_cos=np.array([[0.2, 0.05]]),
                    stiffness_sin=np.array([[0.1, 0.0]]), error_cos=np.array([[0.02, 0.01]]),
                    error_sin=np.array([[0.0, 0.015]]))
    fo = Forcing(F0=np.array([0.2]), Fc=np.array([[0.1], [0.0]]), Fs=np.zeros((H, 1)))
    return ReducedModel(omega2=np.array([1.5]), damping=np.array([0.04]),
                        coupling=LinearCoupling.none(1), forcing=fo, contacts=ct,
                        omega_per_param=2.0)


@pytest.mark.parametrize("p,damping", [(1.0, 0.3), (1.5, 0.0), (10 / 9, 0.2)])
def test_compiled_rhs_runs_the_law(p, damping):
    """accel's acceleration = forcing - d v - w2 x - f(delta, delta'; mu(t)) with f, mu, e
    from the numpy side (evaluate_set, harmonic_series), on every branch."""
    from vibrogear.solvers.integrator.kernels import accel, model_arrays

    model = _one_mode_model(p, damping)
    ct = model.contacts
    A, Om = model_arrays(model, 1.3)[:2]
    for t, x, v, md in [(0.3, 0.2, 0.5, 1), (1.1, -0.3, -0.2, -1), (2.0, 0.0, 0.1, 0),
                        (0.7, 0.04, 0.3, 1)]:           # last: a held mode inside the gap
        out, Cx, Cv, kd, cd = (np.zeros(k) for k in (2, 1, 1, 1, 1))
        accel(t, np.array([x, v]), np.array([md]), A, Om, np.empty(2), np.empty(2), out,
              Cx, Cv, kd, cd, np.zeros(1))
        e, e_dot = harmonic_series(ct.error_cos, ct.error_sin, Om, t)
        mu = 1.0 + harmonic_series(ct.stiffness_cos, ct.stiffness_sin, Om, t)[0]
        r = evaluate_set(ct, x - e, v - e_dot, mu, mode=[[md]])
        expected = 0.2 + 0.1 * np.cos(Om * t) - 0.04 * v - 1.5 * x - r.force[0, 0]
        assert out[1] == pytest.approx(expected, rel=1e-14, abs=1e-15)
        assert kd[0] == pytest.approx(r.stiffness[0, 0], rel=1e-14)
        assert cd[0] == r.damping[0, 0]
