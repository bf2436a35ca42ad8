"""A sweep point's evidence against independent references.

* Largest Lyapunov exponent (two-trajectory Benettin, solvers/sequential/lyapunov.py) on stable
  periodic orbits = ln|mu_max| / T from the Floquet multipliers of the exact
  piecewise-linear solution (vibrogear/verification/impact_exact.py: closed form region by
  region, switch times by root finding) and, for the gear pair, of shooting's monodromy
  (variational equations with saltation: a different method from the two trajectories).
* On a chaotic impact pair (kappa = 0: a lightly loaded backlash pair) the exponent is
  positive with its interval above 0, whatever the perturbation size and tolerance.
* Impacts per period, approach speeds at onset, contact fraction and rattle energy of the
  sweep's metrics equal those of the exact periodic orbit.
* A transient stopped by the converged stroboscopic map gives the fixed-budget result
  within period_tol with fewer periods.
"""
from __future__ import annotations

import numpy as np
import pytest

from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.sequential.lyapunov import largest_lyapunov
from vibrogear.solvers.sequential.motion import CHAOTIC, PERIODIC
from vibrogear.solvers.sequential.sweep import sweep
from vibrogear.config.options import SweepOptions
from reference import impact_exact as ex  # the flow and the periodic orbits
from vibrogear.config.options import ShootingOptions

OPT = IntegrationOptions(rtol=1e-10, atol=1e-12)
#: configs/impact_pair.toml (zeta, kappa, f_m, f_p, b_r)
SCENE = (0.015, 0.5, 0.55, 0.12, 1.0)
#: tests/verification/test_impact_vs_exact.py's P_A (double-sided at 0.8) and P_B
P_A = (0.05, 0.5, 0.2, 0.2, 0.5)
P_B = (0.015, 0.1, 0.1, 0.1, 1.0)
#: no inner stiffness, light mean load: chaotic rattle for Omega ~ 0.95-1.2 (found by a
#: sweep: 32 distinct Poincare points, exponent ~ 0.1)
CHAOS = (0.015, 0.0, 0.1, 0.3, 1.0)


def _exact_orbit(prm, Om, n_periods=1, guess=None):
    p = ex.ImpactParams(*prm, 0.0)
    if guess is None:
        model = impact_pair_model(*prm)
        T = n_periods * 2 * np.pi / Om
        guess = integrate(model, Om, np.zeros(2), 0.0, 400 * T, options=OPT).u_end
    orb = ex.periodic_orbit(p, Om, guess, n_periods=n_periods)
    assert orb.converged and orb.stable
    return orb


@pytest.mark.parametrize("prm,Om,n,real", [(SCENE, 0.54, 1, True), (P_B, 0.85, 2, False)],
                         ids=["scene-near-PD", "P_B-period2"])
def test_lyapunov_equals_floquet_exponent_of_exact_orbit(prm, Om, n, real):
    orb = _exact_orbit(prm, Om, n)
    mu = np.abs(orb.floquet)
    ref = float(np.log(mu.max()) / orb.period)
    # real, distinct multipliers: ln|mu_max| / T differs from -zeta (the mean of the two);
    # a complex pair (the tangent rotates) has ln|mu| / T = -zeta exactly
    assert (abs(ref + prm[0]) > 0.2 * prm[0]) == real
    res = largest_lyapunov(impact_pair_model(*prm), Om, orb.u0, 96, options=OPT)
    lo, hi = res.ci
    assert res.ok and lo <= ref <= hi, (ref, res.exponent, res.ci)
    if real:   # measured: ref -0.00392, interval -0.00413 .. -0.00284
        assert hi - lo < abs(ref)
    else:      # measured: ref -0.015, interval -0.037 .. 0.005 (the tangent rotates)
        assert hi - lo < 4 * abs(ref)


