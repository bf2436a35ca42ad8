"""Periodic orbits of a loose-gear model (a free gear with no restoring force in its
backlash) against independent references: the closed-form forced response, finite
differences of the flow, and settled time integration.

The model (two modes, dimensionless): the driving gear's vibration x0 (x0'' + 2 zeta x0' +
x0 = f cos(W t)) and the free gear's angle x1 (no stiffness, viscous drag c, optional drag
torque d), coupled by the backlash contact on delta = x1 - x0 (gaps +-b, stiffness k).

* Floating (d = 0, small f): the free gear rests anywhere in the backlash while x0
  oscillates, so the orbit is one of a family: shifting x1 is neutral, M has the trivial
  multiplier 1 and M - I is singular.  Shooting borders the neutral direction out;
  the orbit and all four multipliers are known in closed form; the family ends where
  |x1| + A(W) = b (grazing).
* Rattle (d = 0.1, f = 1): the free gear is thrown off its drag flank and hits both flanks
  once per period; the branch period-doubles at W ~ 1.122 and the period-2 branch again
  at W ~ 1.100 (a cascade), which settled integrations confirm (period 1, 2, 4).
"""
from __future__ import annotations

import numpy as np
import pytest

from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel
from vibrogear.solvers.periodic.continuation import (ContinuationOptions, PeriodicOrbitProblem,
                                            PseudoArclength, continuation)
from vibrogear.solvers.periodic.floquet import neutral_directions, split_trivial
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.periodic.shooting import periodic_flow, shoot
from vibrogear.status import Status
from vibrogear.solvers.sequential.sweep import classify_period
from vibrogear.config.options import ShootingOptions

OPT = IntegrationOptions(rtol=1e-10, atol=1e-12)
ZETA, C_DRAG, B, K = 0.05, 0.2, 1.0, 20.0


def loose_gear_model(f: float, d: float = 0.0) -> ReducedModel:
    one = np.ones(1)
    z = np.zeros((1, 1))
    contacts = ContactSet(directions=np.array([[-1.0, 1.0]]), k_hi=K * one, k_lo=K * one,
                          gap_hi=B * one, gap_lo=-B * one, exponent=one.copy(),
                          damping=0.0 * one, stiffness_cos=z, stiffness_sin=z, error_cos=z,
                          error_sin=z, names=("backlash",))
    forcing = Forcing(F0=np.array([0.0, -d]), Fc=np.array([[f, 0.0]]), Fs=np.zeros((1, 2)))
    return ReducedModel(omega2=np.array([1.0, 0.0]), damping=np.array([2 * ZETA, C_DRAG]),
                        coupling=LinearCoupling.none(2), forcing=forcing, contacts=contacts,
                        name="loose_gear", state_names=("x0", "x1", "x0'", "x1'"))


