"""SIGTERM and SIGHUP (kill, docker stop, SLURM, a closed terminal) behave as Ctrl-C: the run
stops cleanly with exit 128 + the signal number (143, 129), keeps what finished, writes
summary.json with status "interrupted", the signal and a resume hint, and the same command
resumes (issue 24)."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
IMPACT = str(ROOT / "configs" / "impact_pair.toml")
GEAR = str(ROOT / "configs" / "gear_pair.toml")
SLOW_SWEEP = ["--set", "sweep.n_points=24", "--set", "sweep.transient_periods=3000",
              "--set", 'sweep.directions=["up"]']


def _stop(args, out: Path, ready, sig, timeout: float = 180.0):
    """Start ``vibrogear args --out out``, wait until ``ready(out)``, send ``sig``; returns
    (exit code, stderr)."""
    proc = subprocess.Popen([sys.executable, "-m", "vibrogear.cli", *args, "--quiet",
                             "--out", str(out)], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout and proc.poll() is None and not ready(out):
        time.sleep(0.02)
    assert proc.poll() is None, "the run finished before it could be stopped"
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=timeout)
    return proc.returncode, err


def _lines(path: Path) -> int:
    return path.read_text().count("\n") if path.is_file() else 0


def _summary_written(out: Path) -> bool:
    return (out / "summary.json").is_file()


def _interrupted(out: Path, analysis: str, sig_name: str) -> dict:
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["signal"] == sig_name
    assert "same command again" in summary["resume"]
    assert summary["results"][analysis]["status"] == "interrupted"
    assert sig_name in summary["results"][analysis]["message"]
    assert (out / "report.html").is_file()
    return summary


@pytest.mark.system
@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGHUP, 129)])
def test_sweep_stopped_by_a_signal_keeps_its_points_and_resumes(tmp_path, sig, code):
    out = tmp_path / "o"
    partial = out / "sweep.partial.jsonl"
    rc, err = _stop(["sweep", IMPACT, *SLOW_SWEEP], out, lambda o: _lines(partial) >= 3, sig)
    assert rc == code, err
    assert "Traceback" not in err and f"interrupted by {sig.name}" in err
    _interrupted(out, "sweep", sig.name)
    kept = _lines(partial) - 1                                  # less the header line
    assert kept >= 2
    from vibrogear.cli import main
    assert main(["sweep", IMPACT, "--quiet", "--out", str(out), *SLOW_SWEEP]) == 0
    res = json.loads((out / "summary.json").read_text())["results"]["sweep"]
    assert res["resumed_points"] == kept and res["points"] == 24


@pytest.mark.system
def test_map_stopped_by_sigterm_keeps_its_partial_file(tmp_path):
    out = tmp_path / "m"
    partial = out / "map.partial.jsonl"
    args = ["map", GEAR, "--set", "map.n_speeds=12", "--set", "map.n_loads=3",
            "--set", "map.workers=1"]
    rc, err = _stop(args, out, lambda o: _lines(partial) >= 3, signal.SIGTERM)
    assert rc == 143 and "Traceback" not in err, err
    _interrupted(out, "map", "SIGTERM")
    assert _lines(partial) >= 3


def test_continuation_stopped_by_sigterm(tmp_path):
    out = tmp_path / "c"
    args = ["run", IMPACT, "--set", 'scene.analyses=["time_response", "continuation"]',
            "--set", "continuation.max_points=100000", "--set", "continuation.ds=0.0004",
            "--set", "continuation.ds_max=0.0005",
            "--set", "continuation.omega_min=0.2", "--set", "continuation.omega_max=3.0"]
    rc, err = _stop(args, out, _summary_written, signal.SIGTERM)
    assert rc == 143 and "Traceback" not in err, err
    summary = _interrupted(out, "continuation", "SIGTERM")
    assert summary["results"]["time_response"]["status"] == "ok"     # what finished is kept


def test_runup_stopped_by_sigterm(tmp_path):
    out = tmp_path / "r"
    args = ["run", GEAR, "--set", 'scene.analyses=["modes", "runup"]', "--set", "runup.rate=5.0"]
    rc, err = _stop(args, out, _summary_written, signal.SIGTERM)
    assert rc == 143 and "Traceback" not in err, err
    _interrupted(out, "runup", "SIGTERM")
