"""The scipy baseline of the benchmarks (benchmarks/scipy_baseline.py) evaluates the same
vector field as the compiled kernel: its dense numpy right-hand side against
``kernels.accel`` called directly with the packed model arrays (contact modes from the
state, as the compiled loop sets them at its start), on the impact pair and on a random
12-mode model with spin-dependent low-rank coupling and every kind of contact law."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

from scipy_baseline import dense_rhs, solve_points_scipy  # noqa: E402

from vibrogear.models.impact_pair import impact_pair_model  # noqa: E402
from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel  # noqa: E402
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate  # noqa: E402
from vibrogear.solvers.integrator.kernels import accel, contact_modes, model_arrays  # noqa: E402


def kernel_rhs(model, param, t, u):
    """u' from the compiled kernel, with the modes the integrator would start with."""
    A, Om, _, _, _ = model_arrays(model, param)
    m, nc, H, r = model.n_modes, model.contacts.count, model.n_harmonics, A.P.shape[0]
    mode = np.zeros(nc, np.int64)
    contact_modes(A, t, Om, np.ascontiguousarray(u[:m]), mode)
    out = np.empty(2 * m)
    work = [np.empty(nc) for _ in range(4)]         # Cx, Cv, kd, cd
    accel(t, np.ascontiguousarray(u), mode, A, Om, np.empty(H), np.empty(H), out, *work,
          np.empty(2 * (r + nc + m) + 1))
    return out, mode


def term_bound(f, t, u):
    """Sum of the magnitudes of every term of u' (the scale of its rounding errors)."""
    m = f.m
    _, _, force = f.contact_forces(t, u) if f.C.shape[0] else (0, 0, np.zeros(0))
    cs = f._trig(t)
    b = np.abs(f.A) @ np.abs(u)
    b[m:] += np.abs(f.F0) + np.abs(cs) @ np.abs(f.Fcs) + np.abs(f.C.T) @ np.abs(force)
    return b


def assert_same_field(model, param, states, times):
    f = dense_rhs(model, param)
    seen = set()
    for t, u in zip(times, states):
        ref, mode = kernel_rhs(model, param, t, u)
        got = f(t, u)
        bound = term_bound(f, t, u)
        assert np.all(np.abs(got - ref) <= 1e-12 * bound), \
            f"max rel deviation {np.max(np.abs(got - ref) / bound):.2e} at t={t}"
        seen.update((j, int(md)) for j, md in enumerate(mode))
    return seen


def test_impact_pair_dense_rhs_matches_kernel():
    model = impact_pair_model(zeta=0.05, kappa=0.3, f_m=0.1, f_p=0.6, b_r=0.5,
                              contact_damping=0.2)
    rng = np.random.default_rng(0)
    states = np.column_stack([rng.uniform(-1.5, 1.5, 60), rng.normal(size=60)])
    seen = assert_same_field(model, 1.3, states, rng.uniform(0, 20, 60))
    assert seen == {(0, -1), (0, 0), (0, 1)}


M, R, H, NC = 12, 4, 3, 6


def random_model(seed: int = 11) -> ReducedModel:
    rng = np.random.default_rng(seed)
    w2 = np.sort(rng.uniform(0.5, 40.0, M))
    P = rng.normal(size=(R, M))
    S = rng.normal(size=(R, R))
    coupling = LinearCoupling(P=P, Kc0=S @ S.T / R + np.eye(R), Kc1=0.3 * rng.normal(size=(R, R)),
                              Bc0=0.05 * np.eye(R), Bc1=0.2 * (S - S.T))
    forcing = Forcing(F0=rng.normal(size=M), Fc=rng.normal(size=(H, M)),
                      Fs=rng.normal(size=(H, M)))
    inf = np.inf
    harm = [0.1 * rng.normal(size=(NC, H)) for _ in range(2)] + \
        [0.05 * rng.normal(size=(NC, H)) for _ in range(2)]
    for a in harm:
        a[2] = 0.0                                # one contact with neither harmonic
    contacts = ContactSet(
        directions=rng.normal(size=(NC, M)) / np.sqrt(M),
        k_hi=rng.uniform(1.0, 5.0, NC), k_lo=rng.uniform(1.0, 5.0, NC),
        gap_hi=np.array([0.1, 0.0, -0.05, 0.2, 0.05, 0.0]),
        gap_lo=np.array([-0.3, -inf, -inf, -0.1, -inf, -0.2]),
        exponent=np.array([1.0, 1.5, 10 / 9, 1.5, 1.0, 10 / 9]),
        damping=np.array([0.3, 0.0, 0.0, 0.2, 0.1, 0.0]),
        stiffness_cos=harm[0], stiffness_sin=harm[1], error_cos=harm[2], error_sin=harm[3])
    return ReducedModel(omega2=w2, damping=0.02 * np.sqrt(w2), coupling=coupling,
                        forcing=forcing, contacts=contacts, omega_per_param=1.7,
                        spin_per_param=0.8, monitor=0)


