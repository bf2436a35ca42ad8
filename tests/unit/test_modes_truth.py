"""Modal statuses and tables that tell the truth (issue 14), each against an independent
statement: rigid-body counts from kinematics, a closed mesh equal to a linear spring, a
complete reduction basis equal to the full eigensolution, non-finite results failing."""
from __future__ import annotations

import csv
import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.config import load_scene
from vibrogear.models.rotor.model import build_rotor_model
from vibrogear.solvers.rotor.modes import rotor_modes

ROOT = Path(__file__).resolve().parents[2]
GEAR_PAIR = str(ROOT / "configs" / "gear_pair.toml")
FRISWELL = str(ROOT / "configs" / "rotor_friswell_5_9_1.toml")
FREE = ["--set", "gearbox.couplings=[]", "--set", "gearbox.bearings[0].axial_stiffness=0",
        "--set", "gearbox.bearings[2].axial_stiffness=0", "--set", "gearbox.modes_rpm=0"]


def _modes(tmp_path, name, *sets):
    out = tmp_path / name
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["modes", GEAR_PAIR, "--quiet", "--out", str(out), *sets]) == 0
    summary = json.loads((out / "summary.json").read_text())["results"]["modes"]
    with open(out / "modes.csv") as fh:
        rows = list(csv.DictReader(fh))
    return summary, rows, [str(w.message) for w in caught]


def test_gearbox_rigid_body_modes_counted_not_listed(tmp_path):
    """gear_pair without motor/load couplings and axial springs, at rest: each shaft is free
    to slide axially (2) and to turn (2, the mesh is open in its backlash): 4 rigid-body
    modes.  With zero backlash the unloaded mesh is closed and ties the two rotations: 3.
    None is listed in modes.csv; the resonance map at 0 rpm draws without warnings."""
    s_open, rows_open, warned = _modes(tmp_path, "open", *FREE)
    assert s_open["n_rigid"] == 4 and not warned
    s_closed, rows_closed, warned = _modes(tmp_path, "closed", *FREE,
                                           "--set", "gearbox.meshes[0].backlash=0")
    assert s_closed["n_rigid"] == 3 and not warned
    for rows in (rows_open, rows_closed):
        f = np.array([float(r["frequency_hz"]) for r in rows])
        assert f.min() > 10.0                             # the elastic modes only
        zeta = np.array([float(r["damping_ratio"]) for r in rows])
        assert np.all(zeta > -1e-9)
        assert all(0.0 <= float(r["mesh_energy_G1"]) <= 1.0 + 1e-9 for r in rows)
    # the closed mesh adds one elastic mode (the two rotations against the mesh spring)
    assert len(rows_closed) == len(rows_open) + 1


def test_unloaded_zero_backlash_mesh_linearises_as_the_loaded_one(tmp_path):
    """With linear laws only (spring bearings, mesh exponent 1) the tangent stiffness of a
    closed mesh is its stiffness whatever the load: the unloaded zero-backlash mesh (twist
    0, deformation exactly on the flank) must give the modes of the loaded one."""
    common = ["--set", "gearbox.meshes[0].backlash=0", "--set", "gearbox.modes_rpm=3000"]
    _, unloaded, _ = _modes(tmp_path, "u", *common, "--set", "gearbox.couplings[0].twist=0",
                            "--set", "gearbox.couplings[1].twist=0")
    _, loaded, _ = _modes(tmp_path, "l", *common)
    fu = np.array([float(r["frequency_hz"]) for r in unloaded])
    fl = np.array([float(r["frequency_hz"]) for r in loaded])
    np.testing.assert_allclose(fu, fl, rtol=1e-9)
    assert max(float(r["mesh_energy_G1"]) for r in unloaded) > 0.05


def test_modes_csv_frequency_is_the_natural_frequency_at_full_precision(tmp_path):
    """Both modes.csv files: frequency_hz = |lambda| / 2 pi, damped_frequency_hz =
    Im(lambda) / 2 pi, so damped = natural sqrt(1 - zeta^2); written with repr (round-trip)."""
    _, rows, _ = _modes(tmp_path, "g")
    out = tmp_path / "r"
    assert main(["modes", FRISWELL, "--quiet", "--out", str(out),
                 "--set", "rotor.bearings[0].cxx=200.0"]) == 0
    with open(out / "modes.csv") as fh:
        rotor_rows = list(csv.DictReader(fh))
    for table in (rows, rotor_rows):
        fn = np.array([float(r["frequency_hz"]) for r in table])
        fd = np.array([float(r["damped_frequency_hz"]) for r in table])
        z = np.array([float(r["damping_ratio"]) for r in table])
        np.testing.assert_allclose(fd, fn * np.sqrt(1 - z ** 2), rtol=1e-5)
        assert all(len(r["frequency_hz"].replace(".", "").lstrip("0")) >= 12 for r in table)


def test_complete_rotor_basis_is_ok_and_matches_the_full_eigensolution():
    """Friswell 5.9.1: 42 DOF, count 30 asks for a basis of every lateral mode.  The old
    estimate (top third of the basis cut) called this 'inaccurate' (7e-2); the reduction is
    exact, so the status is ok and the eigenvalues equal the dense full solution."""
    model = build_rotor_model(load_scene(FRISWELL).rotor)
    for rpm in (0.0, 3000.0):
        red = rotor_modes(model, rpm, count=30)
        full = rotor_modes(model, rpm, count=30, method="full")
        assert red.status == "ok" and red.error_estimate == 0.0
        np.testing.assert_allclose(red.eigenvalues, full.eigenvalues, rtol=1e-8)


def test_overflowing_rotor_fails_instead_of_ok(tmp_path, capsys):
    """E = 1e300: the stiffness overflows, the eigenvalues are NaN; exit 1, status failed."""
    out = tmp_path / "o"
    code = main(["modes", FRISWELL, "--quiet", "--out", str(out),
                 "--set", "rotor.material.E=1e300", "--set", "rotor.material.G=4e299"])
    assert code == 1
    assert "non-finite eigenvalues" in capsys.readouterr().err
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and s["results"]["modes"]["status"] == "failed"


@pytest.mark.parametrize("sets, key", [
    (["--set", "housing.material.E=1e300"], "housing.material.E"),
    (["--set", 'housing.support="elastic"', "--set", "housing.foundation_stiffness=1e-6"],
     "housing.foundation_stiffness"),
])
def test_housing_numerical_failure_says_where_and_why(tmp_path, monkeypatch, capsys, sets, key):
    pytest.importorskip("dolfinx")
    monkeypatch.setenv("VIBROGEAR_CACHE_DIR", str(tmp_path / "cache"))
    out = tmp_path / "o"
    code = main(["modes", str(ROOT / "configs" / "housing_small.toml"), "--quiet",
                 "--out", str(out), *sets])
    err = capsys.readouterr().err
    assert code == 1 and "Traceback" not in err
    assert "housing FE modal solve failed" in err and key in err
    assert json.loads((out / "summary.json").read_text())["status"] == "failed"
    assert [p.name for p in (tmp_path / "cache").iterdir() if "modes" in p.name] == []
