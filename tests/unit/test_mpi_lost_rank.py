"""A lost MPI rank (issue 24, item 4): under ``mpirun --enable-recovery`` the other ranks
finish every other unit, the run exits 1 naming the unit the lost rank was computing (and
the rank), every finished point stays in the partial file, ``summary.json`` records it, and
the same command computes only the missing points, giving the uninterrupted run's result.

The rank is killed by the test hook ``VIBROGEAR_TEST_LOSE_RANK=R:N`` (rank R SIGKILLs itself
after handing over its N-th point, :mod:`vibrogear.pipeline.mpi_units`), so where it dies
does not depend on timing.  Open MPI 4.1's ``mpirun --enable-recovery`` itself exits 0
whatever the ranks return, so each rank's own exit code is read from a file written by a
two-line wrapper around :func:`vibrogear.cli.main`."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from vibrogear.pipeline.resume import read_items

ROOT = Path(__file__).resolve().parents[2]
IMPACT = str(ROOT / "configs" / "impact_pair.toml")
GEAR = str(ROOT / "configs" / "gear_pair.toml")
MPIRUN = shutil.which("mpirun")

pytestmark = [pytest.mark.mpi, pytest.mark.skipif(MPIRUN is None, reason="no mpirun")]

#: 16 points in 4 pieces per direction: 8 units of 4 points
SWEEP = ["sweep", IMPACT, "--set", "sweep.n_points=16", "--set", "sweep.segments=4"]
#: 2 loads x 2 directions: 4 units of 3 points
MAP = ["map", GEAR, "--set", "map.n_speeds=3", "--set", "map.n_loads=2",
       "--set", "map.curves=false", "--set", "map.transient_periods=40",
       "--set", "map.extra_transient_periods=0", "--set", "map.record_periods=8",
       "--set", "map.max_period=4"]

#: vibrogear's command line on one rank, its exit code written to $VG_RC_DIR/rc.<rank>
WRAPPER = ("import os, sys\nfrom vibrogear.cli import main\nrc = main(sys.argv[1:])\n"
           "open(os.path.join(os.environ['VG_RC_DIR'], 'rc.' + "
           "os.environ['OMPI_COMM_WORLD_RANK']), 'w').write(str(rc))\nsys.exit(rc)\n")


def _mpirun(args, out: Path, rc_dir: Path, lose: str | None = None, timeout: float = 600,
            recovery: bool = True):
    rc_dir.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "VG_RC_DIR": str(rc_dir)}
    env.pop("VIBROGEAR_TEST_LOSE_RANK", None)
    if lose is not None:
        env["VIBROGEAR_TEST_LOSE_RANK"] = lose
    cmd = [MPIRUN, "-n", "2", "--oversubscribe"] + (["--enable-recovery"] if recovery else [])
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    r = subprocess.run(cmd + [sys.executable, "-c", WRAPPER, *args, "--quiet", "--out", str(out)],
                       env=env, cwd=ROOT, capture_output=True, text=True, timeout=timeout)
    codes = {int(p.name.split(".")[1]): int(p.read_text()) for p in rc_dir.glob("rc.*")}
    return (codes, r.stderr) if recovery else (r.returncode, r.stderr)


def _partial_lines(path: Path) -> list[dict]:
    """Every line of a partial file, each a whole JSON object (nothing torn)."""
    text = path.read_text()
    assert text.endswith("\n")
    return [json.loads(line) for line in text.splitlines()]


def _same_arrays(a: Path, b: Path) -> None:
    with np.load(a, allow_pickle=False) as za, np.load(b, allow_pickle=False) as zb:
        assert sorted(za.files) == sorted(zb.files)
        for k in za.files:
            if "wall" not in k:                  # timings differ, nothing else
                assert np.array_equal(za[k], zb[k]), k


def _lost_then_resumed(tmp_path, args, partial_name, total, unit_len, npz, lose="1:1"):
    ref = tmp_path / "ref"
    from vibrogear.cli import main
    assert main([*args, "--quiet", "--out", str(ref)]) == 0    # uninterrupted, in-process

    out = tmp_path / "out"
    codes, err = _mpirun(args, out, tmp_path / "rc1", lose=lose)
    lost_rank = int(lose.split(":")[0])
    assert lost_rank not in codes                 # killed: it wrote no exit code
    assert codes == {1 - lost_rank: 1}, err[-3000:]
    assert "Traceback" not in err, err[-3000:]
    assert f"vibrogear: lost MPI rank: MPI rank {lost_rank} was lost" in err
    assert "Run the same command again" in err
    summary = json.loads((out / "summary.json").read_text())
    analysis = args[0]
    rec = summary["results"][analysis]
    assert summary["status"] == "failed" and rec["status"] == "failed"
    assert rec["lost_ranks"] == [lost_rank] and "same command" in rec["resume"]
    (unit,) = rec["lost_units"]
    assert unit["rank"] == lost_rank and unit["label"] in err and unit["label"] in rec["message"]
    # the unit is named by what it computes: its parameter range
    assert ("Omega =" if analysis == "sweep" else " rpm (points ") in unit["label"]
    assert unit["items_kept"] == 1               # it died after handing over its first point
    assert not (out / npz).exists()              # no result from an incomplete run
    lines = _partial_lines(out / partial_name)   # intact: a header, then whole points
    assert lines[0]["kind"] == "header" and all(x["kind"] == "point" for x in lines[1:])
    kept = len(lines) - 1
    assert kept == len(read_items(out / partial_name)) == total - (unit_len - 1)

    codes, err = _mpirun(args, out, tmp_path / "rc2")
    assert codes == {0: 0, 1: 0}, err[-3000:]
    rec = json.loads((out / "summary.json").read_text())["results"][analysis]
    assert rec["status"] in ("ok", "partial") and "lost_units" not in rec
    assert not (out / partial_name).exists()
    _same_arrays(out / npz, ref / npz)
    return kept, rec


def test_a_sweep_that_loses_a_rank_names_the_unit_and_the_same_command_completes(tmp_path):
    kept, rec = _lost_then_resumed(tmp_path, SWEEP, "sweep.partial.jsonl", total=32,
                                   unit_len=4, npz="sweep.npz")
    assert rec["resumed_points"] == kept and rec["points"] == 32


@pytest.mark.slow   # the sweep case covers the same path in CI
def test_a_map_that_loses_a_rank_names_the_unit_and_the_same_command_completes(tmp_path):
    _, rec = _lost_then_resumed(tmp_path, MAP, "map.partial.jsonl", total=12, unit_len=3,
                                npz="map.npz")
    assert rec["points"] == 12


@pytest.mark.system
def test_losing_rank_0_ends_the_others_without_a_hang_and_resumes(tmp_path):
    """Rank 0 writes the files: the others cannot go on; they exit 1 at once (no hang), the
    partial file keeps what rank 0 received, and the same command completes."""
    out = tmp_path / "out"
    codes, err = _mpirun(SWEEP, out, tmp_path / "rc1", lose="0:3")
    assert codes == {1: 1}, err[-3000:]
    assert "rank 0" in err and "was lost" in err and "Traceback" not in err
    lines = _partial_lines(out / "sweep.partial.jsonl")
    assert len(lines) - 1 >= 3
    codes, err = _mpirun(SWEEP, out, tmp_path / "rc2")
    assert codes == {0: 0, 1: 0}, err[-3000:]
    rec = json.loads((out / "summary.json").read_text())["results"]["sweep"]
    assert rec["resumed_points"] == len(lines) - 1 and rec["points"] == 32


@pytest.mark.slow   # the sweep case covers the same path in CI
def test_without_recovery_mpirun_ends_the_job_and_the_same_command_completes(tmp_path):
    """Open MPI's default: a rank's death ends the job (the others get SIGTERM, then SIGKILL,
    within about 2 s), mpirun exits non-zero; every point rank 0 received is in the partial
    file, whole, and the same command computes only the others."""
    out = tmp_path / "out"
    code, err = _mpirun(SWEEP, out, tmp_path / "rc1", lose="1:1", recovery=False)
    assert code != 0, err[-3000:]
    lines = _partial_lines(out / "sweep.partial.jsonl")
    assert lines[0]["kind"] == "header" and all(x["kind"] == "point" for x in lines[1:])
    assert 1 <= len(lines) - 1 < 32
    code, err = _mpirun(SWEEP, out, tmp_path / "rc2", recovery=False)
    assert code == 0, err[-3000:]
    rec = json.loads((out / "summary.json").read_text())["results"]["sweep"]
    assert rec["resumed_points"] == len(lines) - 1 and rec["points"] == 32


EXECUTOR_SCRIPT = r"""
import json, os, sys, time
from mpi4py import MPI
from vibrogear.pipeline.executors import broadcast, run_units
from vibrogear.pipeline.outcome import LostUnits
rank = MPI.COMM_WORLD.rank
def work(unit, emit):
    for k in range(3):
        time.sleep(0.02)
        emit((unit, k, rank))
    return unit
