"""Critical damping of the impact pair: the zeta where the primary-resonance folds meet.

Default scene (kappa, f_m, f_p, b_r) = (0.5, 0.55, 0.12, 1): the bisection of
continuations over Omega in [0.6, 1.5] gave zeta_c = 0.033752 (bracket 8.5e-6 wide), the
folds at the last zeta with folds 0.855433 / 0.855433 (gap 4.3e-7), and the
(gap)^(2/3) extrapolation 0.033754.
"""
import json

import numpy as np
import pytest

from vibrogear.analyses.critical_damping import critical_zeta, fold_scan
from vibrogear.cli import main
from vibrogear.config import load_scene
from vibrogear.solvers.periodic.continuation import ContinuationOptions, PseudoArclength
from vibrogear.solvers.integrator.integrate import IntegrationOptions
from vibrogear.status import Status
from reference import impact_exact as ex  # the flow and the periodic orbits

SCENE = "configs/impact_pair.toml"
ZETA_C = 0.033752
OPTS = IntegrationOptions(rtol=1e-8, atol=1e-10)
WINDOW = ContinuationOptions(param_min=0.6, param_max=1.5, ds=0.02, ds_max=0.05, max_points=3000)
METHOD = PseudoArclength(integration=OPTS, tol=1e-8)


@pytest.fixture(scope="module")
def cfg():
    return load_scene(SCENE).impact_pair


def _exact_sweep_end(cfg, zeta, omegas):
    """Sequential continuation with the exact piecewise-linear solution (independent of the
    solvers): each orbit seeds the next; returns the last orbit."""
    p = ex.ImpactParams(zeta=zeta, kappa=cfg.kappa, f_m=cfg.f_m, f_p=cfg.f_p, b_r=cfg.b_r)
    u = np.array([cfg.f_m, 0.0])
    for om in omegas:
        u = ex.exact_flow(p, om, u, 0.0, 150 * 2 * np.pi / om).u_end
        orb = ex.periodic_orbit(p, om, u)
        assert orb.converged
        u = orb.u0
    return orb


def _coexist(cfg, zeta, om, lo, hi):
    """Exact orbits at ``om`` reached from below the window and from above it."""
    up = _exact_sweep_end(cfg, zeta, np.linspace(lo - 0.03, om, 4))
    down = _exact_sweep_end(cfg, zeta, np.linspace(hi + 0.03, om, 4))
    return up, down


def test_fold_pair_below_none_above(cfg):
    below = fold_scan(cfg, ZETA_C - 0.003, WINDOW, METHOD)
    above = fold_scan(cfg, ZETA_C + 0.003, WINDOW, METHOD)
    assert below.status == above.status == Status.LEFT_RANGE
    assert below.has_fold_pair and len(below.folds) == 2
    lo, hi = below.folds
    assert 0.85 < lo < hi < 0.87          # hysteresis window of the primary resonance
    assert above.folds == ()
    # independent check with the exact solution: two stable orbits coexist inside the window
    # below zeta_c, a single one above it
    up, down = _coexist(cfg, ZETA_C - 0.003, 0.5 * (lo + hi), lo, hi)
    assert up.stable and down.stable and up.q_max - down.q_max > 0.1
    up, down = _coexist(cfg, ZETA_C + 0.003, 0.5 * (lo + hi), lo, hi)
    assert abs(up.q_max - down.q_max) < 1e-6


def test_default_scene_folds_bound_the_hysteresis(cfg):
    """At the scene's zeta = 0.015 the folds bound the window where the exact solution has two
    stable orbits: inside they coexist, just outside either fold only one is left."""
    s = fold_scan(cfg, 0.015, WINDOW, METHOD)
    lo, hi = s.folds
    assert 0.8 < lo < hi < 1.0
    up, down = _coexist(cfg, 0.015, 0.5 * (lo + hi), lo, hi)
    assert up.stable and down.stable and up.q_max - down.q_max > 1.0
    for om in (lo - 0.005, hi + 0.005):
        up, down = _coexist(cfg, 0.015, om, lo, hi)
        assert abs(up.q_max - down.q_max) < 1e-6


def test_bisection_coarse(cfg):
    res = critical_zeta(cfg, WINDOW, METHOD, zeta_lo=0.015, zeta_hi=0.05, tol=2e-3)
    lo, hi = res.bracket
    assert hi - lo <= 2e-3
    assert lo <= ZETA_C <= hi
    assert res.continuations == len(res.scans) == 2 + 5
    assert len(res.folds_at_bracket) == 2


def test_cli_bad_bracket_is_numerical_failure(tmp_path, capsys):
    rc = main(["run", SCENE, "--quiet", "--out", str(tmp_path),
               "--set", 'scene.analyses=["critical_damping"]',
               "--set", "critical_damping.zeta_hi=0.02"])
    assert rc == 1
    assert "raise zeta_hi" in capsys.readouterr().err


@pytest.mark.slow
def test_cli_critical_zeta(tmp_path):
    rc = main(["run", SCENE, "--quiet", "--out", str(tmp_path),
               "--set", 'scene.analyses=["critical_damping"]'])
    assert rc == 0
    res = json.loads((tmp_path / "critical_damping.json").read_text())
    assert res["bracket_width"] <= 1e-5
    assert res["bracket"][0] <= res["zeta_critical"] <= res["bracket"][1]
    assert res["zeta_critical"] == pytest.approx(ZETA_C, abs=2e-5)
    assert res["fold_gap_at_bracket"] < 1e-4          # the two folds have (nearly) met
    assert res["zeta_extrapolated"] == pytest.approx(res["zeta_critical"], abs=2e-5)
    assert (tmp_path / "critical_damping.png").stat().st_size > 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["results"]["critical_damping"]["continuations"] == res["continuations"]
