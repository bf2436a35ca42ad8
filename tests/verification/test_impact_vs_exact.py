"""Cross-tests: the project's integrator and shooting solver vs the independent exact
reference for the piecewise-linear impact pair (tests/reference/impact_exact.py).

The reference is closed-form region by region (switch times by Brent + Newton on the
closed form), so its own error is ~1e-12 or less (see test_reference_impact_exact.py);
every tolerance below is set by the solver's requested accuracy, with a margin of
roughly 5-50x over the agreement measured when these tests were written
(numbers quoted in the comments).

Parameter sets (found with the exact tools):

* P_A = (zeta, kappa, f_m, f_p, b_r) = (0.05, 0.5, 0.2, 0.2, 0.5)
    Omega = 0.5: stable period-1 orbit impacting q = +b_r only (2 switches / period)
    Omega = 0.8: stable period-1 orbit impacting both sides (4 switches / period);
                 with contact damping c_d = 0.3 the orbit is double-sided too.
* P_B = (0.015, 0.1, 0.1, 0.1, 1.0)
    Omega = 0.55: stable double-sided period-1 orbit
    Omega = 0.85: stable one-sided period-2 orbit (|mu| = 0.8011), coexisting with the
                  unstable period-1 orbit it bifurcated from (mu = -2.366, -0.3385:
                  a flip / period-doubling).
"""
import numpy as np
import pytest

try:
    from tests.reference import impact_exact as ex
except ImportError:  # tests/ itself on sys.path (pytest rootdir-less import)
    from reference import impact_exact as ex

from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.config.options import ShootingOptions

try:
    from vibrogear.solvers.periodic.shooting import shoot
except ModuleNotFoundError as exc:  # only a *missing* module skips; a broken one fails
    if exc.name != "vibrogear.solvers.periodic.shooting":
        raise
    shoot = None
needs_shoot = pytest.mark.skipif(shoot is None, reason="vibrogear.solvers.periodic.shooting not available yet")

P_A = (0.05, 0.5, 0.2, 0.2, 0.5)
P_B = (0.015, 0.1, 0.1, 0.1, 1.0)

FLOW_CASES = {
    "A-double-sided": (P_A + (0.0,), 0.8),
    "A-contact-damping": (P_A + (0.3,), 0.8),
    "B-double-sided": (P_B + (0.0,), 0.55),
    "B-period2": (P_B + (0.0,), 0.85),
    "undamped-kappa0": ((0.0, 0.0, 0.05, 0.3, 0.5, 0.0), 0.7),
    "overdamped": ((0.7, 0.0, 0.05, 1.0, 0.5, 0.0), 0.7),
    "critical-contact": ((1.0, 0.3, 0.0, 2.0, 0.3, 0.0), 1.3),
}

OPT_1E10 = IntegrationOptions(rtol=1e-10, atol=1e-12)
OPT_SHOOT = IntegrationOptions(rtol=1e-11, atol=1e-13)


def _both(prm):
    return ex.ImpactParams(*prm), impact_pair_model(*prm)


# ---------------------------------------------------------------------------
# integrator vs exact flow
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(FLOW_CASES))
def test_integrator_end_state_events_and_variational_vs_exact(name):
    prm, Om = FLOW_CASES[name]
    p, model = _both(prm)
    u0, t1 = np.array([0.0, 0.0]), 60.0
    tr = integrate(model, Om, u0, 0.0, t1, options=OPT_1E10, variational=True)
    fl = ex.exact_flow(p, Om, u0, 0.0, t1, stm=True, dOmega=True)
    assert tr.status == 0, tr.message
    assert fl.n_switches >= 10
    # end state, several switches on the way; measured 1e-11 .. 3.7e-9 (undamped case)
    assert np.max(np.abs(tr.u_end - fl.u_end)) < 1e-7 * (1.0 + np.max(np.abs(fl.u_end)))
    # every switch found, at the exact time; measured 4e-11 .. 3.8e-8 (undamped case)
    assert tr.events == fl.n_switches
    assert len(tr.event_times) == fl.n_switches
    assert np.max(np.abs(tr.event_times - fl.switch_times)) < 2e-7
    # monodromy (saltation included when c_d != 0); measured relative 2e-10 .. 5.7e-8
    assert np.max(np.abs(tr.monodromy - fl.stm)) < 1e-6 * np.max(np.abs(fl.stm))
    # d u_end / d Omega at fixed t_end; measured relative 5e-11 .. 1.1e-8
    assert np.max(np.abs(tr.dparam - fl.dOmega)) < 1e-6 * np.max(np.abs(fl.dOmega))


