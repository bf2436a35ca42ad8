"""Rotor scenes through the CLI: they run and reproduce published numbers; bad input exits 2
naming the field and writes nothing."""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main

ROOT = Path(__file__).resolve().parents[2]
FRISWELL = str(ROOT / "configs" / "rotor_friswell_5_9_1.toml")
STEPPED = str(ROOT / "configs" / "rotor_stepped_free_gear.toml")


def read_csv(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


def test_friswell_scene_modes_reproduce_published_values(tmp_path):
    out = tmp_path / "f"
    assert main(["modes", FRISWELL, "--out", str(out), "--quiet"]) == 0
    rows = read_csv(out / "modes.csv")
    assert list(rows[0])[:2] == ["index", "frequency_hz"]
    lat = [r for r in rows if r["mode_type"] == "lateral"][:6]
    w = np.array([float(r["frequency_hz"]) for r in lat]) * 2 * np.pi
    # Friswell et al. (2010) Example 5.9.1 at 4000 rev/min (via ROSS test_examples.py), rad/s
    np.testing.assert_allclose(w, [85.39, 87.80, 251.78, 294.71, 600.18, 827.08], rtol=1e-3)
    assert [r["whirl"] for r in lat] == ["backward", "forward"] * 3
    summary = json.loads((out / "summary.json").read_text())
    assert summary["results"]["modes"]["status"] == "ok"
    assert (out / "mode_shapes.png").is_file() and (out / "master_modes.npz").is_file()
    master = read_csv(out / "master_modes.csv")
    assert sum(int(r["rigid_body"]) for r in master) == 6


def test_friswell_scene_campbell_critical_speeds(tmp_path):
    out = tmp_path / "c"
    assert main(["campbell", FRISWELL, "--out", str(out), "--quiet",
                 "--set", "rotor.campbell.orders=[1.0]"]) == 0
    crit = read_csv(out / "critical_speeds.csv")
    first = [c for c in crit if c["order"] == "1"][:2]
    # at a critical speed the line crosses 1x: f = rpm / 60
    for c in first:
        assert float(c["frequency_hz"]) == pytest.approx(float(c["speed_rpm"]) / 60, rel=1e-5)
    # the first pair lies between the 0 and 4000 rpm values of the first published modes
    # (13.59..13.98 Hz, Friswell 5.9.1), i.e. near 815..839 rpm
    assert all(13.59 * 60 < float(c["speed_rpm"]) < 13.98 * 60 for c in first)
    assert {c["whirl"] for c in first} == {"forward", "backward"}
    assert (out / "campbell.png").is_file() and (out / "campbell.svg").is_file()
    rows = read_csv(out / "campbell.csv")
    assert len(rows) == 31


def test_stepped_free_gear_scene(tmp_path):
    out = tmp_path / "s"
    assert main(["run", STEPPED, "--out", str(out), "--quiet"]) == 0
    npz = np.load(out / "master_modes.npz")
    assert npz["vectors"].shape[0] == 6 * 17 + 1          # 16 elements + the free gear DOF
    assert int(npz["n_rigid"]) == 7                       # free gear with k_t = 0 turns freely
    s = json.loads((out / "summary.json").read_text())["results"]
    assert s["modes"]["status"] == "ok" and s["campbell"]["status"] == "ok"


BAD = [
    ("rotor.sections.0.length=-1", "rotor.sections[0].length"),
    ("rotor.sections.0.length=0", "rotor.sections[0].length"),
    ("rotor.sections.0.outer_diameter=0", "rotor.sections[0].outer_diameter"),
    ("rotor.sections.0.inner_diameter=0.05", "rotor.sections[0].inner_diameter"),
    ("rotor.discs.1.position=1.6", "rotor.discs[1].position"),
    ("rotor.discs.1.position=0.9", "rotor.discs[1].position"),          # not a node
    ("rotor.bearings.1.position=0.0", "rotor.bearings[1].position"),    # two bearings at a node
    ("rotor.material.rho=0", "rotor.material.rho"),
    ("rotor.campbell.rpm_max=-5", "rotor.campbell.rpm_max"),
]


@pytest.mark.parametrize("override, field", BAD)
def test_bad_input_exit_2_names_field_writes_nothing(tmp_path, capsys, override, field):
    out = tmp_path / "bad"
    assert main(["run", FRISWELL, "--out", str(out), "--set", override]) == 2
    err = capsys.readouterr().err
    assert field in err
    assert not out.exists()


@pytest.mark.parametrize("nu", [0.5, -1.0, 0.7])
def test_poisson_ratio_outside_range(tmp_path, capsys, nu):
    out = tmp_path / "bad"
    args = ["check", STEPPED, "--out", str(out), "--set", f"rotor.material.nu={nu}"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "rotor.material.nu" in err and "0.5" in err
    assert not out.exists()


def test_poisson_ratio_implied_by_G(tmp_path, capsys):
    assert main(["check", FRISWELL, "--set", "rotor.material.G=50e9"]) == 2
    assert "rotor.material.G" in capsys.readouterr().err


def test_campbell_needs_its_section(tmp_path, capsys):
    src = (ROOT / "configs" / "rotor_friswell_5_9_1.toml").read_text()
    cut = src[: src.index("[rotor.campbell]")]
    scene = tmp_path / "s.toml"
    scene.write_text(cut)
    out = tmp_path / "o"
    assert main(["campbell", str(scene), "--out", str(out)]) == 2
    assert "rotor.campbell" in capsys.readouterr().err and not out.exists()


def test_cli_exit_code_in_a_subprocess(tmp_path):
    import subprocess
    import sys
    r = subprocess.run([sys.executable, "-m", "vibrogear.cli", "modes", FRISWELL, "--out",
                        str(tmp_path / "x"), "--set", "rotor.sections.0.inner_diameter=0.06"],
                       capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 2 and "rotor.sections[0].inner_diameter" in r.stderr
