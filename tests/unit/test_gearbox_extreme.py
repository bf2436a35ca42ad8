"""Extreme gearbox inputs (gear_pair scene): a stiff mesh (1e10 N/m), no backlash, no mesh
damping, speeds far above the range, ball bearings with a 1 mm clearance.  Each gives a
correct result or a clear failure status per point, never NaN/inf in an output file and
never a hang (small period counts, a max_steps cap on every integration)."""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.config import load_scene
from vibrogear.models.gearbox.model import build_gearbox
from vibrogear.solvers.static import static_equilibrium

ROOT = Path(__file__).resolve().parents[2]
GEAR_PAIR = str(ROOT / "configs" / "gear_pair.toml")

CI = ["scene.analyses=[\"modes\",\"time_response\",\"sweep\"]",
      "time_response.periods=10", "time_response.samples_per_period=16",
      "sweep.n_points=3", "sweep.rpm_min=5000", "sweep.rpm_max=6000",
      "sweep.transient_periods=10", "sweep.extra_transient_periods=10",
      "sweep.record_periods=4", "sweep.max_period=2", "integration.max_steps=200000"]

BALL_1MM = [f"gearbox.bearings.{b}.{k}" for b in range(4) for k in
            ("type=ball", "clearance=1e-3", "elements=8", "stiffness=8e9")]

CASES = {
    "stiff_mesh": ["gearbox.meshes.0.stiffness=1e10"],
    "no_backlash": ["gearbox.meshes.0.backlash=0.0"],
    "no_damping": ["gearbox.meshes.0.damping=0.0", "gearbox.couplings.0.damping=0.0",
                   "gearbox.couplings.1.damping=0.0"],
    "far_above_range": ["time_response.rpm=60000", "sweep.rpm_min=55000",
                        "sweep.rpm_max=60000"],
    "ball_clearance_1mm": BALL_1MM,
}


def _run(out, overrides):
    args = ["run", GEAR_PAIR, "--quiet", "--out", str(out)]
    for o in overrides:
        args += ["--set", o]
    return main(args)