@pytest.mark.parametrize("name", ["A-double-sided", "A-contact-damping", "B-double-sided"])
def test_integrator_dense_output_vs_exact(name):
    prm, Om = FLOW_CASES[name]
    p, model = _both(prm)
    t_eval = np.linspace(0.0, 60.0, 3001)
    tr = integrate(model, Om, np.zeros(2), 0.0, 60.0, t_eval=t_eval, options=OPT_1E10)
    assert tr.status == 0, tr.message
    U = ex.exact_dense(p, Om, np.zeros(2), 0.0, t_eval)
    # measured 1.2e-10 .. 2.2e-9
    assert tr.u.shape == U.shape
    assert np.max(np.abs(tr.u - U)) < 1e-7 * (1.0 + np.max(np.abs(U)))


def test_integrator_restart_in_contact_and_on_surface():
    """Start inside contact, and exactly on the surface moving into contact."""
    prm, Om = FLOW_CASES["A-double-sided"]
    p, model = _both(prm)
    for u0 in (np.array([0.9, -0.2]), np.array([p.b_r, 0.4]), np.array([-p.b_r, -0.3])):
        tr = integrate(model, Om, u0, 1.3, 31.3, options=OPT_1E10, variational=True)
        fl = ex.exact_flow(p, Om, u0, 1.3, 31.3, stm=True)
        assert tr.status == 0, tr.message
        assert np.max(np.abs(tr.u_end - fl.u_end)) < 1e-7
        assert np.max(np.abs(tr.monodromy - fl.stm)) < 1e-6 * np.max(np.abs(fl.stm))


def test_integrator_order_on_linear_interval():
    """Adaptive Dormand-Prince 5(4): error ~ steps^-5 on a contact-free interval.

    Measured slope -5.21 (rtol 1e-4 .. 1e-12, 52 .. 1841 steps) and error / rtol ~ 1.2 .. 1.6.
    """
    prm = (0.05, 0.5, 0.2, 0.2, np.inf, 0.0)
    Om = 0.8
    p, model = _both(prm)
    u0 = np.array([0.3, 0.1])
    t1 = 4 * 2 * np.pi / Om
    ref = ex.exact_flow(p, Om, u0, 0.0, t1).u_end
    errs, steps, rtols = [], [], np.logspace(-4, -12, 9)
    for rtol in rtols:
        # max_step_periods large: let the error control alone choose the steps
        opt = IntegrationOptions(rtol=rtol, atol=1e-2 * rtol, max_step_periods=100.0)
        tr = integrate(model, Om, u0, 0.0, t1, options=opt)
        assert tr.status == 0 and tr.events == 0
        errs.append(np.max(np.abs(tr.u_end - ref)))
        steps.append(tr.steps)
    slope = np.polyfit(np.log(steps), np.log(errs), 1)[0]
    assert -5.7 <= slope <= -4.3, slope
    # tolerance proportionality: the global error tracks rtol
    ratio = np.array(errs) / rtols
    assert np.all(ratio < 20.0) and np.all(ratio > 0.05), ratio
    assert np.polyfit(np.log(rtols), np.log(errs), 1)[0] == pytest.approx(1.0, abs=0.15)


