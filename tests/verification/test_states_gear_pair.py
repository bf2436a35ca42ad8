"""gear_pair: every stable branch that the continuation finds shows up in the census as an
attractor (issue 33; slow).

Reference: shooting + pseudo-arclength continuation of the period-1 orbit over 4900-5400 rpm
(``vibrogear continue configs/gear_pair.toml``, with its period-2 branch from the PD):
LP 5126.6 / 5233.7 rpm, PD 5131.2 / 5195.4 rpm, NS 4929.0 / 5175.7 / 5205.1 / 5227.2 rpm.  The
census at 5100-5225 rpm in 25 rpm steps, 16 random starts each, then has to show, at every
grid speed where a branch is stable, an attractor of that period whose largest mesh
deformation is the branch's there (within the branch's own interpolation error between
points, as :func:`vibrogear.analyses.sweep_branches.on_branch` measures).

Measured (2026-11-27, 16 starts per speed): see the assertion messages and docs/states.md.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.analyses.sweep_branches import branch_value_at
from vibrogear.config import load_scene
from vibrogear.pipeline.outcome import RunContext
from vibrogear.runner import run_scene

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
STARTS = 32


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("gear_pair_states")
    scene = load_scene(ROOT / "configs" / "gear_pair.toml", (
        'scene.analyses=["continuation", "states"]', "continuation.rpm_min=4900.0",
        "continuation.rpm_max=5400.0", "states.rpm_min=5100.0", "states.rpm_max=5220.0",
        "states.n_points=7", f"states.starts={STARTS}"))
    ctx = RunContext(out=out, quiet=True)
    from vibrogear.analyses.continuation import run as cont_run
    from vibrogear.analyses.states import run as states_run
    from vibrogear.analyses.study import build_study

    study = build_study(scene)
    cont = cont_run(study, scene, ctx)
    got = states_run(study, scene, ctx, previous={"continuation": cont})
    return cont.result, got


def test_every_stable_branch_is_an_attractor(run):
    cont, got = run
    res = got.result
    missing, found = [], []
    for p in res.params:
        atts = [a for a in res.attractors if a.param == p]
        for br in cont.branches:
            for value, stable, change in branch_value_at(br, float(p)):
                if not stable:
                    continue
                tol = max(1e-3 * abs(value), 0.25 * change)
                hit = [a for a in atts if a.period_n == br.n_periods and
                       abs(a.qmax - value) <= tol]
                (found if hit else missing).append((float(p), br.n_periods, value * 1e6))
    assert found, "no stable branch crosses the census grid"
    assert not missing, f"stable branches without an attractor ({STARTS} starts): {missing}; " \
                        f"found {found}"


def test_coexisting_states_and_files(run, tmp_path):
    _, got = run
    summary = got.summary
    assert summary["coexisting_at"], summary["message"]
    for rec in summary["per_speed"]:
        fr = [a["basin_fraction"] for a in rec["attractors"]]
        assert abs(sum(fr) - 1.0) < 1e-12 and rec["n_starts"] + rec["failed"] == STARTS
    from vibrogear.report.states_report import write
    files = write(None, got, tmp_path)
    with np.load(files["npz"]) as z:
        assert z["attractor_param"].size == len(got.result.attractors)
        assert np.all(z["basin_ci_lo"] <= z["basin_fraction"])
        assert np.all(z["basin_fraction"] <= z["basin_ci_hi"])
        assert z["n_starts"].tolist() == [r["n_starts"] for r in summary["per_speed"]]
    assert Path(files["danger_map_png"]).stat().st_size > 10_000
