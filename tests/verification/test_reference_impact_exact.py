"""Self-tests of the independent exact impact-pair reference (tests/reference/impact_exact.py).

These verify the reference against first principles (ODE residual, an
independent high-accuracy event-restarted DOP853 integration, finite
differences, Liouville's formula, the linear closed-form FRF) so that it can
in turn be trusted to verify the project's solvers.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

try:
    from tests.reference import impact_exact as ex
except ImportError:  # tests/ itself on sys.path (pytest rootdir-less import)
    from reference import impact_exact as ex

# ---------------------------------------------------------------------------
# parameter sets found with the exact tools (see module docstring of the cross-tests)
# ---------------------------------------------------------------------------
P_A = ex.ImpactParams(zeta=0.05, kappa=0.5, f_m=0.2, f_p=0.2, b_r=0.5)
OMEGA_ONE_SIDED = 0.5      # period-1, impacts q = +b_r only (2 switches / period)
OMEGA_DOUBLE_SIDED = 0.8   # period-1, impacts both sides (4 switches / period)
P_B = ex.ImpactParams(zeta=0.015, kappa=0.1, f_m=0.1, f_p=0.1, b_r=1.0)
OMEGA_PERIOD2 = 0.85       # period-2, one impact on +b_r every two periods

FLOW_CASES = [
    (P_A, 0.8),
    (ex.ImpactParams(0.05, 0.5, 0.2, 0.2, 0.5, contact_damping=0.3), 0.8),
    (P_B, 0.55),
    (P_B, 0.85),
    (ex.ImpactParams(0.0, 0.0, 0.05, 0.3, 0.5), 0.7),           # undamped, kappa = 0 inside
    (ex.ImpactParams(0.7, 0.0, 0.05, 1.0, 0.5), 0.7),           # over-damped contact, q''+1.4q'=F inside
    (ex.ImpactParams(1.0, 0.3, 0.0, 2.0, 0.3), 1.3),            # critically damped contact (c = 2, k = 1)
]


# ---------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------
def _fd5(f, t, h):
    """5-point central difference of an array-valued f at t."""
    return (-f(t + 2 * h) + 8 * f(t + h) - 8 * f(t - h) + f(t - 2 * h)) / (12 * h)


def ivp_flow(p, Omega, u0, t0, t1, rtol=1e-12, atol=1e-12):
    """Independent flow: DOP853 with switch events, restarted at each event."""
    u = np.array(u0, float)
    t = float(t0)
    reg = ex.initial_region(p, Omega, t, u)
    times = []
    while t < t1:
        def up(t, u):
            return u[0] - p.b_r

        def lo(t, u):
            return u[0] + p.b_r

        for e in (up, lo):
            e.terminal = True
        if reg == 0:
            up.direction, lo.direction = 1, -1
            evs = [up, lo]
        elif reg == 1:
            up.direction = -1
            evs = [up]
        else:
            lo.direction = 1
            evs = [lo]
        sol = solve_ivp(lambda t, u: ex.vector_field(p, Omega, t, u, reg), (t, t1), u,
                        method="DOP853", rtol=rtol, atol=atol, events=evs)
        assert sol.status in (0, 1), sol.message
        if sol.status == 1:
            k = [i for i, te in enumerate(sol.t_events) if len(te)][0]
            t = float(sol.t_events[k][0])
            u = sol.y_events[k][0].copy()
            u[0] = np.sign(u[0]) * p.b_r
            times.append(t)
            reg = ex.initial_region(p, Omega, t, u)
        else:
            u, t = sol.y[:, -1], t1
    return u, np.array(times)


# ---------------------------------------------------------------------------
# (a) closed-form region solution satisfies the ODE
# ---------------------------------------------------------------------------
REGION_CASES = {
    "underdamped": (0.1, 1.0, 0.3, 0.5, 0.8),
    "critical": (2.0, 1.0, 0.3, 0.5, 0.8),
    "near-critical": (2.0 * (1 + 1e-9), 1.0, 0.3, 0.5, 0.8),
    "overdamped": (3.0, 1.0, -0.2, 0.5, 0.8),
    "undamped": (0.0, 0.5, 0.1, 0.4, 1.3),
    "k0-damped": (0.1, 0.0, 0.1, 0.4, 0.6),
    "k0-undamped": (0.0, 0.0, 0.1, 0.4, 0.6),
    "k0-undamped-noforce": (0.0, 0.0, 0.1, 0.0, 0.6),
    "undamped-resonance": (0.0, 0.25, 0.1, 0.4, 0.5),   # Omega^2 == k exactly: secular term
    "undamped-near-resonance": (0.0, 0.64, 0.1, 0.4, 0.8),  # 0.8**2 != 0.64 in floating point
    "static-forcing(Omega=0)": (0.2, 0.5, 0.1, 0.4, 0.0),
    "strongly-overdamped": (40.0, 1.0, 0.1, 0.4, 0.6),
}


@pytest.mark.parametrize("name", list(REGION_CASES))
def test_region_solution_satisfies_ode(name):
    c, k, F0, Fp, Om = REGION_CASES[name]
    t0, u0 = 0.7, np.array([0.3, -0.4])

    def q(t):
        return ex.linear_solution(c, k, F0, Fp, Om, t0, u0, t)[0]

    def v(t):
        return ex.linear_solution(c, k, F0, Fp, Om, t0, u0, t)[1]

    q0, v0 = ex.linear_solution(c, k, F0, Fp, Om, t0, u0, t0)
    assert q0 == pytest.approx(u0[0], abs=1e-15) and v0 == pytest.approx(u0[1], abs=1e-15)
    ts = t0 + np.linspace(0.05, 12.0, 37)
    h = 1e-3 / max(1.0, 0.5 * c)  # resolve the fastest transient e^{-c s}
    qd = _fd5(q, ts, h)
    qdd = _fd5(v, ts, h)
    scale = 1.0 + np.max(np.abs(qdd)) + np.max(np.abs(ex.linear_solution(c, k, F0, Fp, Om, t0, u0, ts)[0]))
    # analytic velocity is the derivative of the position
    assert np.max(np.abs(qd - v(ts))) < 1e-9 * scale
    # ODE residual  (measured: <= ~1e-11 relative)
    res = qdd + c * v(ts) + k * q(ts) - F0 - Fp * np.cos(Om * ts)
    assert np.max(np.abs(res)) < 1e-9 * scale


@pytest.mark.parametrize("name", list(REGION_CASES))
def test_region_stm_exact(name):
    """Phi(0) = I, Phi' = A Phi, and Phi maps initial-state differences exactly (linear ODE)."""
    c, k, F0, Fp, Om = REGION_CASES[name]
    A = np.array([[0.0, 1.0], [-k, -c]])
    assert np.allclose(ex.linear_stm(c, k, 0.0), np.eye(2), atol=0, rtol=0)
    s = np.linspace(0.05, 10.0, 23)
    dphi = _fd5(lambda x: ex.linear_stm(c, k, x), s, 1e-3 / max(1.0, 0.5 * c))
    phi = ex.linear_stm(c, k, s)
    assert np.max(np.abs(dphi - A @ phi)) < 1e-9 * (1 + np.max(np.abs(A)) * np.max(np.abs(phi)))
    # differences of two solutions evolve with Phi exactly
    t0, ua, ub = 0.2, np.array([0.3, -0.4]), np.array([-0.1, 0.9])
    t = 5.3
    qa = np.array(ex.linear_solution(c, k, F0, Fp, Om, t0, ua, t))
    qb = np.array(ex.linear_solution(c, k, F0, Fp, Om, t0, ub, t))
    assert np.allclose(qa - qb, ex.linear_stm(c, k, t - t0) @ (ua - ub), atol=1e-13, rtol=1e-12)
    # Liouville for one region
    assert np.linalg.det(ex.linear_stm(c, k, 3.0)) == pytest.approx(np.exp(-3.0 * c), rel=1e-12)