def test_lyapunov_equals_floquet_exponent_of_gear_pair_orbit():
    from vibrogear.analyses.study import build_study
    from vibrogear.config import load_scene
    from vibrogear.solvers.periodic.shooting import shoot

    study = build_study(load_scene("configs/gear_pair.toml"))
    model, rpm = study.model, 5000.0
    opts = IntegrationOptions(rtol=1e-9, atol=1e-15)
    T = model.excitation_period(rpm)
    u = integrate(model, rpm, study.start(rpm), 0.0, 400 * T, options=opts).u_end
    orb = shoot(model, rpm, u, options=opts, shooting=ShootingOptions(tol=1e-10))
    assert orb.converged and orb.stable
    ref = float(np.log(np.abs(orb.floquet).max()) / T)     # -0.0032: |mu| = 0.9940
    # start along the last step of the stroboscopic map of the converging trajectory (what
    # the sweep does); two complex pairs (|mu| 0.9940, 0.9926, 45 deg per period) rotate
    # the tangent: the blocks scatter, the interval is wide (measured -0.024 .. 0.014)
    step = integrate(model, rpm, u, 0.0, T, options=opts).u_end - u
    res = largest_lyapunov(model, rpm, orb.u0, 192, options=opts, direction=step)
    lo, hi = res.ci
    assert res.ok and lo <= ref <= hi, (ref, res.exponent, res.ci)
    assert hi - lo < 0.05


def test_lyapunov_positive_on_chaotic_impact_pair():
    model, Om = impact_pair_model(*CHAOS), 1.1
    T = 2 * np.pi / Om
    u = integrate(model, Om, np.zeros(2), 0.0, 300 * T, options=OPT).u_end
    a = largest_lyapunov(model, Om, u, 96, options=OPT)
    b = largest_lyapunov(model, Om, u, 96, options=IntegrationOptions(rtol=1e-8, atol=1e-10),
                         d0=1e-8, seed=3)
    for r in (a, b):
        assert r.ok and r.ci[0] > 0.0, r.ci
    # two perturbation sizes, tolerances and start directions: the intervals overlap
    assert a.ci[0] <= b.ci[1] and b.ci[0] <= a.ci[1]
    # the sweep calls it chaotic with the same evidence
    s = sweep(model, [Om], SweepOptions(directions=("up",), transient_periods=200, record_periods=64, extra_transient_periods=0), options=OPT, u0=u)
    assert s.motion_class[0] == CHAOTIC and s.period_n[0] == 0
    assert s.lyapunov_ci[0][0] > 0.0
    # the lower bound is above the exponent's noise floor: the change when the same record
    # is integrated again at rtol / 10 (per excitation period both)
    g = s.metrics
    assert 0.0 <= g["lyapunov_floor_per_period"][0] < g["lyapunov_lo_per_period"][0]
    assert g["lyapunov_lo_per_period"][0] == pytest.approx(s.lyapunov_ci[0][0] * T)
    # samples spread by many resolutions (1e-3 of the range: no floor on this model)
    assert g["resolution_period_n"][0] == 0 and g["resolution_defect"][0] > 10


@pytest.mark.parametrize("prm,Om,n", [(P_A, 0.8, 1), (P_B, 0.85, 2)],
                         ids=["P_A-double-sided", "P_B-period2"])
