"""A general ReducedModel (low-rank coupling with spin-dependent gyroscopic/circulatory terms,
harmonic forcing, a dead-zone contact with transmission error and mesh-stiffness modulation,
a Hertzian one-sided contact) against an independent dense numpy right-hand side, and its
variational equations against finite differences; each with integer harmonic orders (1, 2)
and with fractional ones (1/2, 4/3: a torque order's slots, period 6 base periods)."""
from __future__ import annotations

import numpy as np
import pytest
from finite_differences import fd_shooting_jacobian
from scipy.integrate import solve_ivp

from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.periodic.shooting import periodic_flow
from vibrogear.solvers.static import static_equilibrium

M, R, H = 4, 2, 2


def _model(orders=None) -> ReducedModel:
    rng = np.random.default_rng(3)
    P = rng.standard_normal((R, M))
    S = rng.standard_normal((R, R))
    G = S - S.T                                  # skew: gyroscopic
    coupling = LinearCoupling(P=P, Kc0=np.diag([0.5, 0.3]), Kc1=0.05 * G, Bc0=np.diag([0.02, 0.01]),
                              Bc1=0.1 * G)
    forcing = Forcing(F0=np.array([0.2, 0.0, 0.1, 0.0]),
                      Fc=0.1 * rng.standard_normal((H, M)), Fs=0.1 * rng.standard_normal((H, M)))
    C = np.vstack([rng.standard_normal(M), rng.standard_normal(M)]) * 0.5
    contacts = ContactSet(
        directions=C, k_hi=np.array([3.0, 5.0]), k_lo=np.array([2.0, 0.0]),
        gap_hi=np.array([0.05, 0.02]), gap_lo=np.array([-0.1, -np.inf]),
        exponent=np.array([1.0, 1.5]), damping=np.array([0.0, 0.0]),
        stiffness_cos=np.array([[0.2, 0.05], [0.0, 0.0]]),
        stiffness_sin=np.array([[0.1, 0.0], [0.0, 0.0]]),
        error_cos=np.array([[0.02, 0.01], [0.0, 0.0]]),
        error_sin=np.array([[0.0, 0.015], [0.0, 0.0]]))
    return ReducedModel(omega2=np.array([1.0, 2.5, 4.0, 9.0]), damping=np.array([0.04, 0.05, 0.06, 0.1]),
                        coupling=coupling, forcing=forcing, contacts=contacts,
                        omega_per_param=2.0, spin_per_param=0.5, monitor=0,
                        harmonic_orders=orders)


def _dense_rhs(model: ReducedModel, param: float):
    """The same equations written out directly with dense numpy matrices."""
    cp, fo, ct = model.coupling, model.forcing, model.contacts
    W, s = model.omega_per_param * param, model.spin_per_param * param
    Klin = np.diag(model.omega2) + cp.P.T @ (cp.Kc0 + s * cp.Kc1) @ cp.P
    Blin = np.diag(model.damping) + cp.P.T @ (cp.Bc0 + s * cp.Bc1) @ cp.P
    h = model.harmonic_orders

    def f(t, u):
        x, v = u[:M], u[M:]
        c, sn = np.cos(h * W * t), np.sin(h * W * t)
        F = fo.F0 + c @ fo.Fc + sn @ fo.Fs
        e = ct.error_cos @ c + ct.error_sin @ sn
        ed = ct.error_cos @ (-h * W * sn) + ct.error_sin @ (h * W * c)
        mod = 1.0 + ct.stiffness_cos @ c + ct.stiffness_sin @ sn
        d = ct.directions @ x - e
        dd = ct.directions @ v - ed
        up = np.clip(d - ct.gap_hi, 0.0, None)
        lo = np.clip(ct.gap_lo - d, 0.0, None)
        fc = mod * (ct.k_hi * up ** ct.exponent - np.where(np.isfinite(ct.gap_lo), ct.k_lo * lo ** ct.exponent, 0.0))
        fc = fc + ct.damping * dd * ((up > 0) | (lo > 0))
        a = F - Blin @ v - Klin @ x - ct.directions.T @ fc
        return np.concatenate([v, a])
    return f


@pytest.fixture(scope="module", params=[None, (0.5, 4.0 / 3.0)], ids=["orders-1-2", "orders-1/2-4/3"])
def model(request):
    return _model(request.param)


def test_period_multiple_is_the_least_common_denominator():
    assert _model().period_multiple == 1
    m = _model((0.5, 4.0 / 3.0))
    assert m.period_multiple == 6
    assert m.excitation_period(1.3) == pytest.approx(6 * 2 * np.pi / (2.0 * 1.3), rel=1e-15)
    with pytest.raises(ValueError, match="ratio of integers"):
        _model((0.5, np.sqrt(2.0)))


def test_trajectory_matches_dense_reference(model):
    p = 1.3
    u0 = static_equilibrium(model, p).u0 + np.array([0.1, -0.05, 0.02, 0.0, 0.0, 0.1, 0.0, -0.1])
    t1 = 20.0
    t_eval = np.linspace(0, t1, 41)
    ours = integrate(model, p, u0, 0.0, t1, t_eval=t_eval,
                     options=IntegrationOptions(rtol=1e-11, atol=1e-13))
    assert ours.ok and ours.events > 4
    ref = solve_ivp(_dense_rhs(model, p), (0, t1), u0, method="DOP853", t_eval=t_eval,
                    rtol=1e-12, atol=1e-13, max_step=0.005)
    assert np.max(np.abs(ours.u - ref.y.T)) < 1e-7


def test_static_equilibrium_balances_the_mean_load(model):
    st = static_equilibrium(model, 1.3)
    assert st.converged
    # the mean-load balance: the dense acceleration with every harmonic term removed is zero
    m2 = ReducedModel(omega2=model.omega2, damping=model.damping, coupling=model.coupling,
                      forcing=Forcing(model.forcing.F0, 0 * model.forcing.Fc, 0 * model.forcing.Fs),
                      contacts=model.contacts.__class__(
                          **{**model.contacts.__dict__,
                             "stiffness_cos": 0 * model.contacts.stiffness_cos,
                             "stiffness_sin": 0 * model.contacts.stiffness_sin,
                             "error_cos": 0 * model.contacts.error_cos,
                             "error_sin": 0 * model.contacts.error_sin}),
                      omega_per_param=model.omega_per_param, spin_per_param=model.spin_per_param,
                      harmonic_orders=model.harmonic_orders)
    a = _dense_rhs(m2, 1.3)(0.0, st.u0)[M:]
    assert np.max(np.abs(a)) < 1e-10


def test_variational_equations_against_finite_differences(model):
    """Monodromy and d u(T)/d param (forcing, transmission error, mesh stiffness, spin,
    period) of a flow that crosses the contact switches."""
    p = 1.3
    u0 = static_equilibrium(model, p).u0 + np.array([0.1, -0.05, 0.02, 0.0, 0.0, 0.1, 0.0, -0.1])
    opt = IntegrationOptions(rtol=1e-12, atol=1e-14)
    f = periodic_flow(model, p, u0, options=opt)
    assert f.trajectory.events >= 2
    J, dp = fd_shooting_jacobian(model, p, u0, opt)
    assert np.max(np.abs(J - f.dG_du0)) < 1e-5 * (1 + np.max(np.abs(J)))
    assert np.max(np.abs(dp - f.dG_dparam)) < 1e-5 * (1 + np.max(np.abs(dp)))
