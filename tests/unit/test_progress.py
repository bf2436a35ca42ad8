"""Progress bars: rate and ETA on a terminal, silent otherwise or with --quiet."""
from __future__ import annotations

import io

from vibrogear.cli import main
from vibrogear.pipeline.progress import Progress


class FakeTTY(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_terminal_gets_rate_and_eta():
    s = FakeTTY()
    with Progress(4, "sweep", stream=s) as bar:
        for k in range(4):
            bar.update(1, f"p={k}")
    text = s.getvalue()
    assert "4/4" in text and "/s" in text and "ETA" in text and "sweep" in text


def test_silent_when_not_a_terminal_or_quiet():
    s = io.StringIO()
    with Progress(3, "x", stream=s) as bar:
        bar.update(3)
    assert s.getvalue() == ""
    t = FakeTTY()
    with Progress(3, "x", stream=t, quiet=True) as bar:
        bar.update(3)
    assert t.getvalue() == ""


def test_cli_run_prints_only_the_verdict_when_quiet(tmp_path, capsys):
    """--quiet: no progress on stderr, one line on stdout: the findings' verdict."""
    code = main(["run", "configs/impact_pair.toml", "--quiet", "--out", str(tmp_path / "o"),
                 "--set", "scene.analyses=[\"sweep\"]", "--set", "sweep.n_points=3",
                 "--set", "sweep.transient_periods=5", "--set", "sweep.extra_transient_periods=0",
                 "--set", "sweep.record_periods=8"])
    assert code == 0
    captured = capsys.readouterr()
    import json
    verdict = json.loads((tmp_path / "o" / "summary.json").read_text())["findings"]["verdict"]
    assert captured.err == "" and captured.out == verdict + "\n"