# ---------------------------------------------------------------------------
# shooting vs exact periodic orbits
# ---------------------------------------------------------------------------
ORBITS = {
    # name: (params, Omega, n_periods, contact sides, Newton seed near the orbit)
    "one-sided-P1": (P_A + (0.0,), 0.5, 1, {1}, [0.9224403590110651, 0.0334195909010497]),
    "double-sided-P1": (P_A + (0.0,), 0.8, 1, {1, -1}, [1.3617506569731983, 0.6237573054151337]),
    "double-sided-P1-cd": (P_A + (0.3,), 0.8, 1, {1, -1}, [0.5587155405423206, 0.8892760004772642]),
    "double-sided-P1-B": (P_B + (0.0,), 0.55, 1, {1, -1}, [1.8453664300767039, 0.4170298432999809]),
    "one-sided-P2": (P_B + (0.0,), 0.85, 2, {1}, [0.19042901104947035, 0.013224900302871115]),
    "unstable-P1-flip": (P_B + (0.0,), 0.85, 1, {1}, [0.6794174449795924, 0.007725562650991945]),
}


@needs_shoot
@pytest.mark.parametrize("name", list(ORBITS))
def test_shooting_vs_exact_periodic_orbit(name):
    prm, Om, n, sides, u_ref = ORBITS[name]
    p, model = _both(prm)
    orb = ex.periodic_orbit(p, Om, u_ref, n_periods=n)
    assert orb.converged and orb.contact_sides == sides
    guess = orb.u0 + np.array([1e-3, -1e-3])
    r = shoot(model, Om, guess, n_periods=n, options=OPT_SHOOT, shooting=ShootingOptions(tol=1e-10))
    assert r.converged and r.status == 0, r.message
    assert r.residual < 1e-10
    assert r.period == pytest.approx(orb.period, rel=1e-14)
    # measured |du0| <= 1.3e-11, |dmu| <= 2e-11, |dM| <= 7e-11 (rtol 1e-11)
    assert np.max(np.abs(r.u0 - orb.u0)) < 1e-8
    mu_s, mu_e = np.sort_complex(np.asarray(r.floquet)), np.sort_complex(orb.floquet)
    assert np.max(np.abs(mu_s - mu_e)) < 1e-7
    assert np.max(np.abs(r.monodromy - orb.monodromy)) < 1e-7 * max(1.0, np.max(np.abs(orb.monodromy)))
    assert r.stable == orb.stable
    # contact losses per orbit = exits from contact in the exact orbit
    assert r.impacts == int(np.sum(orb.flow.switch_to == 0))
    # extrema of q over the orbit (exact q_min/q_max by dense sampling: ~1e-7 sampling error)
    assert r.monitor_max == pytest.approx(orb.q_max, abs=1e-6)
    assert r.monitor_min == pytest.approx(orb.q_min, abs=1e-6)
    # Liouville (c_d = 0) / Liouville with contact damping
    T = orb.period
    assert abs(np.prod(mu_s)) == pytest.approx(
        np.exp(-2 * p.zeta * T - p.contact_damping * orb.flow.time_in_contact), rel=1e-8)


@needs_shoot
def test_period2_orbit_is_a_flip_of_the_unstable_period1():
    """The P2 orbit at Omega = 0.85 and the unstable P1 orbit: multipliers of the P1 orbit
    squared are those of the P1 orbit traversed twice (consistency of shooting with n = 2)."""
    prm, Om, _, _, u_ref = ORBITS["unstable-P1-flip"]
    p, model = _both(prm)
    r1 = shoot(model, Om, u_ref, n_periods=1, options=OPT_SHOOT, shooting=ShootingOptions(tol=1e-10))
    r2 = shoot(model, Om, u_ref, n_periods=2, options=OPT_SHOOT, shooting=ShootingOptions(tol=1e-10))
    assert r1.converged and r2.converged
    assert np.allclose(r2.u0, r1.u0, rtol=0, atol=1e-8)
    mu1 = np.sort(np.real(r1.floquet))
    assert mu1[0] < -1.0  # flip instability
    assert np.allclose(np.sort(np.real(r2.floquet)), np.sort(mu1 ** 2), rtol=1e-6)
    orb = ex.periodic_orbit(p, Om, u_ref, n_periods=1)
    assert np.allclose(mu1, np.sort(np.real(orb.floquet)), rtol=0, atol=1e-7)