def _assert_finite_outputs(out: Path):
    text = (out / "summary.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    for name in ("sweep.npz", "time_response.npz", "branch.npz"):
        if (out / name).exists():
            with np.load(out / name) as z:
                for k in z.files:
                    if z[k].dtype.kind in "fc":
                        assert np.all(np.isfinite(z[k])), (name, k)
    for name in ("sweep.csv", "time_response.csv", "modes.csv", "branch.csv"):
        if (out / name).exists():
            with open(out / name) as fh:
                for row in csv.reader(fh):
                    for cell in row:
                        try:
                            value = float(cell)
                        except ValueError:
                            continue
                        assert np.isfinite(value), (name, row)
    return json.loads(text)


def _mesh_delta_static(overrides, rpm=5800.0):
    gm = build_gearbox(load_scene(GEAR_PAIR, tuple(overrides)))
    st = static_equilibrium(gm.reduced, rpm)
    assert st.converged and np.all(np.isfinite(st.x)), st.message
    return gm, st, float(gm.reduced.contacts.directions[0] @ st.x)


@pytest.mark.parametrize("case", [c if c in ("stiff_mesh", "no_backlash") else
                                  pytest.param(c, marks=pytest.mark.system) for c in CASES])
def test_extreme_case_finite_result_or_clear_status(tmp_path, case):
    out = tmp_path / case
    code = _run(out, CI + CASES[case])
    summary = _assert_finite_outputs(out)
    assert code in (0, 1)
    assert (code == 0) == (summary["status"] == "ok")
    for name, res in summary["results"].items():
        assert res["status"] in ("ok", "partial", "failed"), name
        if res["status"] != "ok":
            assert res["message"], name                     # a failure says why
    sw = summary["results"].get("sweep")
    if sw is not None and sw["status"] != "failed":
        with np.load(out / "sweep.npz") as z:
            failed = z["status"] != 0
            assert sw["failed_points"] == int(failed.sum())
            assert np.all(z["ok"] == ~failed)
            assert all(str(m) for m in z["message"][failed])
    tr = summary["results"]["time_response"]
    if tr["status"] == "ok":
        lo, hi = tr["deformation_second_half"]["G1"]
        assert np.isfinite(lo) and np.isfinite(hi) and lo <= hi
    CHECKS[case](summary, out)


def _check_stiff_mesh(summary, out):
    """k = 1e10 N/m: the static deformation is F/k (~1e-7 m) and the dynamic one stays far
    below the 5 um transmission error that the stiff mesh imposes on the gears."""
    gm, st, delta = _mesh_delta_static(CASES["stiff_mesh"])
    assert 0 < delta < 1e-6
    _, _, delta_nominal = _mesh_delta_static([])
    assert delta < delta_nominal / 10
    lo, hi = summary["results"]["time_response"]["deformation_second_half"]["G1"]
    assert max(abs(lo), abs(hi)) < 2e-6
    assert summary["results"]["sweep"]["status"] == "ok"


def _check_no_backlash(summary, out):
    """Zero backlash: no dead zone, the mesh is always in contact on one flank or the
    other, so the linearised model has the mesh stiffness and the run is complete."""
    gm, st, delta = _mesh_delta_static(CASES["no_backlash"])
    assert delta > 0 and gm.contacts[0].gap_lo == 0.0
    assert summary["status"] == "ok"
    with np.load(out / "time_response.npz") as z:
        assert all(np.all(np.isfinite(z[k])) for k in z.files if z[k].dtype.kind == "f")


def _check_no_damping(summary, out):
    """No mesh and coupling damping: the modes keep the shafts' modal damping only (>= 0)."""
    with open(out / "modes.csv") as fh:
        rows = list(csv.DictReader(fh))
    zeta = np.array([float(r["damping_ratio"]) for r in rows])
    assert np.all(zeta > -1e-9) and np.all(zeta < 0.05)
    assert summary["results"]["time_response"]["status"] == "ok"


def _check_far_above_range(summary, out):
    """60000 rpm (40 kHz mesh frequency, far above every mode): quasi-static response, the
    gears cannot follow the transmission error, the mesh never separates."""
    _, _, delta = _mesh_delta_static(CASES["far_above_range"], 60000.0)
    tr = summary["results"]["time_response"]
    assert tr["status"] == "ok" and tr["excitation_frequency_hz"] == pytest.approx(40000.0)
    lo, hi = tr["deformation_second_half"]["G1"]
    assert 0 < lo < delta < hi < 3 * delta
    with np.load(out / "sweep.npz") as z:
        ok = z["status"] == 0
        assert ok.any() and np.all(z["qmin"][ok] > 0)


def _check_ball_clearance(summary, out):
    """1 mm bearing clearance: the shafts move through the clearance until the rolling
    elements on the loaded side carry the mesh force (no gravity in the model)."""
    gm, st, delta = _mesh_delta_static(BALL_1MM)
    assert delta > 0
    d = gm.reduced.contacts.directions @ st.x
    for group in {c.group for c in gm.contacts if c.kind == "bearing"}:
        idx = [j for j, c in enumerate(gm.contacts) if c.group == group]
        assert d[idx].max() > 1e-3                       # past the clearance: in contact
        assert d[idx].max() < 1.1e-3                     # by a Hertzian deflection only


CHECKS = {"stiff_mesh": _check_stiff_mesh, "no_backlash": _check_no_backlash,
          "no_damping": _check_no_damping, "far_above_range": _check_far_above_range,
          "ball_clearance_1mm": _check_ball_clearance}


def test_sweep_keeps_going_and_reports_failing_points(tmp_path):
    """A step cap that the low-speed points exceed (~1000 steps) and the high-speed points
    do not (~200): the sweep finishes, the failed points carry their status and message,
    the others their results; exit code 0 with the sweep marked 'partial'."""
    out = tmp_path / "capped"
    code = _run(out, CI + ["scene.analyses=[\"sweep\"]", "sweep.rpm_min=5000",
                           "sweep.rpm_max=60000", "sweep.extra_transient_periods=0",
                           "integration.max_steps=500"])
    summary = _assert_finite_outputs(out)
    assert code == 0
    sw = summary["results"]["sweep"]
    with np.load(out / "sweep.npz") as z:
        param, status, msg = z["param"], z["status"], z["message"]
        qmax = z["qmax"]
    failed = status != 0
    assert sw["status"] == "partial" and sw["points"] == 6
    assert sw["failed_points"] == int(failed.sum()) >= 1
    assert sw["message"].startswith(f"{int(failed.sum())} of 6 points failed")
    assert np.all(param[failed] < 10000)                 # only the slow points
    assert all("maximum number of steps" in str(m) for m in msg[failed])
    assert np.all(~failed[param > 30000])                # later points went on
    assert np.all(qmax[~failed] > 0)
    with open(out / "sweep.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert sum(int(r["status"]) != 0 for r in rows) == int(failed.sum())
