"""``vibrogear optimize`` killed (SIGKILL) in the middle and run again: the evaluations in
``optimize.partial.jsonl`` are read back, none is lost or run twice, and the run ends with the
same evaluations as one that was never interrupted.  Batches on MPI ranks: the serial
evaluations."""
from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from test_optimize import LINEAR

ROOT = Path(__file__).resolve().parents[2]


def _points(path: Path) -> list[dict]:
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines()
            if line.endswith("}") and '"kind":"point"' in line]


def _cmd(scene: Path, out: Path) -> list[str]:
    return [sys.executable, "-m", "vibrogear.cli", "optimize", str(scene), "--out", str(out),
            "--quiet"]


def _values(out: Path) -> list[str]:
    with open(out / "optimize.csv", newline="") as fh:
        return [row["impact_pair.kappa"] for row in csv.DictReader(fh)]


@pytest.mark.system
def test_kill_and_resume_loses_and_repeats_no_evaluation(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(LINEAR)
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    ref = tmp_path / "ref"
    subprocess.run(_cmd(scene, ref), check=True, cwd=ROOT, env=env, timeout=600)

    out = tmp_path / "out"
    partial = out / "optimize.partial.jsonl"
    proc = subprocess.Popen(_cmd(scene, out), cwd=ROOT, env=env, start_new_session=True)
    try:
        deadline = time.monotonic() + 300
        while len(_points(partial)) < 3 and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    before = _points(partial)
    assert 3 <= len(before) < len(_values(ref)), "killed too late to test a resume"

    subprocess.run(_cmd(scene, out), check=True, cwd=ROOT, env=env, timeout=600)
    doc = json.loads((out / "optimize.json").read_text())
    assert doc["resumed_evaluations"] == len(before)
    # the same evaluations, in the same order, as the run never interrupted; none twice
    assert _values(out) == _values(ref)
    assert len(set(_values(out))) == len(_values(out))
    # so the second run computed only the evaluations the first had not finished
    assert doc["evaluations"] == json.loads((ref / "optimize.json").read_text())["evaluations"]
    assert not partial.exists()


MPIRUN = shutil.which("mpirun")


@pytest.mark.system
@pytest.mark.mpi
@pytest.mark.skipif(MPIRUN is None, reason="no mpirun")
def test_batches_on_mpi_ranks_give_the_serial_evaluations(tmp_path):
    """A generation of differential evolution runs on 2 MPI ranks: the same evaluations as
    one process (rank 0 alone writes the files)."""
    scene = tmp_path / "s.toml"
    scene.write_text(LINEAR.replace("budget = 30", 'budget = 8\nmethod = "differential-evolution"'))
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    subprocess.run(_cmd(scene, tmp_path / "serial"), check=True, cwd=ROOT, env=env, timeout=600)
    mpi = [MPIRUN, "-n", "2", "--oversubscribe"] + (["--allow-run-as-root"] if os.geteuid() == 0
                                                     else [])
    subprocess.run(mpi + _cmd(scene, tmp_path / "mpi"), check=True, cwd=ROOT, env=env,
                   timeout=600)
    assert _values(tmp_path / "mpi") == _values(tmp_path / "serial")
    assert len(_values(tmp_path / "serial")) == 8
