"""Scene validation: bad input fails before any work, names the field, exit code 2,
nothing written; overrides and `check` work."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from vibrogear.cli import main
from vibrogear.config import ConfigError, load_scene, scene_from_dict

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "configs" / "impact_pair.toml"


def _run(tmp_path, *args):
    out = tmp_path / "out"
    code = main(["run", str(SCENE), "--out", str(out), "--quiet", *args])
    return code, out


# (override, field path that the message must name)
BAD_OVERRIDES = [
    ("impact_pair.zeta=-0.01", "impact_pair.zeta"),            # negative damping
    ("impact_pair.zeta=1.5", "impact_pair.zeta"),              # beyond the allowed range
    ("impact_pair.b_r=0", "impact_pair.b_r"),                   # zero clearance
    ("impact_pair.b_r=-1", "impact_pair.b_r"),                  # negative clearance
    ("impact_pair.kappa=2", "impact_pair.kappa"),
    ("impact_pair.f_p=nan", "impact_pair.f_p"),                 # non-finite
    ("impact_pair.f_m=inf", "impact_pair.f_m"),                 # non-finite
    ("impact_pair.zeta=\"small\"", "impact_pair.zeta"),         # wrong type
    ("impact_pair.colour=1", "impact_pair.colour"),             # unknown key
    ("sweep.omega_max=0.05", "sweep.omega_max"),                # reversed range
    ("sweep.omega_min=3.0", "sweep.omega_max"),                 # empty range
    ("sweep.n_points=1", "sweep.n_points"),
    ("sweep.n_points=2.5", "sweep.n_points"),                   # float for an integer
    ("sweep.directions=[\"sideways\"]", "sweep.directions[0]"),
    ("continuation.ds=1.0", "continuation.ds"),                 # ds > ds_max
    ("continuation.start=\"middle\"", "continuation.start"),
    ("integration.rtol=0", "integration.rtol"),
    ("integration.max_steps=true", "integration.max_steps"),    # bool for an integer
    ("scene.analyses=[\"dance\"]", "scene.analyses[0]"),
    ("scene.analyses=[]", "scene.analyses"),
    ("scene.analyses=[\"sweep\",\"sweep\"]", "scene.analyses[1]"),
]


@pytest.mark.parametrize("override,field", BAD_OVERRIDES)
def test_bad_value_exit_2_names_field_writes_nothing(tmp_path, capsys, override, field):
    code, out = _run(tmp_path, "--set", override)
    err = capsys.readouterr().err
    assert code == 2
    assert field in err
    assert not out.exists()


def _minimal():
    return {"scene": {"name": "x", "analyses": ["sweep"]},
            "impact_pair": {"zeta": 0.01, "kappa": 0.5, "f_m": 0.1, "f_p": 0.1, "b_r": 1.0},
            "sweep": {"omega_min": 0.1, "omega_max": 3.0}}


def test_missing_sections_and_keys_are_named():
    d = _minimal()
    del d["sweep"]
    with pytest.raises(ConfigError, match=r"sweep: missing section"):
        scene_from_dict(d)
    d = _minimal()
    del d["impact_pair"]
    with pytest.raises(ConfigError, match="missing section"):
        scene_from_dict(d)
    d = _minimal()
    del d["impact_pair"]["b_r"]
    with pytest.raises(ConfigError, match=r"impact_pair\.b_r: missing required key"):
        scene_from_dict(d)
    d = _minimal()
    d["scene"]["analyses"] = ["campbell"]
    with pytest.raises(ConfigError, match=r"scene\.analyses\[0\].*rotor"):
        scene_from_dict(d)


def test_range_message_states_allowed_range():
    d = _minimal()
    d["impact_pair"]["b_r"] = 0.0
    with pytest.raises(ConfigError, match=r"must be > 0"):
        scene_from_dict(d)


def test_not_toml_and_missing_file(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[scene\nname = ")
    assert main(["check", str(bad)]) == 2
    assert "not a valid TOML file" in capsys.readouterr().err
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe\x00\x01")
    assert main(["check", str(binary)]) == 2
    assert main(["check", str(tmp_path / "nope.toml")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_check_and_overrides(capsys):
    assert main(["check", str(SCENE)]) == 0
    assert "ok" in capsys.readouterr().out
    s = load_scene(SCENE, ("impact_pair.zeta=0.05", "sweep.n_points=7", "sweep.directions=[\"up\"]"))
    assert s.impact_pair.zeta == 0.05 and s.sweep.n_points == 7 and s.sweep.directions == ("up",)
    assert s.impact_pair.kappa == 0.5          # untouched values keep the file's
    with pytest.raises(ConfigError, match="--set"):
        load_scene(SCENE, ("no_equals_sign",))


def test_frozen():
    s = load_scene(SCENE)
    with pytest.raises(Exception):
        s.impact_pair.zeta = 1.0  # type: ignore[misc]


def test_impact_scene_never_imports_fe_stack(tmp_path):
    """The runner resolves the stages a scene needs: no dolfinx, gmsh or petsc4py."""
    code = (
        "import sys\n"
        "from vibrogear.cli import main\n"
        f"rc = main(['run', {str(SCENE)!r}, '--quiet', '--out', {str(tmp_path / 'o')!r},\n"
        "  '--set', 'scene.analyses=[\"time_response\"]', '--set', 'time_response.periods=3'])\n"
        "assert rc == 0, rc\n"
        "bad = [m for m in ('dolfinx', 'gmsh', 'petsc4py', 'slepc4py', 'mpi4py') if m in sys.modules]\n"
        "assert not bad, bad\n"
        "print('clean')\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert "clean" in r.stdout
    assert (tmp_path / "o" / "time_response.csv").is_file()
