"""Output files honour the umask (0644 under the usual 022), as a plain ``open()`` would:
the atomic writes go through a temporary file from ``mkstemp``, which is 0600 on its own."""
from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from vibrogear.cli import main
from vibrogear.pipeline.files import (atomic_copy, atomic_write_npz, atomic_write_text,
                                      new_file_mode)

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def umask():
    """Set the process umask for a test and restore it afterwards."""
    old = os.umask(0o022)
    yield os.umask
    os.umask(old)


def _mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


@pytest.mark.parametrize("mask, expected", [(0o022, 0o644), (0o002, 0o664), (0o077, 0o600)])
def test_atomic_writes_get_the_mode_of_open(tmp_path, umask, mask, expected):
    umask(mask)
    assert new_file_mode() == expected
    with open(tmp_path / "plain", "w"):            # what the operating system gives
        pass
    assert _mode(tmp_path / "plain") == expected
    text = atomic_write_text(tmp_path / "a.txt", "x")
    npz = atomic_write_npz(tmp_path / "a.npz", {"a": [1.0]})
    copy = atomic_copy(text, tmp_path / "b.txt")
    for p in (text, npz, copy):
        assert _mode(p) == expected, p.name
    assert not list(tmp_path.glob(".*.tmp"))


def test_a_run_writes_every_file_0644_under_umask_022(tmp_path, umask):
    out = tmp_path / "out"
    assert main(["run", str(ROOT / "configs" / "impact_pair.toml"), "--quiet", "--out", str(out),
                 "--set", 'scene.analyses=["sweep"]', "--set", "sweep.n_points=3",
                 "--set", "sweep.transient_periods=5", "--set", "sweep.extra_transient_periods=0",
                 "--set", "sweep.record_periods=8"]) == 0
    written = [p for p in out.iterdir() if p.is_file() and not p.name.startswith(".")]
    assert {"summary.json", "report.html", "sweep.npz", "sweep.csv", "bifurcation.png"} <= \
        {p.name for p in written}
    assert {p.name: oct(_mode(p)) for p in written} == {p.name: oct(0o644) for p in written}
