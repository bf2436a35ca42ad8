"""Every independent piece of an analysis is a work unit, the results do not depend on the
number of workers, and the wall split (parallel / serial) is reported and projected."""
from __future__ import annotations

import time

import numpy as np
import pytest

from vibrogear.pipeline.executors import effective_workers, unit_size
from vibrogear.pipeline.wall_split import WallSplit, project


def test_unit_size_caps_at_batch_and_gives_each_worker_about_16_units():
    assert unit_size(352, 2, cap=8) == 8            # ceil(352 / 32) = 11, capped at 8
    assert unit_size(352, 16, cap=8) == 2           # ceil(352 / 256) = 2: 176 units
    assert unit_size(352, 64, cap=8) == 1
    assert unit_size(0, 4, cap=8) == 1
    assert effective_workers(5, 1) == 1 and effective_workers(1, 4) == 1
    assert effective_workers(3, 8) == 3             # at most one process per unit


def test_projection_is_amdahl_for_fine_units_and_the_largest_unit_bounds_it():
    # fine units: Amdahl's law with serial s = 10 s, parallel work 220 s
    fine = {"serial_wall_s": 10.0, "parallel_phases": [
        {"unit_work_s": 220.0, "largest_unit_s": 1e-9}]}
    p = project(fine, 16)
    assert p["one_worker_s"] == 230.0
    assert p["speedup"][1] == pytest.approx(230.0 / (10.0 + 220.0 / 16), rel=1e-12)
    assert p["speedup"][0] == pytest.approx(p["speedup"][1], rel=1e-9)
    assert p["amdahl_speedup"] == pytest.approx(p["speedup"][1], rel=1e-12)
    # one unit of 50 s: no number of workers finishes the phase before it does
    coarse = {"serial_wall_s": 10.0, "parallel_phases": [
        {"unit_work_s": 220.0, "largest_unit_s": 50.0}]}
    q = project(coarse, 64)
    assert q["wall_s"][0] == 60.0                   # 10 + max(220 / 64, 50)
    assert q["wall_s"][1] == pytest.approx(10.0 + 220.0 / 64 + (63 / 64) * 50.0)
    # two phases (barriers) add up
    two = {"serial_wall_s": 0.0, "parallel_phases": [
        {"unit_work_s": 8.0, "largest_unit_s": 1.0}, {"unit_work_s": 2.0, "largest_unit_s": 2.0}]}
    assert project(two, 4)["wall_s"][0] == 4.0      # max(2, 1) + max(0.5, 2)
    # no more units than workers: each has its own, the phase lasts its largest unit
    few = {"serial_wall_s": 1.0, "parallel_phases": [
        {"units": 3, "unit_work_s": 6.0, "largest_unit_s": 3.0}]}
    assert project(few, 4)["wall_s"] == [4.0, 4.0]
    assert project(few, 2)["wall_s"] == [4.0, pytest.approx(1.0 + 3.0 + 0.5 * 3.0)]
    with pytest.raises(ValueError, match="workers"):
        project(fine, 0)


def _sleep(unit, emit):
    time.sleep(unit)
    emit(unit)
    return 2 * unit


def test_wall_split_times_every_unit_and_keeps_the_values():
    split = WallSplit("nothing")
    got = split.run("phase", _sleep, [0.05, 0.2, 0.1], workers=2, costs=[1, 3, 2])
    assert got == [0.1, 0.4, 0.2]                   # fn's values in unit order
    time.sleep(0.05)                                # a serial part
    s = split.summary()
    (ph,) = s["parallel_phases"]
    assert ph["units"] == 3 and ph["workers"] == 2
    assert ph["unit_work_s"] >= 0.35 and ph["largest_unit_s"] >= 0.2
    assert s["parallel_wall_s"] >= 0.2              # the longest unit at least
    assert s["serial_wall_s"] >= 0.05 and s["serial_part"] == "nothing"
    assert split.run("empty", _sleep, []) == [] and len(split.phases) == 1


# ------------------------------------------------------------------ states


def _ip_scene(**states):
    from vibrogear.config import scene_from_dict
    d = {"scene": {"name": "ip", "analyses": ["states"]},
         "impact_pair": {"zeta": 0.05, "kappa": 0.5, "f_m": 0.55, "f_p": 0.12, "b_r": 1.0},
         "integration": {"rtol": 1e-8, "atol": 1e-10},
         "states": {"omega_min": 0.8, "omega_max": 1.1, "n_points": 3, "starts": 6,
                    "batch": 3, "q_range": [-3.0, 4.0], "v_range": [-3.0, 3.0],
                    "transient_periods": 100, "record_periods": 16, "branches": True,
                    "workers": 1, **states}}
    return scene_from_dict(d)


