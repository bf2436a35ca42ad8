"""docs/your-gearbox.md: every ``$ vibrogear`` line runs as written (exit 0), in a folder
holding the page's ``my_gearbox.toml`` and the repository's test data; the sweep lines
run in the slow tier."""
import re
import shlex
import shutil
from pathlib import Path

import pytest

from vibrogear.cli import main

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "your-gearbox.md"


def _commands():
    return [shlex.split(m)[1:] for m in re.findall(r"^\$ (vibrogear .+)$", DOC.read_text(), re.M)]


def _workdir(tmp_path, monkeypatch):
    (tmp_path / "tests" / "data").mkdir(parents=True)
    shutil.copytree(ROOT / "tests" / "data" / "rexs", tmp_path / "tests" / "data" / "rexs")
    toml = re.search(r"```toml\n(.*?)```", DOC.read_text(), re.S).group(1)
    (tmp_path / "my_gearbox.toml").write_text(toml)
    monkeypatch.chdir(tmp_path)


@pytest.mark.system
def test_doc_commands_fast(tmp_path, monkeypatch):
    cmds = _commands()
    assert len(cmds) >= 6
    _workdir(tmp_path, monkeypatch)
    for argv in cmds:
        if argv[0] == "sweep":
            continue
        assert main(argv) == 0, argv
    assert (tmp_path / "fva.toml").exists()
    assert (tmp_path / "out" / "fva" / "modes.csv").exists()
    assert (tmp_path / "out" / "my_gearbox" / "modes.csv").exists()


@pytest.mark.slow
def test_doc_commands_all(tmp_path, monkeypatch):
    _workdir(tmp_path, monkeypatch)
    for argv in _commands():
        assert main(argv) == 0, argv
    assert (tmp_path / "out" / "fva" / "sweep.npz").exists()
