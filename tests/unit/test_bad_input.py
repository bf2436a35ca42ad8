"""Malformed scenes and command lines: each is rejected before anything is computed or
written, with exit code 2 and a message naming the field path (issue 14).

Every case runs ``vibrogear run`` with the runner replaced by a tripwire, from an empty
working folder, and checks: the exit code, the field path (and the expected type/range
where it is a type error) in the message, and that the working folder is still empty.
"""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from vibrogear import runner
from vibrogear.cli import main
from vibrogear.config import load_scene

ROOT = Path(__file__).resolve().parents[2]
IMPACT = str(ROOT / "configs" / "impact_pair.toml")
GEAR_PAIR = str(ROOT / "configs" / "gear_pair.toml")
SINGLE = str(ROOT / "configs" / "single_stage.toml")


def _scene_file(tmp, name: str, text: str | bytes) -> str:
    p = tmp / "scenes" / name
    p.parent.mkdir(exist_ok=True)
    (p.write_bytes if isinstance(text, bytes) else p.write_text)(text)
    return str(p)


def _impact_text() -> str:
    return Path(IMPACT).read_text()


# (id, how to make the command line, expected text in the message (field path first))
CASES = [
    # --- output paths ---
    ("out-under-a-file", lambda t: [IMPACT, "--out", str(t / "afile" / "x")], ["--out", "is a file"]),
    ("out-is-a-file", lambda t: [IMPACT, "--out", str(t / "afile")], ["--out", "not a folder"]),
    ("out-too-long", lambda t: [IMPACT, "--out", str(t / ("a" * 300))], ["--out", "255"]),
    ("out-empty", lambda t: [IMPACT, "--out", ""], ["--out", "empty"]),
    ("out-unwritable", lambda t: [IMPACT, "--out", "/proc/vibrogear-out"], ["--out", "cannot create"]),
    ("name-dotdot", lambda t: [IMPACT, "--set", 'scene.name="../../x"'], ["scene.name", "safe file name"]),
    ("name-absolute", lambda t: [IMPACT, "--set", 'scene.name="/tmp/x"'], ["scene.name", "safe file name"]),
    ("name-empty", lambda t: [IMPACT, "--set", 'scene.name=""'], ["scene.name", "empty"]),
    ("name-too-long", lambda t: [IMPACT, "--set", f'scene.name="{"n" * 300}"'],
     ["scene.name", "at most 100 characters"]),
    # --- the scene file itself ---
    ("scene-is-a-folder", lambda t: [str(t / "scenes_dir")], ["scenes_dir", "is a folder"]),
    ("scene-is-a-fifo", lambda t: [str(t / "fifo.toml")], ["fifo.toml", "not a regular file"]),
    ("scene-link-loop", lambda t: [str(t / "loop1.toml")], ["loop1.toml", "symbolic link loop"]),
    ("scene-missing", lambda t: [str(t / "nope.toml")], ["nope.toml", "no such file"]),
    ("deep-nesting", lambda t: [_scene_file(t, "deep.toml", "a = " + "[" * 5000 + "]" * 5000)],
     ["deep.toml", "nested too deeply"]),
    ("not-utf8", lambda t: [_scene_file(t, "latin.toml", b"[scene]\nname = \"\xe9\"\n")],
     ["latin.toml", "not UTF-8"]),
    # --- types, keys and tables ---
    ("string-for-number", lambda t: [IMPACT, "--set", 'integration.rtol="0.015"'],
     ["integration.rtol", "expected a number > 0 and < 1", "a string '0.015'"]),
    ("bool-for-int", lambda t: [IMPACT, "--set", "sweep.n_points=true"],
     ["sweep.n_points", "expected an integer", "a boolean"]),
    ("missing-key", lambda t: [_scene_file(t, "nobr.toml", _impact_text().replace("b_r = 1.0", ""))],
     ["impact_pair.b_r", "missing required key", "a number > 0", "required keys here"]),
    ("unknown-key", lambda t: [IMPACT, "--set", "impact_pair.zetta=0.1"],
     ["impact_pair.zetta", "did you mean 'zeta'", "allowed keys"]),
    ("table-typo", lambda t: [_scene_file(t, "typo.toml", _impact_text().replace(
        "[integration]", "[integraton]"))], ["integraton", "line 19", "did you mean 'integration'"]),
    ("indexed-set-out-of-range", lambda t: [GEAR_PAIR, "--set", "gearbox.gears[0].teeth=4"],
     ["gearbox.gears[0].teeth", ">= 5"]),
    ("indexed-set-no-entry", lambda t: [GEAR_PAIR, "--set", "gearbox.gears[7].teeth=30"],
     ["gearbox.gears[7]", "the list has 2 entries"]),
    # --- layout checks that need no solve ---
    ("ball-bearing-without-elements", lambda t: [GEAR_PAIR, "--set", 'gearbox.bearings[0].type="ball"'],
     ["gearbox.bearings[0].elements", "rolling elements"]),
    ("elements-differ-from-bore", lambda t: [SINGLE, "--set", "gearbox.bearings[0].elements=9"],
     ["gearbox.bearings[0].elements", "8 coupling points"]),
    ("two-bearings-one-bore", lambda t: [SINGLE, "--set", "gearbox.bearings[1].position=0.06"],
     ["gearbox.bearings[1].position", "already carries gearbox.bearings[0]"]),
    ("bearing-far-from-bore", lambda t: [SINGLE, "--set", "gearbox.bearings[1].position=0.14"],
     ["gearbox.bearings[1].position", "0.045 m from the nearest bore"]),
    ("duplicate-bore-names", lambda t: [SINGLE, "--set", 'housing.bores[1].name="input"'],
     ["housing.bores[1].name", "used twice"]),
    ("unknown-bore", lambda t: [SINGLE, "--set", 'gearbox.shafts[1].bore="outptu"'],
     ["gearbox.shafts[1].bore", "unknown bore"]),
    ("gear-through-floor", lambda t: [SINGLE, "--set", "housing.bores[0].z=0.06",
                                      "--set", "housing.bores[1].z=0.06"],
     ["gearbox.gears[1].teeth", "into the housing floor"]),
    ("gear-face-outside-cavity", lambda t: [SINGLE, "--set", "gearbox.gears[0].position=0.04",
                                            "--set", "gearbox.gears[1].position=0.04"],
     ["gearbox.gears[0].position", "not inside the cavity"]),
    ("huge-time-response", lambda t: [IMPACT, "--set", 'scene.analyses=["time_response"]',
                                      "--set", "time_response.periods=1e12"],
     ["time_response.periods", "GiB", "periods must be <="]),
]


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """An empty working folder (default outputs would go to ./out), with the odd files the
    cases name, and a runner that must not be reached."""
    work = tmp_path / "work"
    work.mkdir()
    (tmp_path / "afile").write_text("x")
    (tmp_path / "scenes_dir").mkdir()
    os.mkfifo(tmp_path / "fifo.toml")
    os.symlink(tmp_path / "loop2.toml", tmp_path / "loop1.toml")
    os.symlink(tmp_path / "loop1.toml", tmp_path / "loop2.toml")
    monkeypatch.chdir(work)

    def tripwire(*a, **k):
        raise AssertionError("run_scene reached: the input was not rejected first")
    monkeypatch.setattr(runner, "run_scene", tripwire)
    return work


