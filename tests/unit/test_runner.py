"""The runner protocol on the impact pair: analyses return outcomes and the report writers
write the files; data passes between analyses only as returned outcomes (so the order of
the analyses does not change any result); sweep statuses tell the truth."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCENE = str(ROOT / "configs" / "impact_pair.toml")
SMALL = ["--set", "sweep.n_points=6", "--set", "sweep.omega_min=0.8",
         "--set", "sweep.omega_max=1.0", "--set", "sweep.transient_periods=40",
         "--set", "sweep.extra_transient_periods=0", "--set", "sweep.record_periods=8",
         "--set", "continuation.omega_min=0.8", "--set", "continuation.omega_max=1.0",
         "--set", "continuation.max_points=60", "--quiet"]


def _run(tmp_path, name, *extra) -> tuple[int, Path, dict]:
    out = tmp_path / name
    code = main(["run", SCENE, "--out", str(out), *SMALL, *extra])
    summary = json.loads((out / "summary.json").read_text()) if (out / "summary.json").exists() else {}
    return code, out, summary


@pytest.mark.system
def test_analysis_order_changes_no_result(tmp_path):
    """sweep then continuation, and continuation then sweep: the same numbers in every file,
    and the branch figures carry the sweep overlay either way."""
    c1, a, s1 = _run(tmp_path, "a", "--set", 'scene.analyses=["sweep", "continuation"]')
    c2, b, s2 = _run(tmp_path, "b", "--set", 'scene.analyses=["continuation", "sweep"]')
    assert c1 == c2 == 0
    for name in ("sweep.npz", "branch.npz"):
        with np.load(a / name) as za, np.load(b / name) as zb:
            for k in za.files:
                if k != "point_wall":
                    assert np.array_equal(za[k], zb[k]), (name, k)
    assert s1["results"]["continuation"]["folds"] == s2["results"]["continuation"]["folds"]
    for out in (a, b):
        assert (out / "branch_max.png").stat().st_size > 1000
        assert (out / "bifurcation_branches.png").stat().st_size > 1000
        assert not (out / "sweep.partial.jsonl").exists()     # removed once sweep.npz exists


@pytest.mark.system
def test_continuation_alone_overlays_the_sweep_already_in_the_folder(tmp_path):
    """``continue`` after ``sweep`` into the same folder: the combined figure is drawn from
    the sweep.npz there; into an empty folder there is none."""
    assert _run(tmp_path, "a", "--set", 'scene.analyses=["sweep"]')[0] == 0
    code, out, s = _run(tmp_path, "a", "--set", 'scene.analyses=["continuation"]')
    assert code == 0 and "branches_png" in s["results"]["continuation"]["files"]
    assert (out / "bifurcation_branches.png").stat().st_size > 1000
    code, out, s = _run(tmp_path, "b", "--set", 'scene.analyses=["continuation"]')
    assert code == 0 and not (out / "bifurcation_branches.png").exists()


@pytest.mark.system
def test_branches_from_the_saved_sweep_equal_those_from_this_runs_sweep(tmp_path):
    """``from_sweep`` gets the sweep from the runner: this run's outcome, or the sweep.npz an
    earlier run left in the folder (loaded by the runner, not by the analysis). Both give the
    same windows and branches; with neither, the summary says so."""
    fs = ("--set", "continuation.from_sweep=true")
    assert _run(tmp_path, "one", *fs, "--set", 'scene.analyses=["sweep", "continuation"]')[0] == 0
    assert _run(tmp_path, "two", *fs, "--set", 'scene.analyses=["sweep"]')[0] == 0
    code, two, s2 = _run(tmp_path, "two", *fs, "--set", 'scene.analyses=["continuation"]')
    s1 = json.loads((tmp_path / "one" / "summary.json").read_text())
    w1 = s1["results"]["continuation"]["from_sweep"]
    w2 = s2["results"]["continuation"]["from_sweep"]
    assert code == 0 and w1["windows"] and w1["windows"] == w2["windows"]
    assert w1["source"] == "this run's sweep" and w2["source"].endswith("sweep.npz")
    with np.load(tmp_path / "one" / "branch.npz") as za, np.load(two / "branch.npz") as zb:
        assert np.array_equal(za["param"], zb["param"]) and np.array_equal(za["u0"], zb["u0"])
    code, _, s3 = _run(tmp_path, "empty", *fs, "--set", 'scene.analyses=["continuation"]')
    assert code == 0 and s3["results"]["continuation"]["from_sweep"]["note"] == \
        "no sweep in this run or in the output folder"


def test_continuation_liouville_identity(tmp_path):
    """det M = exp(-2 zeta T) on every branch point (no contact damping): Liouville."""
    code, out, s = _run(tmp_path, "c", "--set", 'scene.analyses=["continuation"]')
    assert code == 0
    assert s["results"]["continuation"]["error_estimate"]["liouville_det_error"] < 1e-5
    assert 0.85 < s["results"]["continuation"]["folds"][0] < 0.95


def test_sweep_whose_every_point_failed_exits_1(tmp_path, capsys):
    code, out, s = _run(tmp_path, "f", "--set", 'scene.analyses=["sweep"]',
                        "--set", "integration.max_steps=5")
    assert code == 1
    assert s["status"] == "failed" and "all 12 points failed" in s["results"]["sweep"]["message"]
    assert "maximum number of steps" in capsys.readouterr().err
    assert (out / "sweep.partial.jsonl").exists()          # the failed points are kept


def test_loose_tolerance_warns(tmp_path):
    code, out, s = _run(tmp_path, "w", "--set", 'scene.analyses=["sweep"]',
                        "--set", "integration.rtol=1e-3", "--set", "integration.atol=1e-5")
    assert code == 0
    (warning,) = s["results"]["sweep"]["warnings"]
    assert "rtol = 0.001" in warning and "period_tol" in warning


@pytest.mark.parametrize("analysis", ["time_response"])
def test_time_response_files(tmp_path, analysis):
    code, out, s = _run(tmp_path, "t", "--set", f'scene.analyses=["{analysis}"]',
                        "--set", "time_response.periods=5")
    assert code == 0
    head = (out / "time_response.csv").read_text().splitlines()[0].split(",")
    assert head[:3] == ["t", "q", "dq/dtau"]
    with np.load(out / "time_response.npz") as z:
        # the impact pair's contact deformation is q itself (c = 1, no transmission error)
        assert np.array_equal(z["delta"][0], z["u"][:, 0])
