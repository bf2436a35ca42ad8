"""Gearbox scenes through the CLI with CI-sized settings: gear_pair with every analysis
(the files of docs/gearbox.md, finite values, never importing the FE stack) and
single_stage with a small housing (modes, time response, reduction accuracy against the
full model with all housing DOF)."""
from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main

ROOT = Path(__file__).resolve().parents[2]
GEAR_PAIR = str(ROOT / "configs" / "gear_pair.toml")
SINGLE_STAGE = str(ROOT / "configs" / "single_stage.toml")

GEAR_PAIR_CI = [
    'scene.analyses=["modes","time_response","sweep","continuation","reduction_accuracy"]',
    "time_response.periods=20", "time_response.samples_per_period=16",
    "sweep.n_points=4", "sweep.rpm_min=5000", "sweep.rpm_max=6500",
    "sweep.transient_periods=20", "sweep.extra_transient_periods=20",
    "sweep.record_periods=8", "sweep.max_period=4",
    "continuation.rpm_min=5500", "continuation.rpm_max=6500", "continuation.max_points=5",
    "continuation.transient_periods=20",
    "reduction_accuracy.rpm=5800", "reduction_accuracy.shaft_counts=[10,16]",
    "reduction_accuracy.housing_counts=[1,1]", "reduction_accuracy.transient_periods=5",
    "reduction_accuracy.record_periods=5",
    "integration.max_steps=500000",
]
FE_STACK = ("dolfinx", "gmsh", "petsc4py", "slepc4py", "mpi4py", "ufl", "basix")


