"""Engine-order torque fluctuation (``[[gearbox.couplings]] torque_orders``).

A torque order k of a shaft turning at p_s times the driving speed has the frequency
n W, n = k p_s / z (W the mesh frequency of the model's parameter, z the teeth of the
first mesh's gear_a): the reduced model carries it as a harmonic slot of order n, and the
excitation repeats after P mesh periods, P the least common denominator of the orders.

Independent references:
* a one-mode linear oscillator under a fractional order: the closed-form steady state
  X = F / (w0^2 - w^2 + i c w) is the periodic orbit that shooting finds, and its Floquet
  multipliers are exp(lambda T) over the whole period T = P 2 pi / W;
* the gear pair: the order's force is the static-load path's force of a torque step
  (two scenes with the static torque T0 +- A, the coupling's twist path, verified against
  torque and power in test_coupling_loads);
* the gear pair with its contacts closed: the periodic orbit under +A and under -A (phase
  180 deg), half their difference, equals the linear frequency response of the tangent
  system at the order's frequency (even nonlinear terms cancel in the half difference).
"""
from __future__ import annotations

import dataclasses
import math
from fractions import Fraction

import numpy as np
import pytest

from vibrogear.config import ConfigError, load_scene
from vibrogear.models.gearbox.model import build_gearbox
from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.linear import tangent_matrices
from vibrogear.solvers.periodic.shooting import ShootingOptions, periodic_flow, shoot
from vibrogear.solvers.static import static_equilibrium

SCENE = "configs/gear_pair.toml"
OPT = IntegrationOptions(rtol=1e-11, atol=1e-14)


def _oscillator(order: float, c: float = 0.1) -> ReducedModel:
    """x'' + c x' + x = 0.3 cos(n W t) + 0.1 sin(n W t), n = ``order`` (slot 2; slot 1 is
    an empty integer harmonic), W = param."""
    return ReducedModel(omega2=np.array([1.0]), damping=np.array([c]),
                        coupling=LinearCoupling.none(1),
                        forcing=Forcing(np.zeros(1), np.array([[0.0], [0.3]]),
                                        np.array([[0.0], [0.1]])),
                        contacts=ContactSet.empty(1, 2), omega_per_param=1.0,
                        harmonic_orders=(1.0, order))


def test_oscillator_orbit_and_multipliers_equal_the_closed_form():
    order, c, p = 2.0 / 3.0, 0.1, 1.2
    model = _oscillator(order, c)
    assert model.period_multiple == 3
    T = model.excitation_period(p)
    assert T == pytest.approx(3 * 2 * math.pi / p, rel=1e-15)
    w = order * p
    X = (0.3 - 0.1j) / (1.0 - w * w + 1j * c * w)
    exact = np.array([X.real, (1j * w * X).real])
    sh = shoot(model, p, np.zeros(2), options=OPT, shooting=ShootingOptions(tol=1e-12))
    assert sh.converged
    assert np.max(np.abs(sh.u0 - exact)) < 1e-9 * np.max(np.abs(exact))
    # the orbit: x(t) = Re(X e^{i w t}) at 30 times over the whole period
    t = np.linspace(0.0, T, 31)
    tr = integrate(model, p, exact, 0.0, T, t_eval=t, options=OPT)
    assert np.max(np.abs(tr.u[:, 0] - (X * np.exp(1j * w * t)).real)) < 1e-9 * abs(X)
    lam = -c / 2 + 1j * math.sqrt(1 - c * c / 4)
    mu = np.sort_complex(np.linalg.eigvals(periodic_flow(model, p, exact, options=OPT).monodromy))
    ref = np.sort_complex(np.exp(np.array([lam, lam.conjugate()]) * T))
    assert np.max(np.abs(mu - ref)) < 1e-8


def _teeth(sc, gear: str) -> int:
    return next(g.teeth for g in sc.gearbox.gears if g.name == gear)


