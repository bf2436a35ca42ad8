"""Fold curves in the (speed, load) plane (issue 12, item 2) against independent runs.

The curves are bifurcation points located on one-parameter branches (continuation in speed)
at a sequence of loads, each load's window seeded from the previous load's points.  Checked:
* at the nominal load the curve's LPs are the folds of the nominal continuation, pinned
  independently by the regression tier and the fold test (tests/verification/
  test_gearbox_fold.py, golden gear_pair_fold.json: 5126.57 / 5233.72 rpm);
* at a second load, reached only through a seeded short window and the load scaling
  F0(s) = F0_rest + s F0_couplings, the LPs equal those of an unseeded continuation over
  4900-5400 rpm of the scene rebuilt with that load's twists (--set), a second, independent
  computation; each is a turning point of the speed along its own branch.
Measured (2026-11-24): nominal LP 5126.568 / 5233.726 rpm; 0.9 x load (56.25 N m) LP
5105.158 / 5192.069 rpm; ~7 s per window.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.analyses.map.curves import join_curves, locate_bifurcations
from vibrogear.analyses.map.load_scaling import load_scaling
from vibrogear.analyses.study import build_study
from vibrogear.cli import main
from vibrogear.config import load_scene

GEAR_PAIR = str(Path(__file__).resolve().parents[2] / "configs" / "gear_pair.toml")
NOMINAL_LP = (5126.6, 5233.7)          # golden gear_pair_fold.json / test_gearbox_fold.py
LOW = 0.9                              # the second load: 0.9 x the nominal twists
MARGIN = 100.0


@pytest.fixture(scope="module")
def scaling():
    scene = load_scene(GEAR_PAIR)
    study = build_study(scene)
    return scene, study, load_scaling(study.gearbox, scene.gearbox)


@pytest.fixture(scope="module")
def curves(scaling):
    scene, study, ls = scaling
    loads = locate_bifurcations(study.model, ls, [LOW, 1.0], (4950.0, 5350.0), margin=MARGIN,
                                integration=scene.integration, tol=scene.shooting.tol,
                                steps=dict(ds=20.0, ds_min=1e-3, ds_max=40.0, max_points=200))
    return loads, join_curves(loads, ls, 2 * MARGIN)


def _lps(load):
    return sorted(p for lab, p in load.points if lab == "LP")


def test_at_the_nominal_load_the_curves_pass_through_the_nominal_folds(curves, scaling):
    loads, joined = curves
    nominal = loads[1]
    assert nominal.scale == 1.0 and nominal.windows == ((4950.0, 5350.0),)
    assert np.allclose(_lps(nominal), NOMINAL_LP, atol=0.5)
    lp = [c for c in joined if c.label == "LP"]
    assert len(lp) == 2                                   # one curve per fold, both loads
    for c, ref in zip(sorted(lp, key=lambda c: c.rpm[-1]), NOMINAL_LP):
        assert np.allclose(c.torque, scaling[2].torque(np.array([LOW, 1.0])), rtol=1e-12)
        assert c.rpm[-1] == pytest.approx(ref, abs=0.5)


def test_the_next_load_traces_only_a_window_around_the_previous_folds(curves):
    loads, _ = curves
    lo, hi = _lps(loads[1])
    assert loads[0].windows == ((lo - MARGIN, hi + MARGIN),)
    assert len(_lps(loads[0])) == 2
    # the folds move with the load: less load, both folds at lower speed
    assert all(a < b for a, b in zip(_lps(loads[0]), _lps(loads[1])))


@pytest.mark.slow
def test_a_seeded_window_finds_the_folds_of_an_independent_continuation(curves, tmp_path):
    """~10 s more: the independent continuation of the rebuilt scene."""
    low = curves[0][0]
    twist = LOW * 0.025
    code = main(["continue", GEAR_PAIR, "--quiet", "--out", str(tmp_path),
                 "--set", "continuation.rpm_min=4900", "--set", "continuation.rpm_max=5400",
                 "--set", f"gearbox.couplings[0].twist={twist!r}",
                 "--set", f"gearbox.couplings[1].twist={twist!r}",
                 "--set", "continuation.period_doubling_branch=false"])
    assert code == 0
    with np.load(tmp_path / "branch.npz") as z:
        b0 = z["branch"] == 0
        p, lab = z["param"][b0], z["label"][b0].astype(str)
    ref = sorted(p[lab == "LP"])
    assert len(ref) == 2
    assert np.allclose(_lps(low), ref, atol=0.5)
    for i in np.flatnonzero(lab == "LP"):        # a fold: the speed turns back around it
        assert (p[i - 3] - p[i]) * (p[i + 3] - p[i]) > 0
