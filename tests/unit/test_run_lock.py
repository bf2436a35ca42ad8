"""One run per output folder at a time (pipeline/run_lock.py): a second run into a held folder
exits 2 naming the holder, or waits with --wait; a lock left by a killed run (kill -9) is
taken over (issue 24)."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from vibrogear.cli import main

ROOT = Path(__file__).resolve().parents[2]
IMPACT = str(ROOT / "configs" / "impact_pair.toml")
SLOW_SWEEP = ["--set", "sweep.n_points=24", "--set", "sweep.transient_periods=3000",
              "--set", 'sweep.directions=["up"]', "--quiet"]


def _start(out: Path, *extra) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "vibrogear.cli", "sweep", IMPACT, *SLOW_SWEEP,
                             "--out", str(out), *extra], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _wait_points(proc, out: Path, n: int = 2, timeout: float = 120.0) -> None:
    partial = out / "sweep.partial.jsonl"
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout and proc.poll() is None:
        if partial.is_file() and partial.read_text().count("\n") > n:
            return
        time.sleep(0.02)
    raise AssertionError("the run ended before it held the folder")


def test_second_run_into_a_held_folder_exits_2_naming_the_holder(tmp_path, capsys):
    out = tmp_path / "o"
    first = _start(out)
    try:
        _wait_points(first, out)
        assert main(["sweep", IMPACT, *SLOW_SWEEP, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert f"pid {first.pid}" in err and "in use by another run" in err and "--wait" in err
        assert not (out / "summary.json").exists()          # the refused run wrote nothing
    finally:
        first.send_signal(signal.SIGTERM)
        first.communicate(timeout=120)
    assert first.returncode == 143


@pytest.mark.system
def test_wait_takes_the_folder_when_the_holder_ends_and_resumes_its_points(tmp_path):
    out = tmp_path / "o"
    first = _start(out)
    _wait_points(first, out)
    second = _start(out, "--wait")
    time.sleep(1.0)
    assert second.poll() is None                             # waiting, not refused
    first.send_signal(signal.SIGTERM)
    first.communicate(timeout=120)
    _, err = second.communicate(timeout=300)
    assert first.returncode == 143 and second.returncode == 0, err
    res = json.loads((out / "summary.json").read_text())["results"]["sweep"]
    assert res["resumed_points"] >= 2 and res["points"] == 24


def test_lock_of_a_killed_run_is_taken_over(tmp_path):
    out = tmp_path / "o"
    first = _start(out)
    _wait_points(first, out)
    os.kill(first.pid, signal.SIGKILL)                       # no handler runs: the file stays
    first.communicate(timeout=60)
    lock = out / ".vibrogear.lock"
    assert f'"pid": {first.pid}' in lock.read_text()
    assert main(["sweep", IMPACT, *SLOW_SWEEP, "--out", str(out)]) == 0
    res = json.loads((out / "summary.json").read_text())["results"]["sweep"]
    assert res["resumed_points"] >= 2
    assert lock.read_text() == ""                           # released at the end