@needs_shoot
def test_shooting_converged_orbit_is_exact_orbit_from_far_guess():
    """From a far guess the shooting may land on any orbit; whichever it is, it must be an
    exact periodic orbit with the exact multipliers."""
    prm, Om, n = P_B + (0.0,), 0.85, 2
    p, model = _both(prm)
    guess = np.array([0.19042901104947035, 0.013224900302871115]) + 0.05 * np.array([1.0, -1.0])
    r = shoot(model, Om, guess, n_periods=n, options=OPT_SHOOT, shooting=ShootingOptions(tol=1e-10))
    assert r.converged
    fl = ex.exact_flow(p, Om, r.u0, 0.0, r.period, stm=True)
    assert np.max(np.abs(fl.u_end - r.u0)) < 1e-8
    assert np.allclose(np.sort_complex(np.linalg.eigvals(fl.stm)), np.sort_complex(np.asarray(r.floquet)),
                       rtol=0, atol=1e-7)


@needs_shoot
# ---------------------------------------------------------------------------
# linear limit
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("Om", [0.3, 0.7, 1.0, 1.6])
def test_linear_limit_shooting_vs_frf(Om):
    zeta, kappa, f_m, f_p = 0.05, 0.5, 0.2, 0.2
    model = impact_pair_model(zeta, kappa, f_m, f_p, 1e6)
    r = shoot(model, Om, np.zeros(2), options=OPT_SHOOT, shooting=ShootingOptions(tol=1e-10))
    assert r.converged, r.message
    offset, amp = ex.linear_frf(zeta, kappa, f_m, f_p, Om)
    # measured ~7e-12
    assert np.allclose(r.u0, ex.linear_periodic_state(zeta, kappa, f_m, f_p, Om), rtol=0, atol=1e-8)
    assert r.monitor_max == pytest.approx(offset + amp, abs=1e-8)
    assert r.monitor_min == pytest.approx(offset - amp, abs=1e-8)
    assert r.impacts == 0
    lam = -zeta + 1j * np.sqrt(kappa - zeta ** 2)
    mu = np.exp(lam * 2 * np.pi / Om)
    assert np.allclose(np.sort_complex(np.asarray(r.floquet)), np.sort_complex(np.array([mu, mu.conjugate()])),
                       rtol=0, atol=1e-8)


@pytest.mark.parametrize("pen", [-1e-8, 1e-8, 1e-6, 1e-4, 1e-2])
def test_integrator_grazing_contact(pen):
    """Free undamped motion q = A sin(w t), A = b_r + pen: a graze of depth pen.

    Measured (rtol 1e-10): the integrator finds both switches for pen >= 1e-6 (entry time
    error 2e-8 at pen = 1e-6, <= 1e-13 at pen >= 1e-4); for pen <= 1e-8 it reports no
    event (the reference finds them down to pen = 1e-10).  Missing such a graze is
    harmless for the state: the contact force ~ (1-kappa) pen acts for ~sqrt(pen) time;
    end states agree to 2.7e-11 in every case.
    """
    kappa, b = 0.5, 1.0
    w = np.sqrt(kappa)
    prm = (0.0, kappa, 0.0, 0.0, b, 0.0)
    p, model = _both(prm)
    u0 = np.array([0.0, (b + pen) * w])
    t1 = np.pi / w
    fl = ex.exact_flow(p, 0.3, u0, 0.0, t1)
    tr = integrate(model, 0.3, u0, 0.0, t1, options=OPT_1E10)
    assert tr.status == 0, tr.message
    assert np.max(np.abs(tr.u_end - fl.u_end)) < 1e-9
    if pen >= 1e-6:
        assert tr.events == fl.n_switches == 2
        assert np.max(np.abs(tr.event_times - fl.switch_times)) < 1e-6
    elif pen < 0:
        assert tr.events == 0
