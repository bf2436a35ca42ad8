"""A multi-frequency model (meshes at their own frequencies, sampled per base period) carries
the forcing's phase from one integration to the next (``ReducedModel.phase_time``): a record
in chunks equals one continuous integration, where restarting each chunk at time 0 jumped the
phase of the slower mesh (a 0.8 % state error per restart on the FVA gearbox, and a dynamic
factor of 1.10 at 543 rpm where the continuous response has 1.001)."""
from __future__ import annotations

import numpy as np
import pytest

from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate

ORDERS = np.array([1.0, 23.0 / 51.0])         # a second mesh at 23/51 of the first's frequency
OPT = IntegrationOptions(rtol=1e-11, atol=1e-14)


def _oscillator(period_limit):
    """x'' + 0.02 x' + 0.3 x = cos(W t) + 0.5 cos(23/51 W t)."""
    forcing = Forcing(F0=np.zeros(1), Fc=np.array([[1.0], [0.5]]), Fs=np.zeros((2, 1)))
    return ReducedModel(omega2=np.array([0.3]), damping=np.array([0.02]),
                        coupling=LinearCoupling.none(1), forcing=forcing,
                        contacts=ContactSet.empty(1, 2), harmonic_orders=ORDERS,
                        period_limit=period_limit)


def test_phase_time_is_the_elapsed_periods_modulo_the_common_period():
    m = _oscillator(period_limit=16)
    assert m.multi_frequency and m.period_multiple == 1 and m.forcing_period_multiple == 51
    T = m.excitation_period(1.0)
    assert m.phase_time(0, 1.0) == 0.0
    assert m.phase_time(7, 1.0) == pytest.approx(7 * T, rel=1e-15)
    assert m.phase_time(51 + 7, 1.0) == pytest.approx(7 * T, rel=1e-15)
    whole = _oscillator(period_limit=None)             # spans its 51 base periods: always 0
    assert not whole.multi_frequency and whole.phase_time(7, 1.0) == 0.0


def test_chunks_from_their_phase_time_equal_one_continuous_integration():
    m = _oscillator(period_limit=16)
    T = m.excitation_period(1.0)
    u = np.array([0.1, 0.0])
    continuous = integrate(m, 1.0, u, 0.0, 12 * T, options=OPT).u_end
    chained, restarted = u.copy(), u.copy()
    for k in range(3):                                  # three chunks of 4 periods
        t0 = m.phase_time(4 * k, 1.0)
        chained = integrate(m, 1.0, chained, t0, t0 + 4 * T, options=OPT).u_end
        restarted = integrate(m, 1.0, restarted, 0.0, 4 * T, options=OPT).u_end
    scale = np.linalg.norm(continuous)
    assert np.linalg.norm(chained - continuous) < 1e-8 * scale
    assert np.linalg.norm(restarted - continuous) > 1e-2 * scale   # the jump it replaces


def test_a_sweeps_next_speed_continues_the_forcing_where_the_last_speed_left_it():
    """A sweep's next point is at another speed.  Every forcing frequency is a multiple of
    the speed, so after n excitation periods the forcing's phase is the same at any speed:
    continuing from ``end_phase`` (n) at the new speed is the response to a forcing whose
    speed steps while its phase runs on.  Reference: scipy's solve_ivp on x'' + 0.02 x' +
    0.3 x = cos(theta) + 0.5 cos(23/51 theta), theta(t) = W t up to the step and
    W t1 + W' (t - t1) after it (independent of the model's forcing code)."""
    from types import SimpleNamespace

    from scipy.integrate import solve_ivp

    from vibrogear.solvers.sequential.sweep_point import end_phase

    m = _oscillator(period_limit=16)
    W, W2, n1, n2 = 1.0, 1.3, 10, 6
    T, T2 = m.excitation_period(W), m.excitation_period(W2)
    u = np.array([0.1, 0.0])
    t0 = m.phase_time(0, W)
    first = integrate(m, W, u, t0, t0 + n1 * T, options=OPT)
    rec = SimpleNamespace(u_end_t=m.phase_time(n1, W), param=W, ok=True)
    n = end_phase(m, rec)
    assert n == n1 % 51
    ts = m.phase_time(n, W2)
    carried = integrate(m, W2, first.u_end, ts, ts + n2 * T2, options=OPT).u_end
    restarted = integrate(m, W2, first.u_end, 0.0, n2 * T2, options=OPT).u_end
    t1 = n1 * T

    def rhs(t, y):
        th = W * t if t <= t1 else W * t1 + W2 * (t - t1)
        f = np.cos(th) + 0.5 * np.cos(23.0 / 51.0 * th)
        return [y[1], f - 0.02 * y[1] - 0.3 * y[0]]

    ref = u.copy()
    for a, b in ((0.0, t1), (t1, t1 + n2 * T2)):
        ref = solve_ivp(rhs, (a, b), ref, rtol=1e-11, atol=1e-14, method="DOP853").y[:, -1]
    scale = np.linalg.norm(ref)
    assert np.linalg.norm(carried - ref) < 1e-7 * scale
    assert np.linalg.norm(restarted - ref) > 1e-2 * scale     # the phase jump it replaces
    assert end_phase(_oscillator(period_limit=None), rec) == 0  # one common period: none
