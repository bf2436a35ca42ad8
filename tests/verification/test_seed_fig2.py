"""The seed's Fig. 2 scene (configs/two_stage_seed.toml) and its figure.

* Sweep and continuation agree on the seed scene (slow): over its period-1 window
  (2150-2450 rpm, docs/gearbox.md "The seed's gearbox") every sweep point classified
  period-1 or period-2 lies on a stable branch of that period.  The two sides are
  independent: the sweep settles by plain time integration from the previous speed's state,
  the branches come from shooting (Newton on the period map) and pseudo-arclength
  continuation started from the sweep's window (``from_sweep``).  At each such sweep speed
  the branch is evaluated by shooting from the branch state interpolated between the two
  branch points around it (as tests/verification/test_branches_agree_with_sweep.py does for
  gear_pair); that orbit must be stable and its extrema agree with the sweep's within 1e-3
  of the extremum.  The identified scene has no period-2 sweep point (its period-1 window
  ends in z4 rattle, not in a period doubling), so only period-1 points are checked there;
  a period-2 point, should one appear, is checked the same way.
* ``fig2.png`` is drawn from given arrays: the sweep's extremes as dots, the branches, the
  zero line and one band row per direction and per mesh whose class differs (fast).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from branch_orbits import extrema_error, stable_orbits_through
from vibrogear.analyses.study import build_study
from vibrogear.cli import main
from vibrogear.config.scene import load_scene
from vibrogear.report.writers.fig2 import plot_fig2
from vibrogear.report.figure import save_figure

ROOT = Path(__file__).resolve().parents[2]
SCENE = str(ROOT / "configs" / "two_stage_seed.toml")
SETTINGS = ["sweep.rpm_min=2150.0", "sweep.rpm_max=2450.0", "sweep.n_points=13",
            "sweep.workers=1", "continuation.rpm_min=2150.0", "continuation.rpm_max=2450.0",
            "continuation.start=min", "continuation.max_points=3",
            "continuation.from_sweep=true", "continuation.from_sweep_max_points=12"]


@pytest.mark.slow
def test_seed_sweep_periodic_points_lie_on_stable_branches(tmp_path):
    out = tmp_path / "out"
    args = ["run", SCENE, "--quiet", "--out", str(out)]
    for s in SETTINGS:
        args += ["--set", s]
    assert main(args) == 0
    summary = json.loads((out / "summary.json").read_text())["results"]["continuation"]
    assert summary["from_sweep"]["windows"]
    assert (out / "fig2.png").stat().st_size > 1000
    scene = load_scene(SCENE, tuple(SETTINGS))
    study = build_study(scene)
    opts = scene.integration
    sw = dict(np.load(out / "sweep.npz"))
    br = dict(np.load(out / "branch.npz"))
    periodic = np.flatnonzero((sw["status"] == 0) & (sw["period_n"] > 0)
                              & (sw["period_n"] <= 2))
    assert periodic.size >= 8            # the window is period-1 (measured: 13 of 13 points)
    for k in periodic:
        n, p = int(sw["period_n"][k]), float(sw["param"][k])
        found = stable_orbits_through(study.model, br, n, p, opts, scene.shooting.tol)
        assert found, f"no stable period-{n} branch through the sweep point at {p} rpm"
        err = extrema_error(found, sw, k)
        assert err < 1e-3, (n, p, err)


def test_fig2_draws_dots_branches_zero_line_and_band(tmp_path):
    p = np.linspace(1.0, 2.0, 6)
    sweep = {"param": p, "direction": np.array(["up"] * 6), "qmin": -0.5 + 0 * p,
             "qmax": 1.0 + p, "status": np.zeros(6, int), "period_n": np.array([1, 1, 0, 0, 2, 2]),
             "motion_class": np.array([1, 1, 3, 2, 1, 1]),
             "motion_class_G1": np.array([1, 1, 1, 1, 1, 1]),
             "period_n_G1": np.array([1, 1, 1, 1, 2, 2]), "impacts_drive_G1": np.zeros(6),
             "motion_class_bearing": np.array([1, 1, 1, 1, 1, 1])}
    branches = {"param": p, "qmax": 1.0 + p, "qmin": -0.5 + 0 * p,
                "stable": np.array([1, 1, 0, 0, 1, 1], bool),
                "label": np.array(["", "", "PD", "", "", ""]), "branch": np.zeros(6, int),
                "n_periods": np.ones(6, int)}
    paths = save_figure(plot_fig2(sweep, branches, param_label="rpm"), tmp_path / "fig2",
                        formats=("svg",))
    svg = paths[0].read_text()
    # one motion row per direction by default; the PD named with its speed
    assert "PD 1.4" in svg and "G1 up" not in svg and "bearing up" not in svg
    # per-contact rows where asked: each group whose own class differs from the whole's
    # (the bearing has no period of its own here, so its period-n differs too)
    asked = save_figure(plot_fig2(sweep, branches, param_label="rpm", per_contact_rows=True),
                        tmp_path / "fig2_rows", formats=("svg",))[0].read_text()
    assert "G1 up" in asked and "bearing up" in asked
    assert "period-1 branch stable" in svg and "period-1 branch unstable" in svg