@pytest.mark.parametrize("name", list(REGION_CASES))
def test_region_scalar_fast_path_matches_vector(name):
    c, k, F0, Fp, Om = REGION_CASES[name]
    sol = ex.RegionSolution(c, k, F0, Fp, Om, 0.7, [0.3, -0.4])
    ts = 0.7 + np.linspace(0.0, 15.0, 61)
    qv = np.array([sol.scalar(t) for t in ts])
    q, v = sol(ts)
    scale = 1.0 + np.max(np.abs(q)) + np.max(np.abs(v))
    assert np.max(np.abs(qv[:, 0] - q)) < 1e-14 * scale
    assert np.max(np.abs(qv[:, 1] - v)) < 1e-14 * scale


def test_region_dOmega_matches_fd():
    c, k, F0, Fp = 0.1, 1.0, 0.3, 0.5
    t0, u0, t1, Om, h = 0.4, np.array([0.2, 0.1]), 9.0, 0.8, 1e-6
    d = ex.linear_dOmega(c, k, F0, Fp, Om, t0, u0, t1)
    up = np.array(ex.linear_solution(c, k, F0, Fp, Om + h, t0, u0, t1))
    um = np.array(ex.linear_solution(c, k, F0, Fp, Om - h, t0, u0, t1))
    assert np.allclose(d, (up - um) / (2 * h), rtol=1e-7, atol=1e-9)
    with pytest.raises(ValueError):
        ex.linear_dOmega(0.0, 0.25, F0, Fp, 0.5, t0, u0, t1)  # exact undamped resonance


