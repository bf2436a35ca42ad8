"""Stiff and extreme impact-pair cases: a correct result or a clear failure status,
never NaN/inf in an output file, never a hang (every loop is bounded)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.periodic.continuation import (ContinuationOptions, PeriodicOrbitProblem,
                                            PseudoArclength, continuation)
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.periodic.shooting import shoot
from vibrogear.status import Status
from vibrogear.solvers.sequential.sweep import sweep
from vibrogear.config.options import SweepOptions
from vibrogear.verification.impact_exact import ImpactParams, linear_frf
from vibrogear.verification.impact_orbits import periodic_orbit
from vibrogear.config.options import ShootingOptions

OPT = IntegrationOptions(rtol=1e-10, atol=1e-12)


def _against_exact(par, omega, guess=None, n_periods=1):
    """Shoot from the exact orbit's neighbourhood; compare u0 and multipliers."""
    ip = ImpactParams(**par)
    ex = periodic_orbit(ip, omega, guess, n_periods=n_periods)
    assert ex.converged
    model = impact_pair_model(**par)
    sh = shoot(model, omega, ex.u0 * (1 + 1e-3) + 1e-3, n_periods=n_periods, options=OPT, shooting=ShootingOptions(tol=1e-11))
    assert sh.converged, sh.message
    assert np.max(np.abs(sh.u0 - ex.u0)) < 1e-6 * (1 + np.max(np.abs(ex.u0)))
    assert np.max(np.abs(np.sort_complex(sh.floquet) - np.sort_complex(ex.floquet))) < 1e-6
    return sh, ex


def test_pure_dead_zone_kappa_zero():
    """kappa = 0: no stiffness inside the clearance (free flight, pure rattle)."""
    sh, ex = _against_exact(dict(zeta=0.05, kappa=0.0, f_m=0.1, f_p=0.3, b_r=1.0), 0.8)
    assert sh.impacts >= 1 and ex.q_max > 1.0


def test_stiffness_ratio_1e4():
    """Outer/inner stiffness ratio 1e4 (kappa = 1e-4): stiff contact phases."""
    sh, ex = _against_exact(dict(zeta=0.05, kappa=1e-4, f_m=0.05, f_p=0.3, b_r=1.0), 0.7)
    assert sh.impacts >= 1


def test_undamped_orbit_exists_on_unit_circle():
    """zeta = 0: impacting periodic orbits still exist; det(M) = 1 and |mu| = 1."""
    par = dict(zeta=0.0, kappa=0.5, f_m=0.0, f_p=2.5, b_r=1.0)
    sh, ex = _against_exact(par, 1.5)
    assert ex.contact_sides == {1, -1} and sh.impacts == 2
    assert abs(np.prod(sh.floquet).real - 1.0) < 1e-8
    assert np.allclose(np.abs(sh.floquet), 1.0, atol=1e-6)
    assert not sh.stable                       # neutral, not asymptotically stable


def test_tiny_clearance_is_the_linear_system():
    """b_r = 1e-9: the dead zone vanishes; amplitude = FRF with stiffness kappa + (1 - kappa)."""
    par = dict(zeta=0.05, kappa=0.3, f_m=0.0, f_p=0.2, b_r=1e-9)
    model = impact_pair_model(**par)
    for om in (0.5, 1.2):
        warm = integrate(model, om, np.zeros(2), 0.0, 200 * 2 * np.pi / om, options=OPT)
        sh = shoot(model, om, warm.u_end, options=OPT, shooting=ShootingOptions(tol=1e-11))
        assert sh.converged
        amp = 0.5 * (sh.monitor_max - sh.monitor_min)
        _, ref = linear_frf(par["zeta"], 1.0, 0.0, par["f_p"], om)
        assert abs(amp - ref) < 1e-6 + 2e-9
        assert sh.impacts == 2                 # crosses the 2e-9 wide gap twice per period


def test_large_forcing_double_sided_impacts_and_chaos():
    """Large forcing: double-sided impacts; at Omega = 1.0 the motion is chaotic: the sweep
    says 'not periodic', and an independent Lyapunov estimate is positive."""
    par = dict(zeta=0.02, kappa=0.0, f_m=0.1, f_p=1.0, b_r=1.0)
    model = impact_pair_model(**par)
    res = sweep(model, [0.8, 1.0], SweepOptions(directions=("up",), transient_periods=200, record_periods=64, max_period=16, extra_transient_periods=0), options=IntegrationOptions(rtol=1e-8, atol=1e-10))
    assert res.period_n[0] == 1 and res.qmin[0] < -1 and res.qmax[0] > 1   # double-sided
    assert res.period_n[1] == 0 and res.clusters[1] > 16
    # largest Lyapunov exponent from the variational equations, renormalised per period
    T = 2 * np.pi / 1.0
    u = res.u_end[1].copy()
    v = np.array([1.0, 0.0])
    logs = 0.0
    n = 150
    for k in range(n):
        tr = integrate(model, 1.0, u, 0.0, T, options=IntegrationOptions(rtol=1e-9, atol=1e-11),
                       variational=True)
        assert tr.ok
        w = tr.monodromy @ v
        logs += np.log(np.linalg.norm(w))
        v = w / np.linalg.norm(w)
        u = tr.u_end
    lyap = logs / (n * T)
    assert lyap > 0.01
    # the sum of both exponents is the trace -2 zeta: the second one is negative
    assert lyap < 1.0


