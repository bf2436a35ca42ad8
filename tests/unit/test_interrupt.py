"""Ctrl-C: the run stops cleanly (exit 130, no traceback), keeps what finished and says how
to resume; resuming after a change of the model sets the old points aside (issue 14)."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from vibrogear.cli import main

ROOT = Path(__file__).resolve().parents[2]
IMPACT = str(ROOT / "configs" / "impact_pair.toml")
SLOW_POINTS = ["--set", "sweep.n_points=24", "--set", "sweep.transient_periods=3000",
               "--set", 'sweep.directions=["up"]']


@pytest.mark.system
def test_ctrl_c_stops_cleanly_and_a_changed_model_does_not_resume(tmp_path):
    out = tmp_path / "o"
    partial = out / "sweep.partial.jsonl"
    proc = subprocess.Popen([sys.executable, "-m", "vibrogear.cli", "sweep", IMPACT, "--quiet",
                             "--out", str(out), *SLOW_POINTS], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.monotonic()
    while time.monotonic() - t0 < 120 and proc.poll() is None:
        if partial.is_file() and partial.read_text().count("\n") >= 3:
            break
        time.sleep(0.02)
    assert proc.poll() is None, "the sweep finished before it could be interrupted"
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "interrupted" in err and "same command again" in err
    kept = partial.read_text().count("\n")
    assert kept >= 3                                          # (plus its header line)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert summary["results"]["sweep"]["status"] == "interrupted"

    # the same command with a different model (damping): nothing is reused, the old
    # points are set aside (not deleted), and the run completes
    assert main(["sweep", IMPACT, "--quiet", "--out", str(out), *SLOW_POINTS,
                 "--set", "impact_pair.zeta=0.02"]) == 0
    res = json.loads((out / "summary.json").read_text())["results"]["sweep"]
    assert res["resumed_points"] == 0 and res["points"] == 24
    assert "physics" in res["resume"] and "set aside" in res["resume"]
    stale = list(out.glob("sweep.partial.jsonl.stale-*"))
    assert len(stale) == 1 and stale[0].read_text().count("\n") == kept
    assert not partial.exists()


def test_a_recorded_stop_is_raised_once():
    """A signal recorded while workers were forked is raised by the next wait loop, and only
    once: a later run in the same process (a second main()) does not inherit it."""
    import signal

    from vibrogear.pipeline.units_base import Terminated, raise_if_stopped, request_stop

    request_stop(signal.SIGTERM)
    with pytest.raises(Terminated) as e:
        raise_if_stopped()
    assert e.value.signum == signal.SIGTERM
    raise_if_stopped()                      # cleared: nothing raised