def _states(tmp_path, workers):
    from vibrogear.analyses.states import states
    from vibrogear.analyses.study import build_study
    from vibrogear.pipeline.outcome import RunContext
    scene = _ip_scene(workers=workers)
    return states.run(build_study(scene), scene,
                      RunContext(out=tmp_path / f"w{workers}", quiet=True))


def test_states_census_orbits_and_branches_are_the_same_on_one_and_four_workers(tmp_path):
    """The settled starts, the shot orbits and the continued branches are each computed by
    the same deterministic code from the same inputs whichever worker runs them, so they
    agree bit for bit; on four workers the branches run in waves of two attractors, the
    second of which is dropped when the first one's branch passes through it (as it is in
    turn on one worker)."""
    one, four = _states(tmp_path, 1), _states(tmp_path, 4)
    a, b = one.result, four.result
    assert one.summary["per_speed"] == four.summary["per_speed"]
    assert one.summary["branches"] == four.summary["branches"]
    assert len(a.attractors) == len(b.attractors) >= 2
    for x, y in zip(a.attractors, b.attractors):
        assert (x.qmin, x.qmax, x.stable, x.refined) == (y.qmin, y.qmax, y.stable, y.refined)
        assert np.array_equal(x.u0, y.u0)
    assert len(a.branches) == len(b.branches) >= 1
    for x, y in zip(a.branches, b.branches):
        for name in ("param", "u0", "floquet", "qmax"):
            assert np.array_equal(x.array(name), y.array(name)), name
    # the split: one phase of units of three parts (census, orbits, branches run as one
    # stream); on four workers a candidate may be taken before the branch of the one
    # before it is back, so its halves may run and be dropped: as many branch units or more
    for out, w in ((one, 1), (four, 4)):
        s = out.summary
        assert s["serial_wall_s"] >= 0 and s["parallel_wall_s"] > 0 and s["serial_part"]
        (phase,) = s["parallel_phases"]
        assert phase["name"] == "census" and phase["workers"] == w
        parts = phase["parts"]
        assert set(parts) == {"census", "orbits", "branches"}
        assert phase["units"] == sum(p["units"] for p in parts.values())
        assert parts["orbits"]["units"] == sum(1 for x in out.result.attractors
                                               if x.period_n > 0)
    kept = len(one.summary["branches"])
    assert one.summary["parallel_phases"][0]["parts"]["branches"]["units"] == 2 * kept
    assert four.summary["parallel_phases"][0]["parts"]["branches"]["units"] >= 2 * kept
    # the census's units: at most `batch` (3) starts each; on four workers 18 starts in
    # units of ceil(18 / 64) = 1 start
    assert one.summary["parallel_phases"][0]["parts"]["census"]["units"] == 6
    assert four.summary["parallel_phases"][0]["parts"]["census"]["units"] == 18


def test_the_sweep_reports_its_walks_and_serial_part(tmp_path):
    from vibrogear.analyses.sweep import sweep
    from vibrogear.analyses.study import build_study
    from vibrogear.config import scene_from_dict
    from vibrogear.pipeline.outcome import RunContext
    scene = scene_from_dict({
        "scene": {"name": "ip", "analyses": ["sweep"]},
        "impact_pair": {"zeta": 0.05, "kappa": 0.5, "f_m": 0.55, "f_p": 0.12, "b_r": 1.0},
        "sweep": {"omega_min": 0.9, "omega_max": 1.1, "n_points": 3, "transient_periods": 60,
                  "record_periods": 8, "segments": 2, "workers": 2}})
    out = sweep.run(build_study(scene), scene, RunContext(out=tmp_path, quiet=True))
    s = out.summary
    (walks,) = s["parallel_phases"]
    assert walks["name"] == "walks" and walks["units"] == 4     # 2 directions x 2 segments
    assert walks["workers"] == 2 and s["serial_wall_s"] >= 0
    assert "not shared" in s["serial_part"]


STATES_MPI = r"""
import json, sys
sys.path.insert(0, sys.argv[2])
from test_parallel_units import _ip_scene
from vibrogear.analyses import states
from vibrogear.analyses.study import build_study
from vibrogear.pipeline.outcome import RunContext
from mpi4py import MPI
scene = _ip_scene(workers=None)
root = MPI.COMM_WORLD.rank == 0
out = states.run(build_study(scene), scene, RunContext(out=sys.argv[1], quiet=True))
if root:
    s = out.summary
    json.dump({"per_speed": s["per_speed"], "branches": s["branches"],
               "phases": s["parallel_phases"],
               "qmax": [float(b.array("qmax").sum()) for b in out.result.branches]},
              open(sys.argv[1] + "/states.json", "w"))
"""