@pytest.mark.parametrize("make_args, expected", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_exits_2_naming_the_field_and_writes_nothing(workdir, tmp_path, capsys,
                                                               make_args, expected):
    before = sorted(p.name for p in tmp_path.iterdir())
    code = main(["run", *make_args(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith("vibrogear: invalid input: "), err
    msg = err[len("vibrogear: invalid input: "):]
    assert msg.startswith(expected[0]) or f"/{expected[0]}" in msg.split(":")[0], msg
    for text in expected[1:]:
        assert text in msg, msg
    assert list(workdir.iterdir()) == []
    assert sorted(p.name for p in tmp_path.iterdir() if p.name != "scenes") == \
        [n for n in before if n != "scenes"]


def test_check_reports_the_same_errors_as_run(workdir, tmp_path, capsys):
    """``check`` runs every check ``run`` does (here: a layout check and an --out check)."""
    for args in ([SINGLE, "--set", "gearbox.bearings[0].elements=9"],
                 [IMPACT, "--out", str(tmp_path / "afile")]):
        assert main(["check", *args]) == 2
        assert main(["run", *args]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0] == err[1] and err[2] == err[3]


def test_byte_order_mark_is_accepted(tmp_path, capsys):
    p = tmp_path / "bom.toml"
    p.write_bytes(b"\xef\xbb\xbf" + Path(IMPACT).read_bytes())
    assert main(["check", str(p), "--out", str(tmp_path / "o")]) == 0
    assert load_scene(p) == load_scene(IMPACT)
    assert not (tmp_path / "o").exists()


def test_indexed_override_sets_the_list_entry():
    """``gearbox.gears[0].width=...`` (the syntax error messages print) sets gears[0]."""
    scene = load_scene(GEAR_PAIR, ("gearbox.gears[0].width=0.025", "gearbox.gears.1.width=0.026"))
    assert (scene.gearbox.gears[0].width, scene.gearbox.gears[1].width) == (0.025, 0.026)


def test_shipped_scenes_pass_check(tmp_path, capsys):
    """Every shipped scene passes the layout checks (single_stage's z2 tip now inside)."""
    for path in sorted((ROOT / "configs").glob("*.toml")):
        assert main(["check", str(path), "--out", str(tmp_path / "o")]) == 0, path
    assert not (tmp_path / "o").exists()


def test_cache_folder_that_is_a_file(tmp_path, monkeypatch, capsys):
    (tmp_path / "f").write_text("not a folder")
    monkeypatch.setenv("VIBROGEAR_CACHE_DIR", str(tmp_path / "f"))
    assert main(["cache", "clear"]) == 2
    assert "VIBROGEAR_CACHE_DIR" in capsys.readouterr().err
    assert (tmp_path / "f").read_text() == "not a folder"
