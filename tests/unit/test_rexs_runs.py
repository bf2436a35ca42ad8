"""The FVA REXS model runs as imported, with no hand edit: ``vibrogear modes`` and a short
``vibrogear sweep`` straight from the ``.rexs`` file."""
import csv
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main

XML = Path(__file__).resolve().parents[1] / "data" / "rexs" / "FVA-Industriegetriebe_2stufig_1-4.rexs"


def test_modes_from_rexs(tmp_path):
    """Every bearing and both torsional couplings hold the shafts: no rigid-body mode (all
    frequencies above 10 Hz), and both stages carry mesh strain energy in some mode."""
    out = tmp_path / "modes"
    assert main(["modes", str(XML), "--out", str(out), "--quiet"]) == 0
    rows = list(csv.DictReader(open(out / "modes.csv")))
    f = np.array([float(r["frequency_hz"]) for r in rows])
    assert len(f) >= 20 and f.min() > 10.0
    for stage in ("stage19", "stage20"):
        assert max(float(r[f"mesh_energy_{stage}"]) for r in rows) > 0.2


@pytest.mark.slow
def test_short_sweep_from_rexs(tmp_path):
    """Three speeds up over the load cases' driving-speed range (543 .. 3456 rpm)."""
    out = tmp_path / "sweep"
    sets = ["sweep.n_points=3", "sweep.transient_periods=20", "sweep.record_periods=8",
            "sweep.extra_transient_periods=0", 'sweep.directions=["up"]', "sweep.workers=1"]
    argv = ["sweep", str(XML), "--out", str(out), "--quiet"]
    for s in sets:
        argv += ["--set", s]
    assert main(argv) == 0
    data = np.load(out / "sweep.npz")
    assert data["param"].tolist() == pytest.approx([543.0, 1999.5, 3456.0])
    assert np.all(data["qmax"] > data["qmin"])


@pytest.mark.slow
def test_modes_with_the_generated_box_housing(tmp_path):
    """``import --housing box`` (an inner wall at the output shaft's 33014) then ``modes`` with
    the housing, no hand edit: the housing's 20 master modes join the shafts' 60 (measured
    under load: ~25 s cold, most of it the housing's mesh and eigen-solve), every bearing
    holds, and the flexible casing softens the supports.  The rigid-casing import is the same
    model with the housing's coordinates held at zero, and a constraint can only raise the
    eigenvalues of the undamped, non-rotating system (min-max); here the bearings are
    linearised at each model's own static state and gyroscopic terms enter at 1234 rpm, so
    this is checked on the first five modes, measured: 96.23 -> 96.19, 376.4 -> 351.0,
    437.0 -> 385.2, 563.1 -> 512.5, 710.4 -> 699.9 Hz."""
    scene = tmp_path / "box.toml"
    assert main(["import", str(XML), "--housing", "box", "-o", str(scene)]) == 0
    rigid, box = tmp_path / "rigid", tmp_path / "box"
    assert main(["modes", str(XML), "--out", str(rigid), "--quiet"]) == 0
    assert main(["modes", str(scene), "--out", str(box), "--quiet"]) == 0
    f_r = np.array([float(r["frequency_hz"]) for r in csv.DictReader(open(rigid / "modes.csv"))])
    f_b = np.array([float(r["frequency_hz"]) for r in csv.DictReader(open(box / "modes.csv"))])
    assert len(f_b) >= len(f_r) + 20 and f_b.min() > 10.0
    assert np.all(f_b[:5] <= f_r[:5])
