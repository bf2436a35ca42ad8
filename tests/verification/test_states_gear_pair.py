"""gear_pair: every stable branch that the continuation finds shows up in the census as an
attractor (issue 33; slow).

Reference: shooting + pseudo-arclength continuation of the period-1 orbit over 4900-5400 rpm
(``vibrogear continue configs/gear_pair.toml``, with its period-2 branch from the PD):
LP 5126.6 / 5233.7 rpm, PD 5131.2 / 5195.4 rpm, NS 4929.0 / 5175.7 / 5205.1 / 5227.2 rpm.
Where a branch is stable at a census speed, its orbit there is shot from the branch's
neighbouring points (the continuation's own shooting, at exactly that speed) and the census
must hold an attractor of that period with the same largest mesh deformation (1e-3).

The census: 5100-5180 rpm in 20 rpm steps with 32 random starts each (speeds at least 15 rpm
from an NS point, where the multipliers approach the unit circle and a settling of a few
hundred periods cannot end), and 5220 rpm alone with more starts: the period-1 orbit between
the NS at 5205 rpm and the LP at 5233.7 rpm has a small basin.

Measured (2026-11-27): with 32 starts per speed every stable crossing at 5100-5180 rpm is
found (period-1 at 5160 rpm by 1 start of 32; period-2 at 5140-5180 rpm); at 5220 rpm 32
starts (of a 7-speed grid) found no start in the period-1 orbit's basin (all quasi-periodic
rattle); 128 starts found one (basin 0.8 %, Wilson 0.14-4.3 %; qmax 13.702 um).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.config import load_scene
from vibrogear.pipeline.outcome import RunContext

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
STARTS = 32
STARTS_5220 = 128


def _census(scene_sets, out):
    from vibrogear.analyses.states.states import run as states_run
    from vibrogear.analyses.study import build_study

    scene = load_scene(ROOT / "configs" / "gear_pair.toml", scene_sets)
    study = build_study(scene)
    return study, scene, states_run(study, scene, RunContext(out=out, quiet=True))


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    from vibrogear.analyses.continuation import run as cont_run

    out = tmp_path_factory.mktemp("gear_pair_states")
    study, scene, got = _census((
        'scene.analyses=["continuation", "states"]', "continuation.rpm_min=4900.0",
        "continuation.rpm_max=5400.0", "states.rpm_min=5100.0", "states.rpm_max=5180.0",
        "states.n_points=5", f"states.starts={STARTS}", "states.branches=false"), out / "a")
    cont = cont_run(study, scene, RunContext(out=out / "c", quiet=True))
    _, _, single = _census(("states.rpm_min=5220.0", "states.rpm_max=5220.0",
                            "states.n_points=1", f"states.starts={STARTS_5220}",
                            "states.branches=false"), out / "b")
    return study, scene, cont.result, (got, single)


def _stable_orbits(study, scene, branches, p):
    """(n, qmax) of each stable branch orbit at ``p``, shot at exactly ``p`` from the
    bracketing branch points (linear interpolation of their states)."""
    from vibrogear.analyses.study import integration_options
    from vibrogear.config.options import ShootingOptions
    from vibrogear.solvers.periodic.shooting import shoot

    opts = integration_options(scene, section=scene.continuation, study=study)
    out = []
    for br in branches:
        pts = br.points
        for a, b in zip(pts[:-1], pts[1:]):
            lo, hi = sorted((a.param, b.param))
            if not (lo <= p <= hi and hi > lo and a.stable and b.stable):
                continue
            s = (p - a.param) / (b.param - a.param)
            sh = shoot(study.model, p, a.u0 + s * (b.u0 - a.u0), n_periods=br.n_periods,
                       options=opts, shooting=ShootingOptions(tol=scene.shooting.tol))
            assert sh.converged, (p, br.n_periods, sh.message)
            if sh.stable:
                out.append((br.n_periods, float(sh.monitor_max)))
    return out


def test_every_stable_branch_is_an_attractor(run):
    study, scene, cont, outcomes = run
    missing, found = [], []
    for got in outcomes:
        res = got.result
        for p in res.params:
            atts = [a for a in res.attractors if a.param == p]
            for n, qmax in _stable_orbits(study, scene, cont.branches, float(p)):
                hit = [a for a in atts if a.period_n == n and abs(a.qmax - qmax) <= 1e-3 * qmax]
                (found if hit else missing).append(
                    (float(p), n, round(qmax * 1e6, 3), [h.count for h in hit],
                     int(res.n_starts[list(res.params).index(p)])))
    assert found, "no stable branch crosses the census grid"
    assert not missing, f"stable branches without an attractor: {missing}; found {found}"


def test_coexisting_states_and_files(run, tmp_path):
    got = run[3][0]
    summary = got.summary
    assert summary["coexisting_at"], summary["message"]
    for rec in summary["per_speed"]:
        fr = [a["basin_fraction"] for a in rec["attractors"]]
        assert abs(sum(fr) - 1.0) < 1e-12 and rec["n_starts"] + rec["failed"] == STARTS
    from vibrogear.report.writers.states import write
    files = write(None, got, tmp_path)
    with np.load(files["npz"]) as z:
        assert z["attractor_param"].size == len(got.result.attractors)
        assert np.all(z["basin_ci_lo"] <= z["basin_fraction"])
        assert np.all(z["basin_fraction"] <= z["basin_ci_hi"])
        assert z["n_starts"].tolist() == [r["n_starts"] for r in summary["per_speed"]]
    assert Path(files["danger_map_png"]).stat().st_size > 10_000