# ---------------------------------------------------------------------------
# (b) exact flow vs event-restarted DOP853 (rtol = atol = 1e-12)
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("case", range(len(FLOW_CASES)))
def test_exact_flow_vs_solve_ivp(case):
    p, Om = FLOW_CASES[case]
    u0, t1 = np.array([0.0, 0.0]), 60.0
    fl = ex.exact_flow(p, Om, u0, 0.0, t1)
    u, times = ivp_flow(p, Om, u0, 0.0, t1)
    assert fl.n_switches >= 4
    assert fl.n_switches == len(times)
    # measured: states agree to <= 4e-11, switch times to <= 4e-10
    assert np.max(np.abs(fl.switch_times - times)) < 1e-8
    assert np.max(np.abs(fl.u_end - u)) < 1e-8 * (1 + np.max(np.abs(u)))
    # switch states are on the surfaces, alternating region pattern is consistent
    assert np.all(np.abs(np.abs(fl.switch_states[:, 0]) - p.b_r) == 0)
    assert np.all(fl.switch_from[1:] == fl.switch_to[:-1])


def test_exact_dense_continuity_and_consistency():
    p, Om = P_A, 0.8
    fl = ex.exact_flow(p, Om, [0.0, 0.0], 0.0, 40.0)
    t_eval = np.linspace(0.0, 40.0, 801)
    U = ex.exact_dense(p, Om, [0.0, 0.0], 0.0, t_eval, flow=fl)
    assert np.allclose(U[-1], fl.u_end, rtol=0, atol=1e-13)
    # state continuous across switches (evaluate both adjacent segments at the switch)
    for j, ts in enumerate(fl.switch_times):
        before = ex.exact_dense(p, Om, None, 0.0, [ts - 1e-9], flow=fl)[0]
        after = ex.exact_dense(p, Om, None, 0.0, [ts + 1e-9], flow=fl)[0]
        assert np.allclose(before, after, rtol=0, atol=1e-8)
    # restarting the flow from an intermediate dense state gives the same end state
    k = 400
    fl2 = ex.exact_flow(p, Om, U[k], t_eval[k], 40.0)
    assert np.allclose(fl2.u_end, fl.u_end, rtol=0, atol=1e-11)


def test_max_switches_enforced():
    with pytest.raises(RuntimeError):
        ex.exact_flow(P_A, 0.8, [0.0, 0.0], 0.0, 200.0, max_switches=5)


def test_no_contact_when_b_r_infinite():
    p = ex.ImpactParams(0.05, 0.5, 0.2, 0.2, np.inf)
    fl = ex.exact_flow(p, 0.8, [0.0, 0.0], 0.0, 50.0, stm=True)
    assert fl.n_switches == 0
    q, v = ex.linear_solution(0.1, 0.5, 0.2, 0.2, 0.8, 0.0, [0.0, 0.0], 50.0)
    assert np.allclose(fl.u_end, [q, v], atol=0, rtol=0)


