"""``vibrogear states`` on the impact pair against independent answers (issue 33).

* **Linear** (clearance b_r = 100, never reached from the box): one attractor at every Omega,
  basin 1, its extrema the closed-form forced response f_m/kappa +- f_p / |kappa - Omega^2
  + 2 i zeta Omega|.
* **zeta = 0.015** (configs/impact_pair.toml; primary folds LP at Omega = 0.872 and 0.926):
  between the folds two stable period-1 attractors whose extrema equal the exact
  piecewise-linear orbits (vibrogear/verification/impact_orbits.py: Newton on the exact
  flow; extrema polished on the exact dense solution) to 1e-6, both stable by the exact
  monodromy; just outside the folds one stable period-1 attractor with basin 1; the
  branches continued from the attractors have their LP at the folds.
  Measured (2026-11-27): at Omega = 0.89 / 0.91 the extrema agree to 2e-9 .. 4e-8.
* **Basin fraction error ~ 1/sqrt(N)** (slow): the fractions of disjoint blocks of n starts
  scatter about the pooled fraction as the binomial law says, sqrt(p (1 - p) (1/n - 1/N));
  the slope of log(RMS) against log(n) is -1/2 within 0.15.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from vibrogear.analyses.states import states
from vibrogear.analyses.study import build_study
from vibrogear.config import scene_from_dict
from vibrogear.pipeline.outcome import RunContext
from vibrogear.verification.impact_exact import ImpactParams, exact_dense
from vibrogear.verification.impact_orbits import periodic_orbit

PAIR = {"zeta": 0.015, "kappa": 0.5, "f_m": 0.55, "f_p": 0.12, "b_r": 1.0}
LP = (0.872, 0.926)


def _census(tmp_path, pair, lo, hi, n_points, starts, *, q=(-4.0, 5.0), v=(-4.0, 4.0),
            branches=False, **extra):
    d = {"scene": {"name": "ip", "analyses": ["states"]}, "impact_pair": dict(pair),
         "integration": {"rtol": 1e-8, "atol": 1e-10}, "shooting": {"tol": 1e-10},
         "states": {"omega_min": lo, "omega_max": hi, "n_points": n_points, "starts": starts,
                    "q_range": list(q), "v_range": list(v), "transient_periods": 150,
                    "record_periods": 16, "branches": branches, "workers": 1, **extra}}
    scene = scene_from_dict(d)
    study = build_study(scene)
    return states.run(study, scene, RunContext(out=tmp_path, quiet=True))


def _exact_extrema(p, omega, guess):
    """The exact period-1 orbit through ``guess`` and its extrema, each polished by a
    bounded scalar search on the exact dense solution."""
    orb = periodic_orbit(p, omega, guess, tol=1e-13)
    assert orb.converged
    T = 2 * np.pi / omega
    ts = np.union1d(np.linspace(0.0, T, 8001), orb.flow.switch_times)
    q = exact_dense(p, omega, None, 0.0, ts, flow=orb.flow)[:, 0]

    def polish(sign):
        k = int(np.argmax(sign * q))
        a, b = ts[max(k - 1, 0)], ts[min(k + 1, ts.size - 1)]
        r = minimize_scalar(lambda t: -sign * exact_dense(p, omega, None, 0.0, [t],
                                                          flow=orb.flow)[0, 0],
                            bounds=(a, b), method="bounded", options={"xatol": 1e-12})
        return max(sign * q[k], -r.fun) * sign
    return polish(-1.0), polish(1.0), orb


def test_linear_model_has_one_attractor_with_basin_1(tmp_path):
    pair = dict(PAIR, zeta=0.05, b_r=100.0)
    out = _census(tmp_path, pair, 0.6, 1.2, 3, 8)
    res = out.result
    assert len(res.attractors) == 3
    for a in res.attractors:
        assert a.period_n == 1 and a.count == 8 and a.fraction == 1.0
        assert a.ci[0] == pytest.approx(8 / (8 + 1.959963984540054 ** 2))
        A = pair["f_p"] / abs(pair["kappa"] - a.param ** 2 + 2j * pair["zeta"] * a.param)
        mean = pair["f_m"] / pair["kappa"]
        assert a.refined and a.stable
        assert abs(a.qmax - (mean + A)) < 1e-6 and abs(a.qmin - (mean - A)) < 1e-6
    per = out.summary["per_speed"]
    assert [len(s["attractors"]) for s in per] == [1, 1, 1]
    assert not any(s["coexisting"] for s in per)


@pytest.fixture(scope="module")
def around_the_folds(tmp_path_factory):
    """Omega = 0.86, 0.88, 0.90, 0.92, 0.94, 16 starts each, branches from the attractors."""
    return _census(tmp_path_factory.mktemp("folds"), PAIR, 0.86, 0.94, 5, 16, branches=True)


@pytest.mark.parametrize("omega", [0.88, 0.90, 0.92])
def test_two_stable_period_1_attractors_between_the_folds_equal_the_exact_orbits(
        around_the_folds, omega):
    p = ImpactParams(**PAIR)
    atts = [a for a in around_the_folds.result.attractors if abs(a.param - omega) < 1e-12]
    assert len(atts) == 2, [(a.class_name, a.period_n, a.qmax) for a in atts]
    for a in atts:
        assert a.period_n == 1 and a.refined and a.stable
        assert 0.0 < a.fraction < 1.0
        qmin, qmax, orb = _exact_extrema(p, omega, a.u0)
        assert orb.stable
        assert abs(a.qmin - qmin) < 1e-6 and abs(a.qmax - qmax) < 1e-6, \
            (omega, a.qmin - qmin, a.qmax - qmax)
    assert abs(atts[0].qmax - atts[1].qmax) > 0.5        # two different orbits
    assert sum(a.count for a in atts) == 16


@pytest.mark.parametrize("omega", [0.86, 0.94])
def test_one_stable_attractor_just_outside_the_folds(around_the_folds, omega):
    p = ImpactParams(**PAIR)
    atts = [a for a in around_the_folds.result.attractors if abs(a.param - omega) < 1e-12]
    assert len(atts) == 1
    a = atts[0]
    assert a.period_n == 1 and a.fraction == 1.0 and a.stable
    qmin, qmax, orb = _exact_extrema(p, a.param, a.u0)
    assert orb.stable and abs(a.qmax - qmax) < 1e-6 and abs(a.qmin - qmin) < 1e-6


def test_branches_from_the_attractors_fold_at_the_primary_folds(around_the_folds):
    summary = around_the_folds.summary
    lps = sorted(sp["Omega"] for b in summary["branches"] for h in b["halves"]
                 for sp in h["special_points"] if sp["label"] == "LP")
    assert any(abs(x - LP[0]) < 1e-3 for x in lps) and any(abs(x - LP[1]) < 1e-3 for x in lps)
    assert summary["coexisting_at"] == pytest.approx([0.88, 0.90, 0.92])


@pytest.mark.slow
def test_basin_fraction_error_shrinks_like_one_over_sqrt_n(tmp_path):
    N = 256
    out = _census(tmp_path, PAIR, 0.9, 0.9, 1, N)
    atts = out.result.attractors
    assert len(atts) == 2
    upper = max(atts, key=lambda a: a.qmax)
    hit = np.zeros(N, bool)
    hit[upper.members] = True
    p = hit.mean()
    assert 0.1 < p < 0.9
    sizes = np.array([4, 8, 16, 32, 64])
    rms = np.array([math.sqrt(np.mean((hit.reshape(-1, n).mean(axis=1) - p) ** 2))
                    for n in sizes])
    expected = np.sqrt(p * (1 - p) * (1 / sizes - 1 / N))
    # blocks scatter about the pooled fraction: sqrt(1 - n/N) of their scatter about p
    slope = np.polyfit(np.log(sizes), np.log(rms / np.sqrt(1 - sizes / N)), 1)[0]
    assert -0.65 < slope < -0.35, (slope, rms)
    # each scatter within a factor of 2 of the binomial law's (N / n - 1 blocks each)
    assert np.all(rms / expected < 2.0) and np.all(rms / expected > 0.4), rms / expected
    # the Wilson interval of the pooled census holds the blocks' fractions' mean (it is p)
    lo, hi = upper.ci
    assert lo < p < hi and hi - lo < 2 * 1.96 * math.sqrt(p * (1 - p) / N) * 1.05