seen = []
try:
    run_units(work, list(range(8)), on_result=lambda i, it: seen.append(it),
              describe=lambda u: f"unit #{u}")
    out = {"lost": None}
except LostUnits as exc:
    out = {"lost": str(exc), "record": exc.record}
out.update(seen=seen, after=broadcast("from rank 0" if rank == 0 else None))
json.dump(out, open(os.path.join(sys.argv[1], f"rank{rank}.json"), "w"))
"""


def test_run_units_after_a_lost_rank_finishes_the_rest_and_names_the_unit(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1",
           "VIBROGEAR_TEST_LOSE_RANK": "1:1"}
    cmd = [MPIRUN, "-n", "2", "--oversubscribe", "--enable-recovery"]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    r = subprocess.run(cmd + [sys.executable, "-c", EXECUTOR_SCRIPT, str(tmp_path)], env=env,
                       cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert not (tmp_path / "rank1.json").exists(), r.stderr[-3000:]     # it was killed
    out = json.loads((tmp_path / "rank0.json").read_text())
    (unit,) = out["record"]["lost_units"]
    assert unit["rank"] == 1 and unit["items_kept"] == 1
    assert f"unit #{unit['unit']}" in out["lost"] and "on rank 1" in out["lost"]
    got = {(u, k) for u, k, _ in out["seen"]}
    assert len(got) == len(out["seen"])          # nothing delivered twice
    # every other unit finished (rank 0 took those rank 1 had queued), the lost one has
    # the one point it handed over
    assert got == {(u, k) for u in range(8) for k in range(3) if u != unit["unit"]} \
        | {(unit["unit"], 0)}
    assert out["after"] == "from rank 0"         # broadcast skips the lost rank