def fd_monodromy(model, param, u0, n_periods=1, h=1e-6):
    """Central differences of the flow map over the period (integrate only, no
    variational equations)."""
    T = n_periods * model.excitation_period(param)
    n = u0.size
    M = np.empty((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        up = integrate(model, param, u0 + e, 0.0, T, options=OPT).u_end
        um = integrate(model, param, u0 - e, 0.0, T, options=OPT).u_end
        M[:, j] = (up - um) / (2 * h)
    return M


def _closed_form_floating(W, f, s):
    """The floating orbit at phase 0: x0 = Re(X e^{iWt}), x1 = s, and its multipliers."""
    X = f / (1.0 - W ** 2 + 2j * ZETA * W)
    T = 2 * np.pi / W
    lam = -ZETA + 1j * np.sqrt(1 - ZETA ** 2)
    mu = np.array([np.exp(lam * T), np.exp(np.conj(lam) * T), 1.0, np.exp(-C_DRAG * T)])
    return np.array([X.real, s, -W * X.imag, 0.0]), mu, abs(X)


# ------------------------------------------------------------------ floating free gear

F_FLOAT, S_FLOAT = 0.2, 0.3


@pytest.fixture(scope="module")
def floating():
    return loose_gear_model(F_FLOAT)


def test_floating_orbit_is_a_family_that_shooting_borders_out(floating):
    W = 0.5
    guess = np.array([0.0, S_FLOAT, 0.0, 0.0])
    # the plain shooting Jacobian is singular: a column of M - I vanishes (x1 shift)
    flow = periodic_flow(floating, W, guess, options=OPT)
    s = np.linalg.svd(flow.dG_du0, compute_uv=False)
    assert s[-1] <= 1e-12 * s[0]
    sh = shoot(floating, W, guess, options=OPT, shooting=ShootingOptions(tol=1e-11))
    assert sh.converged, sh.message
    u_ex, mu_ex, amp = _closed_form_floating(W, F_FLOAT, S_FLOAT)
    assert amp + S_FLOAT < B                      # really floating: no contact
    assert sh.impacts == 0
    # the phase condition keeps the free gear where it started; the orbit is exact
    assert np.max(np.abs(sh.u0 - u_ex)) < 1e-8
    # multipliers: closed form and finite differences of the flow
    assert np.max(np.abs(np.sort_complex(sh.floquet) - np.sort_complex(mu_ex))) < 1e-8
    mu_fd = np.linalg.eigvals(fd_monodromy(floating, W, sh.u0))
    assert np.max(np.abs(np.sort_complex(sh.floquet) - np.sort_complex(mu_fd))) < 1e-6
    # the trivial multiplier is reported as such and left out of the stability verdict
    assert sh.neutral == 1
    assert abs(sh.trivial_multipliers[0] - 1.0) < 1e-12
    nontrivial, _ = split_trivial(sh.floquet, sh.neutral)
    assert np.max(np.abs(nontrivial)) < 1.0 and sh.stable
    V, B_left = neutral_directions(sh.monodromy, floating.omega2)
    assert V.shape == (4, 1) and abs(abs(V[1, 0]) - 1.0) < 1e-12     # the x1 shift
    assert np.linalg.norm(B_left.T @ (sh.monodromy - np.eye(4))) < 1e-10


def test_floating_branch_ends_at_the_closed_form_grazing(floating):
    W0 = 0.3
    sh = shoot(floating, W0, np.array([0.0, S_FLOAT, 0.0, 0.0]), options=OPT)
    res = continuation(PeriodicOrbitProblem(floating, sh.u0, W0, direction=1),
                       PseudoArclength(integration=OPT, tol=1e-9),
                       ContinuationOptions(param_min=0.2, param_max=1.5, ds=0.02,
                                           ds_max=0.05))
    br = res.branches[0]
    assert br.status == Status.GRAZING_END, br.message
    assert res.status.success
    assert len(br.points) > 5
    # every point: the family (one trivial multiplier), orbitally stable, free gear at s
    assert all(p.neutral == 1 and p.stable for p in br.points)
    assert max(abs(p.u0[1] - S_FLOAT) for p in br.points) < 1e-10
    # grazing where |x1| + A(W) = b: A(W_g) = b - s, the lower root of the response curve
    y = np.roots([1.0, 4 * ZETA ** 2 - 2.0, 1.0 - (F_FLOAT / (B - S_FLOAT)) ** 2])
    w_graze = float(np.sqrt(np.min(y.real)))
    last = br.points[-1]
    assert last.param <= w_graze + 1e-6
    assert abs(last.param - w_graze) < 1e-3
    for p in br.points[::4]:
        u_ex, mu_ex, _ = _closed_form_floating(p.param, F_FLOAT, S_FLOAT)
        assert np.max(np.abs(p.u0 - u_ex)) < 1e-7
        assert np.max(np.abs(np.sort_complex(p.floquet) - np.sort_complex(mu_ex))) < 1e-7


# ------------------------------------------------------------------ rattling free gear

@pytest.fixture(scope="module")
def rattle():
    model = loose_gear_model(1.0, d=0.1)
    W0 = 1.2
    warm = integrate(model, W0, np.array([0.0, -1.0, 0.0, 0.0]), 0.0,
                     400 * model.excitation_period(W0), options=OPT)
    res = continuation(PeriodicOrbitProblem(model, warm.u_end, W0, direction=-1),
                       PseudoArclength(integration=OPT, tol=1e-9),
                       ContinuationOptions(param_min=1.05, param_max=1.3, ds=0.02,
                                           ds_max=0.05))
    return model, res


def _settled_period(model, W, max_period=8):
    T = model.excitation_period(W)
    warm = integrate(model, W, np.array([0.0, -1.0, 0.0, 0.0]), 0.0, 600 * T, options=OPT)
    R = 32
    rec = integrate(model, W, warm.u_end, 0.0, R * T, t_eval=np.arange(R + 1) * T,
                    options=OPT)
    return classify_period(rec.u, max_period, 1e-6, split=2)[0], rec


def test_rattle_orbit_multipliers_against_finite_differences(rattle):
    model, res = rattle
    b1 = res.branches[0]
    pts = [p for p in b1.points if not p.label][::6]
    assert len(pts) >= 3
    for p in pts:
        assert p.neutral == 0 and p.impacts >= 1     # it touches: an isolated orbit
        mu_fd = np.linalg.eigvals(fd_monodromy(model, p.param, p.u0))
        assert np.max(np.abs(np.sort_complex(p.floquet) - np.sort_complex(mu_fd))) < 1e-5


def test_rattle_cascade_agrees_with_settled_integration(rattle):
    model, res = rattle
    b1, b2 = res.branches[0], res.branches[1]
    pd1 = [p.param for p in b1.points if p.label == "PD"]
    assert len(pd1) == 1 and b2.n_periods == 2
    # the period-2 branch goes on through its own PD (the cascade's next step) to its end
    assert b2.status in (Status.REJOINED, Status.LEFT_RANGE), b2.message
    pd2 = [p.param for p in b2.points if p.label == "PD"]
    assert len(pd2) >= 1 and pd2[0] < pd1[0]
    assert b2.points[-1].label != "PD"                       # not ended at the PD
    # a multiplier at -1 at each PD (finite differences of the flow, 1 and 2 periods)
    p1 = next(p for p in b1.points if p.label == "PD")
    p2 = next(p for p in b2.points if p.label == "PD")
    for p, n in ((p1, 1), (p2, 2)):
        mu_fd = np.linalg.eigvals(fd_monodromy(model, p.param, p.u0, n_periods=n))
        assert np.min(np.abs(mu_fd + 1.0)) < 1e-3
    # settled motion: period 1 above the first PD, 2 between, 4 below the second
    W1 = 0.5 * (pd1[0] + b1.points[0].param)
    n1, rec1 = _settled_period(model, W1)
    assert n1 == 1
    q = min(b1.points, key=lambda p: abs(p.param - W1))
    assert _settled_period(model, 0.5 * (pd1[0] + pd2[0]))[0] == 2
    assert _settled_period(model, pd2[0] - 0.005)[0] == 4
    # the stable period-1 orbit is where the settled motion goes
    sh = shoot(model, W1, rec1.u[-1], options=OPT)
    assert sh.converged and sh.stable and sh.neutral == 0
    assert np.max(np.abs(sh.u0 - rec1.u[-1])) < 1e-6
    assert q.stable


def test_starting_orbit_uses_the_settled_period():
    """The continuation analysis starts from the period the sweep's detector finds in the
    settled motion: period 2 between the two PDs of the rattle cascade."""
    from vibrogear.solvers.periodic.starting_orbit import starting_orbit

    model = loose_gear_model(1.0, d=0.1)
    u0, n, _, how = starting_orbit(model, 1.11, np.array([0.0, -1.0, 0.0, 0.0]),
                                   transient_periods=600, options=OPT, tol=1e-9, max_iter=20,
                                   period_tol=1e-6)
    assert n == 2 and "settled" in how
    half = integrate(model, 1.11, u0, 0.0, model.excitation_period(1.11), options=OPT)
    full = integrate(model, 1.11, u0, 0.0, 2 * model.excitation_period(1.11), options=OPT)
    assert np.linalg.norm(full.u_end - u0) < 1e-7 < np.linalg.norm(half.u_end - u0)
