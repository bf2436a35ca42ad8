"""Critical damping of the impact pair: the zeta where the primary-resonance folds meet.

Default scene (kappa, f_m, f_p, b_r) = (0.5, 0.55, 0.12, 1): the bisection of
continuations over Omega in [0.6, 1.5] gave zeta_c = 0.033752 (bracket 8.5e-6 wide), the
folds at the last zeta with folds 0.855433 / 0.855433 (gap 4.3e-7), and the
(gap)^(2/3) extrapolation 0.033754.
"""
import json

import pytest

from vibrogear.analyses.critical_damping import critical_zeta, fold_scan
from vibrogear.cli import main
from vibrogear.config import load_scene
from vibrogear.solvers.integrate import IntegrationOptions

SCENE = "configs/impact_pair.toml"
ZETA_C = 0.033752
OPTS = IntegrationOptions(rtol=1e-8, atol=1e-10)
WINDOW = {"omega_min": 0.6, "omega_max": 1.5}


@pytest.fixture(scope="module")
def cfg():
    return load_scene(SCENE).impact_pair


def test_fold_pair_below_none_above(cfg):
    below = fold_scan(cfg, ZETA_C - 0.003, integration=OPTS, shooting_tol=1e-8, **WINDOW)
    above = fold_scan(cfg, ZETA_C + 0.003, integration=OPTS, shooting_tol=1e-8, **WINDOW)
    assert below.status == 0 and above.status == 0
    assert below.has_fold_pair and len(below.folds) == 2
    lo, hi = below.folds
    assert 0.85 < lo < hi < 0.87          # hysteresis window of the primary resonance
    assert above.folds == ()


def test_default_scene_folds_in_window(cfg):
    """At the scene's zeta = 0.015 the two folds are the ones of the continuation plot."""
    s = fold_scan(cfg, 0.015, integration=OPTS, shooting_tol=1e-8, **WINDOW)
    assert s.folds == pytest.approx((0.87231, 0.92630), abs=2e-4)


def test_bisection_coarse(cfg):
    res = critical_zeta(cfg, zeta_lo=0.015, zeta_hi=0.05, tol=2e-3, integration=OPTS,
                        shooting_tol=1e-8, **WINDOW)
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