def test_random_model_dense_rhs_matches_kernel():
    model = random_model()
    ct = model.contacts
    # both kinds of the kernel: C1 Hertzian contacts (mode from the sign inside the kernel)
    # and event-switched ones (mode given)
    assert np.any((ct.exponent > 1) & (ct.damping == 0)) and np.any(ct.damping > 0)
    rng = np.random.default_rng(5)
    n = 400
    # displacements whose contact deformations spread over all regions (pinv: exact deltas)
    deltas = rng.uniform(-0.8, 0.8, size=(n, NC))
    x = deltas @ np.linalg.pinv(ct.directions).T + 0.1 * rng.normal(size=(n, M))
    states = np.hstack([x, rng.normal(size=(n, M))])
    param = 1.9
    seen = assert_same_field(model, param, states, rng.uniform(0.0, 10.0, n))
    for j in range(NC):
        want = {-1, 0, 1} if np.isfinite(ct.gap_lo[j]) else {0, 1}
        assert {md for (jj, md) in seen if jj == j} == want, f"contact {j} modes not all seen"


def test_solve_points_scipy_matches_integrator_on_impact_pair():
    model = impact_pair_model(zeta=0.05, kappa=0.3, f_m=0.1, f_p=0.6, b_r=0.5)
    params, u0 = [1.0, 1.1], np.array([0.5, 0.0])
    pts = solve_points_scipy(model, params, u0, periods=30, rtol=1e-9, atol=1e-11,
                             record_from=25)
    seed = u0
    opts = IntegrationOptions(rtol=1e-11, atol=1e-13)
    for p, pt in zip(params, pts):
        T = model.excitation_period(p)
        tr = integrate(model, p, seed, 0.0, 30 * T, options=opts, record_from=25 * T)
        seed = tr.u_end
        assert pt.ok and pt.rhs_calls > 0 and pt.wall_time > 0
        scale = tr.monitor_max - tr.monitor_min
        assert pt.monitor_min == pytest.approx(tr.monitor_min, abs=1e-5 * scale)
        assert pt.monitor_max == pytest.approx(tr.monitor_max, abs=1e-5 * scale)
        np.testing.assert_allclose(pt.u_end, tr.u_end, atol=1e-5)


def test_synthetic_gearbox_is_loaded_and_matches_kernel():
    from synthetic_gearbox import synthetic_gearbox
    model, u0 = synthetic_gearbox(m=60, n_contacts=21, seed=1)
    ct = model.contacts
    f = dense_rhs(model, 2500.0)
    _, _, force = f.contact_forces(0.0, u0)
    assert model.omega2[0] == 0.0 and np.sqrt(model.omega2[-1]) / (2 * np.pi) == pytest.approx(5.0)
    # the mesh carries the mean torque (statically, without the transmission error)
    assert ct.directions[0] @ u0[:60] * ct.k_hi[0] == pytest.approx(700.0, rel=1e-6)
    assert np.sum(force[1:] > 0.0) >= (ct.count - 1) // 2   # bearings preloaded / loaded
    assert np.all(ct.exponent[1:] == 1.5) and np.all(np.isinf(ct.gap_lo[1:]))
    rng = np.random.default_rng(2)
    states = u0 + rng.normal(size=(20, u0.size)) * np.concatenate([np.full(60, 2.0),
                                                                   np.full(60, 50.0)])
    assert_same_field(model, 2500.0, states, rng.uniform(0.0, 5.0, 20))