def test_gear_pair_order_slots_and_period():
    """Order 1 and 1/2 of the motor (driving shaft, p = 1) and order 2 of the load shaft
    (p = z_a / z_b): n = k p_s / z_a, P = lcm of the denominators (read from the scene's
    teeth, not from the model)."""
    sc = load_scene(SCENE, ("gearbox.couplings[0].torque_orders=[[1.0, 2.0], [0.5, 1.0, 30]]",
                            "gearbox.couplings[1].torque_orders=[[2.0, 4.0]]"))
    mesh = sc.gearbox.meshes[0]
    za, zb = _teeth(sc, mesh.gear_a), _teeth(sc, mesh.gear_b)
    gm = build_gearbox(sc)
    r = gm.reduced
    n = [Fraction(1, za), Fraction(1, 2 * za), Fraction(2, zb)]
    assert np.allclose(r.harmonic_orders[-3:], [float(x) for x in n], rtol=1e-15)
    assert r.period_multiple == math.lcm(*(x.denominator for x in n))
    assert [t["coupling"] for t in gm.torque_orders] == ["motor", "motor", "load"]
    assert gm.torque_orders[1]["phase_deg"] == 30.0
    # the contacts carry no stiffness or error harmonics in the order slots
    ct = r.contacts
    for a in (ct.stiffness_cos, ct.stiffness_sin, ct.error_cos, ct.error_sin):
        assert not np.any(a[:, -3:])


@pytest.mark.parametrize("coupling, stiffness", [(0, 2.5e3), (1, 1.0e4)])
def test_order_force_is_the_static_path_of_a_torque_step(coupling, stiffness):
    """The order's amplitude A (phase 0) acts as a torque step A does on the static load:
    Fc[slot] = (F0(T0 + A) - F0(T0 - A)) / 2 to 1e-12, motor and load (static correction
    off, so that the basis does not depend on the load)."""
    T0, A = 62.5 if coupling == 0 else 250.0, 2.0

    def f0(T):
        s = load_scene(SCENE, (f"gearbox.couplings[{coupling}].twist={T / stiffness!r}",))
        return build_gearbox(s, static_correction=False).reduced.forcing.F0
    sc = load_scene(SCENE, (f"gearbox.couplings[{coupling}].torque_orders=[[1.0, {A}]]",))
    r = build_gearbox(sc, static_correction=False).reduced
    step = (f0(T0 + A) - f0(T0 - A)) / 2
    assert np.max(np.abs(r.forcing.Fc[-1] - step)) <= 1e-12 * np.max(np.abs(step))
    assert not np.any(r.forcing.Fs[-1])


def test_gear_pair_orbit_equals_the_linear_response_at_the_order():
    """Contacts closed (mesh-stiffness and error harmonics removed, A = 0.05 N m on 62.5):
    (orbit(+A) - orbit(-A)) / 2 = the tangent system's response at the order frequency
    2 W / z_a, to 1e-6 of its size; the mean (orbit(+A) + orbit(-A)) / 2 is the static
    state to second order in A."""
    rpm, A = 3000.0, 0.05

    def model(phase):
        sc = load_scene(SCENE, (f"gearbox.couplings[0].torque_orders=[[2.0, {A}, {phase}]]",))
        r = build_gearbox(sc).reduced
        zero = {k: np.zeros_like(getattr(r.contacts, k)) for k in
                ("stiffness_cos", "stiffness_sin", "error_cos", "error_sin")}
        return dataclasses.replace(r, contacts=dataclasses.replace(r.contacts, **zero))
    plus, minus = model(0.0), model(180.0)
    st = static_equilibrium(plus, rpm)
    orbits = []
    for r in (plus, minus):
        sh = shoot(r, rpm, st.u0, options=IntegrationOptions(rtol=1e-10, atol=1e-13),
                   shooting=ShootingOptions(tol=1e-11))
        assert sh.converged
        orbits.append(sh.u0)
    half = (orbits[0] - orbits[1]) / 2
    K, D = tangent_matrices(plus, st.u0, rpm)
    w = plus.harmonic_orders[-1] * plus.excitation_frequency(rpm)
    m = plus.n_modes
    X = np.linalg.solve(K - w * w * np.eye(m) + 1j * w * D,
                        plus.forcing.Fc[-1] - 1j * plus.forcing.Fs[-1])
    lin = np.concatenate([X.real, (1j * w * X).real])
    assert np.max(np.abs(half - lin)) < 1e-6 * np.max(np.abs(lin))
    assert np.max(np.abs((orbits[0] + orbits[1]) / 2 - st.u0)) < 1e-3 * np.max(np.abs(lin))


