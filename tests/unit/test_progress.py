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


def _last_line(text: str) -> str:
    return text.replace("\r", "\n").strip().splitlines()[-1]


def test_finished_bar_ends_at_its_count_not_its_cap():
    """A cap (continuation max_points = 12) reached at 6: the bar ends 6/6, drawn full;
    one that overran an estimate ends at its count too."""
    s = FakeTTY()
    with Progress(12, "continuation", stream=s) as bar:
        for _ in range(6):
            bar.update(1)
    last = _last_line(s.getvalue())
    assert "6/6" in last and "/12" not in last and "#" * 5 in last
    s = FakeTTY()
    with Progress(3, "runup", stream=s) as bar:
        bar.update(5)
    assert "5/5" in _last_line(s.getvalue())


def test_interrupted_bar_keeps_its_cap():
    s = FakeTTY()
    try:
        with Progress(300, "continuation", stream=s) as bar:
            bar.update(167)
            raise KeyboardInterrupt
    except KeyboardInterrupt:
        pass
    assert "167/300" in _last_line(s.getvalue())
