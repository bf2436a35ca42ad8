"""A full disk or an I/O error while writing (issue 24): exit 1 naming the file and the reason,
no half-written file, and the same command afterwards resumes and completes.  The error is
injected into the one place bytes reach an output file (pipeline/files.py ``_write``) and the
one place a partial file grows (pipeline/resume.py ``_write_line``)."""
from __future__ import annotations

import errno
import json
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.pipeline import files, resume

ROOT = Path(__file__).resolve().parents[2]
IMPACT = str(ROOT / "configs" / "impact_pair.toml")
RUN = ["sweep", IMPACT, "--quiet", "--set", "sweep.n_points=8", "--set", "sweep.omega_min=0.8",
       "--set", "sweep.omega_max=1.0", "--set", "sweep.transient_periods=40",
       "--set", "sweep.extra_transient_periods=0", "--set", "sweep.record_periods=8",
       "--set", 'sweep.directions=["up"]']


def _fail_after(monkeypatch, module, name, n_ok: int, code: int):
    real = getattr(module, name)
    calls = {"n": 0}

    def failing(fh, data):
        calls["n"] += 1
        if calls["n"] > n_ok:
            fh.write(data[: len(data) // 2])          # what a full disk leaves behind
            raise OSError(code, __import__("os").strerror(code))
        real(fh, data)
    monkeypatch.setattr(module, name, failing)


def _no_half_files(out: Path) -> None:
    assert not [p for p in out.rglob("*") if p.name.endswith(".tmp")]
    for p in out.glob("*.npz"):
        with np.load(p) as z:
            assert z.files                             # whole, or not there at all
    if (out / "summary.json").exists():
        json.loads((out / "summary.json").read_text())


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EIO])
def test_a_full_disk_while_writing_results_exits_1_naming_the_file(tmp_path, monkeypatch,
                                                                     capsys, code):
    out = tmp_path / "o"
    _fail_after(monkeypatch, files, "_write", 0, code)      # the first result file fails
    assert main([*RUN, "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "write failed" in err and str(out) in err and __import__("os").strerror(code) in err
    _no_half_files(out)
    monkeypatch.undo()
    assert main([*RUN, "--out", str(out)]) == 0               # resumes every point
    res = json.loads((out / "summary.json").read_text())["results"]["sweep"]
    assert res["resumed_points"] == 8 and res["points"] == 8
    _no_half_files(out)


def test_a_full_disk_while_appending_points_keeps_the_finished_ones(tmp_path, monkeypatch,
                                                                      capsys):
    out = tmp_path / "o"
    _fail_after(monkeypatch, resume, "_write_line", 4, errno.ENOSPC)   # header + 3 points
    assert main([*RUN, "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "sweep.partial.jsonl" in err and "No space left on device" in err
    monkeypatch.undo()
    assert main([*RUN, "--out", str(out)]) == 0              # the torn line is cut, 3 reused
    res = json.loads((out / "summary.json").read_text())["results"]["sweep"]
    assert res["resumed_points"] == 3 and res["points"] == 8
    _no_half_files(out)