def test_bounded_work_gives_a_failure_status_not_a_hang():
    model = impact_pair_model(0.015, 0.5, 0.55, 0.12, 1.0)
    tr = integrate(model, 0.9, np.zeros(2), 0.0, 1000.0, options=IntegrationOptions(max_steps=50))
    assert tr.status == Status.MAX_STEPS and "maximum number of steps" in tr.message
    assert np.all(np.isfinite(tr.u_end))
    sh = shoot(model, 0.9, np.zeros(2), options=IntegrationOptions(max_steps=50))
    assert not sh.converged and sh.status == Status.MAX_STEPS
    res = continuation(PeriodicOrbitProblem(model, np.zeros(2), 0.9),
                       PseudoArclength(integration=IntegrationOptions(max_steps=50)),
                       ContinuationOptions(param_min=0.5, param_max=1.0))
    br = res.branches[0]
    assert res.status == br.status == Status.NO_START and not br.points
    assert "starting orbit" in res.message and "maximum number of steps" in res.message


def test_stiff_contact_damping_exhausts_the_step_budget():
    """Huge contact damping (1e6, a time scale of 1e-6) makes the contact phase stiff for an
    explicit method: the bounded step budget runs out inside the first contact and the run
    says so (MAX_STEPS), with a finite state, instead of hanging."""
    model = impact_pair_model(0.01, 0.0, 0.0, 0.5, 1e-3, contact_damping=1e6)
    tr = integrate(model, 1.0, np.array([0.0, 1.0]), 0.0, 50.0,
                   options=IntegrationOptions(rtol=1e-6, atol=1e-9, max_steps=200_000))
    assert tr.status == Status.MAX_STEPS and tr.steps == 200_000
    assert 0.0 < tr.t_end < 50.0 and tr.events >= 1 and np.all(np.isfinite(tr.u_end))


def test_chattering_contact_is_reported():
    """Events that follow each other with no regular step between them are reported as
    CHATTERING.  Crossing a 2e-9 wide clearance leaves one contact and enters the other
    within 1e-8 time units: two events back to back.  Allowing one event per regular step
    the run stops there (first crossing, t = 2.83); allowing two it completes (79 events),
    so the status comes from the event pile-up and nothing else."""
    model = impact_pair_model(0.05, 0.3, 0.0, 0.2, 1e-9)
    T = 20 * 2 * np.pi / 1.2
    tight = integrate(model, 1.2, np.zeros(2), 0.0, T,
                      options=IntegrationOptions(max_events_per_step=1))
    assert tight.status == Status.CHATTERING and "chattering" in tight.message
    assert tight.events == 2 and 2.8 < tight.t_end < 2.9 and np.all(np.isfinite(tight.u_end))
    loose = integrate(model, 1.2, np.zeros(2), 0.0, T,
                      options=IntegrationOptions(max_events_per_step=2))
    assert loose.status == Status.OK and loose.events > 50


@pytest.mark.parametrize("overrides", [          # two in the CI tier, the rest: make test-system
    ["impact_pair.kappa=0.0"],
    pytest.param(["impact_pair.zeta=0.0", "impact_pair.f_m=0.0", "impact_pair.f_p=0.05"],
                 marks=pytest.mark.system),
    ["impact_pair.b_r=1e-9"],
    pytest.param(["impact_pair.kappa=1e-4"], marks=pytest.mark.system),
    pytest.param(["impact_pair.f_p=1.0", "impact_pair.kappa=0.0", "impact_pair.f_m=0.1",
                  "impact_pair.zeta=0.02"], marks=pytest.mark.system),
])
def test_extreme_scenes_write_finite_files(tmp_path, overrides):
    out = tmp_path / "o"
    args = ["run", "configs/impact_pair.toml", "--quiet", "--out", str(out),
            "--set", "scene.analyses=[\"sweep\",\"continuation\"]",
            "--set", "sweep.n_points=6", "--set", "sweep.omega_min=0.7",
            "--set", "sweep.omega_max=1.2", "--set", "sweep.transient_periods=30",
            "--set", "continuation.omega_min=0.7", "--set", "continuation.omega_max=1.2",
            "--set", "continuation.max_points=60", "--set", "continuation.transient_periods=100"]
    for o in overrides:
        args += ["--set", o]
    code = main(args)
    assert code in (0, 1)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] in ("ok", "failed")
    for name in ("sweep.npz", "branch.npz"):
        if (out / name).exists():
            with np.load(out / name) as z:
                for k in z.files:
                    if z[k].dtype.kind in "fc":
                        assert np.all(np.isfinite(z[k])), (name, k)
    for name in ("sweep.csv", "branch.csv"):
        if (out / name).exists():
            text = (out / name).read_text().lower()
            assert "nan" not in text and "inf" not in text