# ---------------------------------------------------------------------------
# (c) exact STM / d/dOmega vs central finite differences of the exact flow
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("case", [0, 1, 2, 5, 6])
def test_flow_stm_and_dOmega_vs_fd(case):
    p, Om = FLOW_CASES[case]
    u0, h = np.array([0.2, 0.1]), 1e-6
    t1 = 30.0 if p.zeta < 0.5 else 12.0  # keep the heavily damped STMs O(1e-4) or larger
    fl = ex.exact_flow(p, Om, u0, 0.0, t1, stm=True, dOmega=True)
    assert fl.n_switches >= 2
    J = np.zeros((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        J[:, j] = (ex.exact_flow(p, Om, u0 + e, 0.0, t1).u_end
                   - ex.exact_flow(p, Om, u0 - e, 0.0, t1).u_end) / (2 * h)
    dO = (ex.exact_flow(p, Om + h, u0, 0.0, t1).u_end - ex.exact_flow(p, Om - h, u0, 0.0, t1).u_end) / (2 * h)
    # measured: relative 1e-10 .. 1e-8 (FD truncation + root-finding noise / h)
    assert np.max(np.abs(J - fl.stm)) < 1e-6 * np.max(np.abs(fl.stm)) + 1e-9
    assert np.max(np.abs(dO - fl.dOmega)) < 1e-6 * np.max(np.abs(dO))


def test_saltation_matrix_formula():
    # continuous field -> identity; damping jump c_d -> [[1,0],[-c_d,1]] entering contact
    p = ex.ImpactParams(0.05, 0.5, 0.2, 0.2, 0.5, contact_damping=0.3)
    u = np.array([p.b_r, 0.7])
    S = ex.saltation_matrix(ex.vector_field(p, 0.8, 1.0, u, 0), ex.vector_field(p, 0.8, 1.0, u, 1), [1, 0])
    assert np.allclose(S, [[1, 0], [-0.3, 1]], atol=1e-14)
    p0 = ex.ImpactParams(0.05, 0.5, 0.2, 0.2, 0.5)
    S0 = ex.saltation_matrix(ex.vector_field(p0, 0.8, 1.0, u, 0), ex.vector_field(p0, 0.8, 1.0, u, 1), [1, 0])
    assert np.allclose(S0, np.eye(2), atol=1e-15)


# ---------------------------------------------------------------------------
# (d) Liouville: det(monodromy) = exp(-2 zeta T) (c_d = 0), exp(-2 zeta T - c_d T_contact) otherwise
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("p,Om,n", [(P_A, OMEGA_ONE_SIDED, 1), (P_A, OMEGA_DOUBLE_SIDED, 1),
                                    (P_B, OMEGA_PERIOD2, 2), (P_B, 0.55, 1)])
def test_liouville_det_monodromy(p, Om, n):
    orb = ex.periodic_orbit(p, Om, ex.exact_flow(p, Om, [0.0, 0.0], 0.0, 300 * 2 * np.pi / Om).u_end, n_periods=n)
    assert orb.converged
    T = 2 * np.pi * n / Om
    assert np.prod(orb.floquet).real == pytest.approx(np.exp(-2 * p.zeta * T), rel=1e-12)
    assert np.linalg.det(orb.monodromy) == pytest.approx(np.exp(-2 * p.zeta * T), rel=1e-12)


def test_liouville_with_contact_damping():
    p = ex.ImpactParams(0.05, 0.5, 0.2, 0.2, 0.5, contact_damping=0.3)
    Om = 0.8
    orb = ex.periodic_orbit(p, Om, [0.0, 0.0])
    assert orb.converged and orb.contact_sides == {1, -1}
    expected = np.exp(-2 * p.zeta * orb.period - p.contact_damping * orb.flow.time_in_contact)
    assert np.linalg.det(orb.monodromy) == pytest.approx(expected, rel=1e-11)
    # the saltation matrices matter: without them the det would be different
    assert abs(expected - np.exp(-2 * p.zeta * orb.period)) > 0.1


# ---------------------------------------------------------------------------
# (e) impacting periodic orbits
# ---------------------------------------------------------------------------
def _settled(p, Om, u0=(0.0, 0.0), n=300):
    return ex.exact_flow(p, Om, u0, 0.0, n * 2 * np.pi / Om).u_end


def _independently_periodic(p, Om, orb, n=1, eps=1e-6):
    """The exact orbit checked with the independent DOP853 flow: it returns to u0 after n
    periods, and central differences of that flow give the exact monodromy."""
    T = n * 2 * np.pi / Om
    u_end, _ = ivp_flow(p, Om, orb.u0, 0.0, T)
    assert np.max(np.abs(u_end - orb.u0)) < 1e-8
    fd = np.column_stack([(ivp_flow(p, Om, orb.u0 + e, 0.0, T)[0]
                           - ivp_flow(p, Om, orb.u0 - e, 0.0, T)[0]) / (2 * eps)
                          for e in np.eye(2) * eps])
    assert np.max(np.abs(fd - orb.monodromy)) < 1e-5 * (1 + np.max(np.abs(fd)))


def test_period1_one_sided_orbit():
    orb = ex.periodic_orbit(P_A, OMEGA_ONE_SIDED, _settled(P_A, OMEGA_ONE_SIDED))
    assert orb.converged and orb.residual < 1e-13
    assert orb.contact_sides == {1} and orb.flow.n_switches == 2
    assert orb.q_max > P_A.b_r and orb.q_min > -P_A.b_r
    assert orb.stable
    _independently_periodic(P_A, OMEGA_ONE_SIDED, orb)


def test_period1_double_sided_orbit():
    orb = ex.periodic_orbit(P_A, OMEGA_DOUBLE_SIDED, _settled(P_A, OMEGA_DOUBLE_SIDED))
    assert orb.converged and orb.residual < 1e-13
    assert orb.contact_sides == {1, -1} and orb.flow.n_switches == 4
    assert orb.q_max > P_A.b_r and orb.q_min < -P_A.b_r
    assert orb.stable
    _independently_periodic(P_A, OMEGA_DOUBLE_SIDED, orb)


def test_period2_orbit():
    orb = ex.periodic_orbit(P_B, OMEGA_PERIOD2, _settled(P_B, OMEGA_PERIOD2), n_periods=2)
    assert orb.converged and orb.residual < 1e-13
    assert orb.contact_sides == {1} and orb.flow.n_switches == 2
    # genuinely period-2: after one forcing period the state has not returned
    u1 = ex.exact_flow(P_B, OMEGA_PERIOD2, orb.u0, 0.0, 2 * np.pi / OMEGA_PERIOD2).u_end
    assert np.max(np.abs(u1 - orb.u0)) > 0.5
    assert orb.stable
    _independently_periodic(P_B, OMEGA_PERIOD2, orb, n=2)


def test_newton_converges_quadratically_from_nearby_guess():
    orb = ex.periodic_orbit(P_A, OMEGA_DOUBLE_SIDED, _settled(P_A, OMEGA_DOUBLE_SIDED))
    orb2 = ex.periodic_orbit(P_A, OMEGA_DOUBLE_SIDED, orb.u0 + np.array([1e-3, -1e-3]))
    assert orb2.converged and orb2.iterations <= 4
    assert np.allclose(orb2.u0, orb.u0, rtol=0, atol=1e-12)


# ---------------------------------------------------------------------------
# (f) linear limit equals the closed-form FRF
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("b_r", [np.inf, 50.0])
@pytest.mark.parametrize("Om", [0.3, 0.7, 1.0, 1.6])
def test_linear_limit_frf(b_r, Om):
    zeta, kappa, f_m, f_p = 0.05, 0.5, 0.2, 0.2
    p = ex.ImpactParams(zeta, kappa, f_m, f_p, b_r)
    orb = ex.periodic_orbit(p, Om, [0.0, 0.0])
    assert orb.converged and orb.flow.n_switches == 0
    offset, amp = ex.linear_frf(zeta, kappa, f_m, f_p, Om)
    # exact extrema of the harmonic orbit from a fine sample + closed form
    t = np.linspace(0.0, orb.period, 20001)
    q = ex.exact_dense(p, Om, orb.u0, 0.0, t, flow=orb.flow)[:, 0]
    assert 0.5 * (q.max() + q.min()) == pytest.approx(offset, abs=1e-8)
    assert 0.5 * (q.max() - q.min()) == pytest.approx(amp, rel=1e-7)
    assert np.allclose(orb.u0, ex.linear_periodic_state(zeta, kappa, f_m, f_p, Om), rtol=0, atol=1e-12)
    # linear Floquet multipliers: exp(lambda T), lambda = -zeta +- i sqrt(kappa - zeta^2)
    lam = -zeta + 1j * np.sqrt(kappa - zeta ** 2)
    mu = np.exp(lam * orb.period)
    assert np.allclose(np.sort_complex(orb.floquet), np.sort_complex(np.array([mu, mu.conjugate()])), rtol=0, atol=1e-12)


# ---------------------------------------------------------------------------
# tangential grazes: shallow penetrations between grid samples are still found
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("pen", [-1e-8, 1e-10, 1e-8, 1e-4, 1e-2])
def test_grazing_penetration_detected(pen):
    """Free undamped motion q = A sin(w t) in the clearance (w = sqrt(kappa)): it enters
    contact iff A > b_r, first at t = arcsin(b_r / A) / w.  Penetrations of 1e-10 last
    ~4e-5 time units, far below the sampling grid (~0.14), and must still be found."""
    kappa, b = 0.5, 1.0
    w = np.sqrt(kappa)
    A = b + pen
    p = ex.ImpactParams(0.0, kappa, 0.0, 0.0, b)
    fl = ex.exact_flow(p, 0.3, [0.0, A * w], 0.0, np.pi / w)
    if pen < 0:
        assert fl.n_switches == 0
    else:
        assert fl.n_switches == 2 and list(fl.switch_to) == [1, 0]
        assert fl.switch_times[0] == pytest.approx(np.arcsin(b / A) / w, abs=1e-11)  # measured <= 4e-12
        # symmetric contact arc (undamped, unforced): exit mirrors entry about the apex
        t_apex_c = fl.switch_times.mean()
        assert fl.switch_states[1, 1] == pytest.approx(-fl.switch_states[0, 1], rel=1e-6, abs=1e-12)
        assert t_apex_c > fl.switch_times[0]