@pytest.mark.system
@pytest.mark.mpi
@pytest.mark.skipif(__import__("shutil").which("mpirun") is None, reason="no mpirun")
def test_mpirun_two_ranks_share_the_orbits_and_branches_and_match_one_worker(tmp_path):
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    cmd = ["mpirun", "-n", "2", "--oversubscribe"] + (
        ["--allow-run-as-root"] if os.geteuid() == 0 else [])
    env = dict(os.environ, PYTHONPATH=str(root), OPENBLAS_NUM_THREADS="1")
    r = subprocess.run(cmd + [sys.executable, "-c", STATES_MPI, str(tmp_path),
                              str(Path(__file__).parent)],
                       env=env, cwd=root, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    got = json.loads((tmp_path / "states.json").read_text())
    one = _states(tmp_path, 1)
    assert got["per_speed"] == json.loads(json.dumps(one.summary["per_speed"]))
    assert got["branches"] == json.loads(json.dumps(one.summary["branches"]))
    assert got["qmax"] == [float(b.array("qmax").sum()) for b in one.result.branches]
    (phase,) = got["phases"]
    assert phase["workers"] == 2 and set(phase["parts"]) == {"census", "orbits", "branches"}


CURVES_MPI = r"""
import json, sys
from vibrogear.analyses.map.curves import locate_bifurcations
from vibrogear.analyses.map.load_scaling import load_scaling
from vibrogear.analyses.study import build_study
from vibrogear.config import load_scene
from vibrogear.pipeline.wall_split import WallSplit
from mpi4py import MPI
scene = load_scene(sys.argv[2])
study = build_study(scene)
ls = load_scaling(study.gearbox, scene.gearbox)
split = WallSplit()
loads = locate_bifurcations(study.model, ls, [0.9, 1.0], (4950.0, 5350.0), margin=100.0,
                            integration=scene.integration, tol=scene.shooting.tol,
                            steps=dict(ds=20.0, ds_min=1e-3, ds_max=40.0, max_points=200),
                            split=split)
json.dump({"points": [list(map(list, ld.points)) for ld in loads],
           "windows": [list(map(list, ld.windows)) for ld in loads],
           "phases": split.summary()["parallel_phases"]},
          open(sys.argv[1] + f"/rank{MPI.COMM_WORLD.rank}.json", "w"))
"""


@pytest.mark.system
@pytest.mark.mpi
@pytest.mark.skipif(__import__("shutil").which("mpirun") is None, reason="no mpirun")
def test_mpirun_map_curves_run_their_windows_on_every_rank_and_match_one_process(tmp_path):
    """The map's LP / PD curves, collective under MPI: every rank places the same windows
    and gets the same points as one process computing them in turn."""
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path
    from vibrogear.analyses.map.curves import locate_bifurcations
    from vibrogear.analyses.map.load_scaling import load_scaling
    from vibrogear.analyses.study import build_study
    from vibrogear.config import load_scene
    root = Path(__file__).resolve().parents[2]
    gear_pair = str(root / "configs" / "gear_pair.toml")
    cmd = ["mpirun", "-n", "2", "--oversubscribe"] + (
        ["--allow-run-as-root"] if os.geteuid() == 0 else [])
    env = dict(os.environ, PYTHONPATH=str(root), OPENBLAS_NUM_THREADS="1")
    r = subprocess.run(cmd + [sys.executable, "-c", CURVES_MPI, str(tmp_path), gear_pair],
                       env=env, cwd=root, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    scene = load_scene(gear_pair)
    study = build_study(scene)
    ls = load_scaling(study.gearbox, scene.gearbox)
    ref = locate_bifurcations(study.model, ls, [0.9, 1.0], (4950.0, 5350.0), margin=100.0,
                              integration=scene.integration, tol=scene.shooting.tol,
                              steps=dict(ds=20.0, ds_min=1e-3, ds_max=40.0, max_points=200),
                              workers=1)
    want = [[[lab, p] for lab, p in ld.points] for ld in ref]
    for rank in (0, 1):
        got = json.loads((tmp_path / f"rank{rank}.json").read_text())
        assert got["points"] == want
        assert got["windows"] == [[list(w) for w in ld.windows] for ld in ref]
        (ph,) = got["phases"]
        assert ph["name"] == "curves" and ph["units"] == sum(len(ld.windows) for ld in ref)
        assert ph["workers"] == 2