@pytest.mark.parametrize("value, path, words", [
    ("[[1.0]]", "torque_orders[0]", "expected [order, amplitude"),
    ("[[0.0, 1.0]]", "torque_orders[0][0]", "order must be a number > 0"),
    ("[[0.123456, 1.0]]", "torque_orders[0][0]", "ratio of integers"),
    ("[[1.0, -2.0]]", "torque_orders[0][1]", "amplitude must be"),
    ("[[1.0, 2.0, nan]]", "torque_orders[0][2]", "finite number"),
    ("[[1.0, 2.0, 3.0, 4.0]]", "torque_orders[0]", "got 4 numbers"),
])
def test_bad_torque_orders_name_the_entry(value, path, words):
    with pytest.raises(ConfigError) as exc:
        load_scene(SCENE, (f"gearbox.couplings[0].torque_orders={value}",))
    assert exc.value.path == f"gearbox.couplings[0].{path}"
    assert words in str(exc.value)


def test_constant_speed_ramp_continues_the_fractional_phase():
    """The run-up solver at a constant speed restarts each chunk's local time; with order
    2/3 (whole period = 3 base periods) its samples must still follow the closed-form
    steady state over 7.5 base periods (chunks of a quarter base period)."""
    from vibrogear.solvers.sequential.ramp import SpeedProfile, ramp
    order, c, p = 2.0 / 3.0, 0.1, 1.2
    base = _oscillator(order, c)
    probe = ContactSet(directions=np.array([[1.0]]), k_hi=np.zeros(1), k_lo=np.zeros(1),
                       gap_hi=np.array([-1e6]), gap_lo=np.array([-np.inf]),
                       exponent=np.ones(1), damping=np.zeros(1),
                       stiffness_cos=np.zeros((1, 2)), stiffness_sin=np.zeros((1, 2)),
                       error_cos=np.zeros((1, 2)), error_sin=np.zeros((1, 2)))
    model = dataclasses.replace(base, contacts=probe)   # samples x itself, exerts nothing
    w = order * p
    X = (0.3 - 0.1j) / (1.0 - w * w + 1j * c * w)
    u0 = np.array([X.real, (1j * w * X).real])
    T = 7.5 * model.base_period(p)
    r = ramp(model, SpeedProfile(np.array([0.0, T]), np.array([p, p])), u0, options=OPT,
             chunks_per_period=4, samples_per_period=16)
    assert r.ok
    exact = (X * np.exp(1j * w * r.t)).real
    assert r.t.size >= 100
    assert np.max(np.abs(r.delta[0] - exact)) < 1e-8 * abs(X)


def test_an_excitation_period_too_long_is_refused_naming_the_coupling():
    """Order 1/11 of the 40-tooth pinion's shaft is 1/440 of the mesh frequency, order
    1/7 of the 80-tooth wheel's 1/560 (p = 1/2): together lcm(440, 560) = 6160 mesh periods
    > 1000."""
    with pytest.raises(ConfigError) as exc:
        load_scene(SCENE, ("gearbox.couplings[0].torque_orders=[[0.09090909090909091, 1.0]]",
                           "gearbox.couplings[1].torque_orders=[[0.14285714285714285, 1.0]]"))
    assert exc.value.path == "gearbox.couplings[1].torque_orders"
    assert "6160 mesh periods" in str(exc.value)


def test_divergence_scale_bounds_the_order_response():
    """A torque order drives the shafts' rigid rotations (held by the coupling springs in
    the low-rank part, no modal stiffness of their own): the integrator's divergence scale
    stays finite and bounds the mesh's linear response to the order at every speed of
    the gear pair's range (its resonances included, 500-8000 rpm)."""
    from vibrogear.solvers.integrator.trust import deformation_scale
    A = 20.0
    r = build_gearbox(load_scene(SCENE, (f"gearbox.couplings[0].torque_orders=[[2.0, {A}]]",))
                      ).reduced
    scale = deformation_scale(r)
    assert np.all(np.isfinite(scale))
    st = static_equilibrium(r, 0.0)
    c = r.contacts.directions[0]
    worst = 0.0
    for rpm in np.linspace(500.0, 8000.0, 301):
        K, D = tangent_matrices(r, st.u0, rpm)
        w = r.harmonic_orders[-1] * r.excitation_frequency(rpm)
        X = np.linalg.solve(K - w * w * np.eye(r.n_modes) + 1j * w * D, r.forcing.Fc[-1])
        worst = max(worst, abs(c @ X))
    assert worst > 0.0 and worst <= scale[0]