def _read_csv(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


def _finite_csv(path):
    with open(path) as fh:
        for row in csv.reader(fh):
            for cell in row:
                try:
                    value = float(cell)
                except ValueError:
                    continue
                assert np.isfinite(value), (path.name, row)


def _finite_npz(path):
    with np.load(path) as z:
        for k in z.files:
            if z[k].dtype.kind in "fc":
                assert np.all(np.isfinite(z[k])), (path.name, k)
        return {k: z[k] for k in z.files}


@pytest.fixture(scope="module")
def gear_pair_run(tmp_path_factory):
    """One CLI run of gear_pair with every analysis, in a subprocess that reports the
    FE-stack modules it imported."""
    out = tmp_path_factory.mktemp("gear_pair") / "out"
    args = ["run", GEAR_PAIR, "--quiet", "--out", str(out)]
    for o in GEAR_PAIR_CI:
        args += ["--set", o]
    code = (
        "import json, sys\n"
        "from vibrogear.cli import main\n"
        f"rc = main({args!r})\n"
        f"print(json.dumps({{'rc': rc, 'fe': [m for m in {FE_STACK!r} if m in sys.modules]}}))\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=600, cwd=ROOT)
    assert r.returncode == 0, r.stderr[-3000:]
    return out, json.loads(r.stdout.strip().splitlines()[-1])


def test_gear_pair_runs_every_analysis_without_fe_stack(gear_pair_run):
    out, info = gear_pair_run
    assert info["rc"] == 0
    assert info["fe"] == []                               # rotor-only: no dolfinx, gmsh, ...
    text = (out / "summary.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    summary = json.loads(text)
    assert summary["status"] == "ok" and summary["model"] == "gearbox"
    assert set(summary["results"]) == {"modes", "time_response", "sweep", "continuation",
                                       "reduction_accuracy"}
    for name, res in summary["results"].items():
        assert res["status"] in ("ok", "partial"), (name, res.get("message"))
    for name in ("summary.json", "modes.csv", "resonance_map.png", "time_response.npz",
                 "time_response.csv", "time_response.png", "sweep.npz", "sweep.csv",
                 "bifurcation.png", "branch.npz", "branch.csv", "branch_max.png",
                 "branch_min.png", "reduction_levels.csv", "reduction_modes.csv",
                 "reduction_accuracy.png"):
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    for name in ("modes.csv", "time_response.csv", "sweep.csv", "branch.csv",
                 "reduction_levels.csv", "reduction_modes.csv"):
        _finite_csv(out / name)


def test_gear_pair_sweep_csv_names_rpm_and_units(gear_pair_run):
    """sweep.csv's header: the speed column is ``rpm`` (its values the npz's ``param``),
    the deformations in metres, the impact energies in joules."""
    out, _ = gear_pair_run
    rows = _read_csv(out / "sweep.csv")
    header = list(rows[0])
    assert "param" not in header and "rpm" in header
    assert {"qmin [m]", "qmax [m]", "impacts [1/period]", "rattle_G1 [J]",
            "impact_velocity_rms_G1 [m/s]"} <= set(header)
    with np.load(out / "sweep.npz") as z:
        assert [float(r["rpm"]) for r in rows] == z["param"].tolist()
        assert [float(r["qmin [m]"]) for r in rows] == z["qmin"].tolist()


def test_gear_pair_sweep_and_branch_files(gear_pair_run):
    out, _ = gear_pair_run
    sw = _finite_npz(out / "sweep.npz")
    for key in ("param", "direction", "qmin", "qmax", "poincare", "period_n", "impacts"):
        assert key in sw, key
    n = sw["param"].size
    assert n == 8                                          # 4 points up and down
    assert sorted(set(sw["direction"].tolist())) == ["down", "up"]
    assert np.all((sw["param"] >= 5000) & (sw["param"] <= 6500))
    assert sw["poincare"].shape == (n, 8)
    ok = sw["status"] == 0
    assert ok.all()
    assert np.all(sw["qmin"][ok] <= sw["poincare"][ok].min(axis=1) + 1e-12)
    assert np.all(sw["qmax"][ok] >= sw["poincare"][ok].max(axis=1) - 1e-12)
    assert np.all(np.abs(sw["qmax"]) < 1e-3)              # mesh deformations in metres
    assert np.all((sw["period_n"] >= 0) & (sw["period_n"] <= 4)) and np.all(sw["impacts"] >= 0)
    br = _finite_npz(out / "branch.npz")
    summary = json.loads((out / "summary.json").read_text())
    cont = summary["results"]["continuation"]
    assert br["param"].size >= 2 and br["param"][0] == pytest.approx(6500.0)   # start = max
    assert br["branch"][0] == 0 and np.all(np.diff(br["branch"]) >= 0)
    assert len(cont["branches"]) == br["branch"].max() + 1
    for b, info in enumerate(cont["branches"]):
        p = br["param"][br["branch"] == b]
        assert p.size == info["points"] <= 5 + 1                   # max_points (+ a located LP/PD)
        assert np.all(br["n_periods"][br["branch"] == b] == info["n_periods"])
        # inside the range, but for the step that left it and ended the branch
        inside = (p >= 5500 - 1e-9) & (p <= 6500 + 1e-9)
        assert np.all(inside[:-1])
        assert inside[-1] or info["message"] == "left the parameter range"
    assert np.all(br["qmin"] <= br["qmax"]) and np.all(br["period"] > 0)
    assert cont["error_estimate"]["max_periodicity_residual"] <= 10 * cont["error_estimate"][
        "shooting_tol"]


def test_gear_pair_modes_and_time_response(gear_pair_run):
    out, _ = gear_pair_run
    summary = json.loads((out / "summary.json").read_text())["results"]
    rows = _read_csv(out / "modes.csv")
    f = np.array([float(r["frequency_hz"]) for r in rows])
    assert len(rows) == summary["modes"]["modes"] and np.all(np.diff(f) >= 0) and f[0] > 0
    assert {r["dominant"] for r in rows} <= {"driving", "driven"}
    share = np.array([float(r["mesh_energy_G1"]) for r in rows])
    assert np.all((share >= 0) & (share <= 1 + 1e-9)) and share.max() > 0.05
    tr = summary["time_response"]
    lo, hi = tr["deformation_second_half"]["G1"]
    assert np.isfinite(lo) and np.isfinite(hi) and -1e-3 < lo < hi < 1e-3
    assert hi > 0                                          # the loaded mesh is in contact
    assert tr["excitation_frequency_hz"] == pytest.approx(40 * 5800 / 60)
    z = _finite_npz(out / "time_response.npz")
    assert any(np.asarray(v).ndim >= 1 and np.asarray(v).size > 20 * 16 for v in z.values())
    ra = summary["reduction_accuracy"]
    assert ra["full_model"]["dofs"] == 180                 # two 90-DOF shafts, no housing
    # 16 of the 90 modes per shaft: every mode below 5 kHz from above, within 2 %, paired
    # one-to-one; MAC > 0.9 where the full model's neighbours are > 1 % away (the nearly
    # degenerate lateral pairs mix within their plane)
    assert 0 < ra["error_estimate"]["max_freq_error_largest_level"] < 0.02
    rows = _read_csv(out / "reduction_modes.csv")
    assert len(rows) == ra["full_model"]["modes_below_f_max"] >= 10
    f_full = np.array([float(r["f_full_hz"]) for r in rows])
    f_red = np.array([float(r["f_reduced_hz"]) for r in rows])
    mac = np.array([float(r["mac"]) for r in rows])
    assert np.unique(f_red).size == f_red.size
    assert np.all(f_red > f_full) and np.all(f_red < 1.02 * f_full)
    gap = np.minimum(np.r_[np.inf, np.diff(f_full)], np.r_[np.diff(f_full), np.inf]) / f_full
    assert np.sum(gap > 0.01) >= 8 and np.all(mac[gap > 0.01] > 0.9)


@pytest.mark.system
def test_single_stage_small_housing_reduction_accuracy(tmp_path):
    """single_stage at a small reduction level (8 shaft modes, 10 housing modes; levels
    8/5 and 12/10): modes, time response and the reduced-vs-full comparison below 5 kHz.
    Cold (housing mesh, modes and full matrices computed): ~20 s; cached afterwards."""
    out = tmp_path / "ss"
    args = ["run", SINGLE_STAGE, "--quiet", "--out", str(out),
            "--set", 'scene.analyses=["modes","time_response","reduction_accuracy"]',
            "--set", "gearbox.shafts.0.master_count=8", "--set", "gearbox.shafts.1.master_count=8",
            "--set", "housing.modes.count=10", "--set", "time_response.periods=10",
            "--set", "reduction_accuracy.shaft_counts=[8,12]",
            "--set", "reduction_accuracy.housing_counts=[5,10]",
            "--set", "reduction_accuracy.transient_periods=5",
            "--set", "reduction_accuracy.record_periods=5"]
    assert main(args) == 0
    text = (out / "summary.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    res = json.loads(text)["results"]
    assert {k: v["status"] for k, v in res.items()} == {
        "modes": "ok", "time_response": "ok", "reduction_accuracy": "ok"}
    m = res["modes"]["modes"]
    assert m == 8 + 8 + 10
    lo, hi = res["time_response"]["deformation_second_half"]["G1"]
    assert np.isfinite(lo) and np.isfinite(hi) and hi > 0
    ra = res["reduction_accuracy"]
    assert ra["full_model"]["dofs"] > 10_000                # shafts + every housing DOF
    n_ref = ra["full_model"]["modes_below_f_max"]
    assert n_ref >= 10
    small, large = ra["levels"]
    assert (small["m"], large["m"]) == (8 + 8 + 5, 12 + 12 + 10)
    assert large["modes_compared"] == n_ref
    # largest level: every full-model mode below 5 kHz found within a few % and MAC > 0.9
    assert large["max_freq_error"] < 0.04 and large["min_mac"] > 0.9
    assert large["max_freq_error"] < small["max_freq_error"]
    # the reference response: pointwise where periodic, else by its statistics only
    assert large["statistics_error"] == 0.0
    assert small["judged_by"] == large["judged_by"]
    if large["judged_by"] == "pointwise":
        assert large["response_error"] == 0.0 and np.isfinite(small["response_error"])
    else:
        assert small["response_error"] is None             # no pointwise error on chaos
    assert np.isfinite(small["statistics_error"]) and small["statistics_error"] > 0
    rows = _read_csv(out / "reduction_modes.csv")
    assert len(rows) == n_ref
    f_full = np.array([float(r["f_full_hz"]) for r in rows])
    err = np.array([float(r["rel_error"]) for r in rows])
    mac = np.array([float(r["mac"]) for r in rows])
    assert np.all(f_full <= ra["f_max_hz"]) and np.all(np.diff(f_full) > 0)
    assert np.all(err > -1e-6)                              # Ritz: from above
    assert np.all(np.abs(err) < 0.04) and np.all(mac > 0.9)
    # the lowest, well-separated modes: within 2 % and MAC > 0.98
    assert np.all(np.abs(err[:3]) < 0.02) and np.all(mac[:3] > 0.98)
    _finite_csv(out / "reduction_modes.csv")
    _finite_csv(out / "reduction_levels.csv")