def test_impact_metrics_equal_exact_orbit(prm, Om, n):
    orb = _exact_orbit(prm, Om, n)
    fl = orb.flow
    P = n                                           # excitation periods per orbit
    onset = fl.switch_to != 0
    v = np.abs(fl.switch_states[onset, 1])          # delta' = q' (c = 1, e = 0)
    drive = np.sum(fl.switch_to == 1) / P
    back = np.sum(fl.switch_to == -1) / P
    s = sweep(impact_pair_model(*prm), [Om], SweepOptions(directions=("up",), transient_periods=8, record_periods=8 * n, max_period=4, extra_transient_periods=0), options=OPT, u0=orb.u0)
    assert s.period_n[0] == n and s.motion_class[0] == PERIODIC
    g = s.metrics
    assert g["impacts_drive_clearance"][0] == pytest.approx(drive, abs=1e-12)
    assert g["impacts_back_clearance"][0] == pytest.approx(back, abs=1e-12)
    assert drive + back > 0
    # approach speeds at onset; measured agreement ~1e-9
    assert g["impact_velocity_max_clearance"][0] == pytest.approx(v.max(), rel=1e-7)
    assert g["impact_velocity_rms_clearance"][0] == pytest.approx(
        np.sqrt(np.mean(v ** 2)), rel=1e-7)
    assert g["rattle_clearance"][0] == pytest.approx(np.sum(0.5 * v ** 2) / P, rel=1e-7)
    assert g["contact_fraction_clearance"][0] == pytest.approx(
        fl.time_in_contact / orb.period, abs=1e-7)
    # a periodic orbit: the two record halves agree (the error estimate is ~0)
    for k in ("impacts_drive", "impact_velocity_rms", "contact_fraction", "rattle"):
        assert g[f"{k}_clearance_err"][0] < 1e-7


def test_transient_stops_when_the_map_has_converged():
    """Settled and fixed-budget results agree within period_tol; fewer periods used."""
    model, Om, budget, tol = impact_pair_model(*P_A), 0.5, 400, 1e-6
    T = 2 * np.pi / Om
    kw = dict(directions=("up",), record_periods=16, max_period=4, period_tol=tol,
              extra_transient_periods=0)
    settled = sweep(model, [Om], SweepOptions(transient_periods=budget, **kw), options=OPT)
    u_full = integrate(model, Om, np.zeros(2), 0.0, budget * T, options=OPT).u_end
    fixed = sweep(model, [Om], SweepOptions(transient_periods=0, **kw), u0=u_full, options=OPT)
    used = int(settled.transient_used[0])
    # measured: 40 of 400 periods, Poincare samples and extrema within 7e-12 of the scale
    assert settled.settled_by[0] == "map" and used < budget / 2
    assert settled.period_n[0] == fixed.period_n[0] == 1
    scale = np.max(np.abs(fixed.poincare[0]))
    assert np.max(np.abs(settled.poincare[0] - fixed.poincare[0])) <= tol * scale
    for k in ("qmin", "qmax"):
        assert abs(getattr(settled, k)[0] - getattr(fixed, k)[0]) <= tol * scale


def test_chaotic_statistics_converge_with_their_errors():
    """On the chaotic impact pair the pointwise motion does not converge, its statistics
    do: the batch-means errors shrink as the record grows, and records of 64 and 256
    periods, and a 100x looser tolerance, agree within 3 combined errors."""
    model, Om = impact_pair_model(*CHAOS), 1.0
    u = integrate(model, Om, np.zeros(2), 0.0, 300 * 2 * np.pi / Om, options=OPT).u_end
    runs = {}
    for R, rtol in ((64, 1e-9), (256, 1e-9), (256, 1e-7)):
        runs[R, rtol] = sweep(model, [Om], SweepOptions(directions=("up",), transient_periods=0, record_periods=R, lyapunov=False, extra_transient_periods=0), u0=u, options=IntegrationOptions(rtol=rtol, atol=1e-2 * rtol)).metrics
    names = ("impacts_drive", "impacts_back", "contact_fraction", "impact_velocity_rms",
             "rattle")
    short, long_, loose = runs[64, 1e-9], runs[256, 1e-9], runs[256, 1e-7]
    for k in (f"{n}_clearance" for n in names):
        assert long_[k + "_err"][0] < short[k + "_err"][0], k   # measured 2-3x smaller
        for other in (short, loose):
            err = np.hypot(long_[k + "_err"][0], other[k + "_err"][0])
            assert abs(long_[k][0] - other[k][0]) <= 3 * err, k
