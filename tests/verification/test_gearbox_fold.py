"""A gearbox continuation traces its branch through folds (issue 9: `vibrogear continue
configs/gear_pair.toml` had regressed to a one-point branch and no test noticed).

gear_pair over 4900-5400 rpm: the period-1 branch of the loaded mesh is S-shaped (the jump
region of the sweep).  Checked against what defines a fold, independently of how the solver
labels it:
* geometry: at each LP the parameter is a local extremum along the branch, and between the
  two folds a speed is crossed by three sheets of the branch, outside them by one;
* Floquet theory: a fold of periodic orbits has a multiplier +1;
* stability exchange: the number of multipliers outside the unit circle changes by one from
  one side of the fold to the other.
Measured (2026-11-24): folds at 5127.65 and 5236.54 rpm, 63 + 12 points, 13 s.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main

GEAR_PAIR = str(Path(__file__).resolve().parents[2] / "configs" / "gear_pair.toml")


@pytest.fixture(scope="module")
def branch(tmp_path_factory):
    out = tmp_path_factory.mktemp("fold")
    code = main(["continue", GEAR_PAIR, "--quiet", "--out", str(out),
                 "--set", "continuation.rpm_min=4900", "--set", "continuation.rpm_max=5400"])
    assert code == 0
    with np.load(out / "branch.npz") as z:
        b0 = z["branch"] == 0
        return {k: z[k][b0] for k in ("param", "floquet", "label", "residual")}


def test_the_branch_is_traced_over_the_range(branch):
    p = branch["param"]
    assert p.size > 20
    assert p[0] == pytest.approx(5400.0) and p.min() < 4910.0       # from one end to the other
    assert np.all(branch["residual"] < 1e-8)


def test_each_fold_is_a_turning_point_of_the_parameter_with_a_multiplier_one(branch):
    p, mu, lab = branch["param"], branch["floquet"], branch["label"].astype(str)
    folds = np.flatnonzero(lab == "LP")
    assert folds.size == 2
    for i in folds:
        assert 0 < i < p.size - 1
        assert (p[i] - p[i - 1]) * (p[i + 1] - p[i]) < 0          # the parameter turns back
        assert np.min(np.abs(mu[i] - 1.0)) < 1e-4                  # Floquet multiplier +1
        unstable = [int(np.sum(np.abs(mu[k]) > 1 + 1e-6)) for k in (i - 1, i + 1)]
        assert abs(unstable[0] - unstable[1]) == 1                 # one multiplier crosses


def test_three_coexisting_orbits_between_the_folds_one_outside(branch):
    p, lab = branch["param"], branch["label"].astype(str)
    lo, hi = sorted(p[lab == "LP"])
    assert 5100 < lo < hi < 5260

    def sheets(speed):
        return int(np.sum(np.diff(np.sign(p - speed)) != 0))

    assert sheets(0.5 * (lo + hi)) == 3
    assert sheets(hi + 50.0) == 1 and sheets(lo - 100.0) == 1
