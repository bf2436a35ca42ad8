"""Extreme and degenerate ``vibrogear runup`` input (issue 24, item 6): each case gives exit 2
naming the field with nothing written, or runs to an explicit outcome: finite envelopes,
order tracks and counts, or exit 1 with the reason; never a traceback or a run that cannot
end (a run-up too long for memory is refused before it starts).

gear_pair, 5000 -> 5002 rpm at 100 rpm/s (0.02 s, 66 mesh periods), one direction, 10
settling periods: ~0.5 s a run."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cli_cases import cases, cli_args, read_outputs

from vibrogear.cli import main
from vibrogear.config.scene import read_toml
from vibrogear.report.writers.optimize import toml_text

GEAR_PAIR = str(Path(__file__).resolve().parents[2] / "configs" / "gear_pair.toml")

SHORT = ["runup.rpm_start=5000", "runup.rpm_end=5002", "runup.rate=100",
         "runup.settle_periods=10", "runup.window_revs=1", 'runup.directions=["up"]']


@pytest.fixture(scope="module")
def table_scene(tmp_path_factory) -> str:
    """gear_pair with [runup] given as a table (the ramp's keys left out)."""
    data = read_toml(GEAR_PAIR)
    data["runup"] = {"table": [[0.0, 5000.0], [0.02, 5002.0]], "settle_periods": 10,
                     "window_revs": 1, "directions": ["up"]}
    p = tmp_path_factory.mktemp("scene") / "table.toml"
    p.write_text(toml_text(data))
    return str(p)


_args = cli_args


# ------------------------------------------------------------------ rejected input (exit 2)

#: (id, overrides, field, the table scene, found by `vibrogear check` (else once the model
#: is built, still before anything is written)); the run's length is decided from the config
#: (RunupConfig.check_gearbox), so `vibrogear check` finds every case
BAD = [
    ("rate-0", ["runup.rate=0"], "runup.rate", False, True),
    ("rate-negative", ["runup.rate=-5"], "runup.rate", False, True),
    ("range-of-one-point", ["runup.rpm_end=5000"], "runup.rpm_end", False, True),
    ("rpm-0", ["runup.rpm_start=0"], "runup.rpm_start", False, True),
    ("chunks-0", ["runup.chunks_per_period=0"], "runup.chunks_per_period", False, True),
    ("samples-not-a-multiple", ["runup.samples_per_period=30"], "runup.samples_per_period",
     False, True),
    ("no-direction", ["runup.directions=[]"], "runup.directions", False, True),
    # regression: accepted; both runs computed (16 s), one overwrote the other in the files
    ("direction-twice", ['runup.directions=["up","up"]'], "runup.directions[1]", False, True),
    ("order-0", ["runup.mesh_orders=[0]"], "runup.mesh_orders[0]", False, True),
    # regression: orders at or above the samples' Nyquist limit were tracked as their aliases
    ("order-at-nyquist", ["runup.mesh_orders=[1,32]"], "runup.mesh_orders[1]", False, True),
    ("window-0", ["runup.window_revs=0"], "runup.window_revs", False, True),
    ("segment-0-s", ["runup.spectrogram_s=0"], "runup.spectrogram_s", False, True),
    ("rtol-0", ["runup.rtol=0"], "runup.rtol", False, True),
    ("rtol-1", ["runup.rtol=1"], "runup.rtol", False, True),
    ("inertia-sometimes", ['runup.inertia_torque="sometimes"'], "runup.inertia_torque",
     False, True),
    ("settle-negative", ["runup.settle_periods=-1"], "runup.settle_periods", False, True),
    ("table-and-ramp", ["runup.rate=100"], "runup.table", True, True),
    ("table-times-not-increasing", ["runup.table=[[0,5000],[0,5001]]"], "runup.table[1][0]",
     True, True),
    ("table-rpm-0", ["runup.table=[[0,5000],[1,0]]"], "runup.table[1][1]", True, True),
    ("table-late-start", ["runup.table=[[0.5,5000],[1,5001]]"], "runup.table[0][0]", True,
     True),
    # regression: a run shorter than one mesh period was a ValueError traceback (a spline
    # through fewer than two samples)
    ("shorter-than-a-mesh-period", ["runup.rpm_end=5100", "runup.rate=1e9"], "runup.rate",
     False, True),
    ("table-of-0.1-us", ["runup.table=[[0,5000],[1e-7,5001]]"], "runup.table", True, True),
    ("1-to-2-rpm-in-10-ms", ["runup.rpm_start=1", "runup.rpm_end=2", "runup.rate=100"],
     "runup.rate", False, True),
    # regression: a run-up of 1e7 s (3e10 mesh periods) started and could not end
    ("rate-1e-6-rpm-per-s", ["runup.rpm_end=5010", "runup.rate=1e-6"], "runup.rate", False,
     True),
    ("table-of-1e9-s", ["runup.table=[[0,5000],[1e9,5001]]"], "runup.table", True, True),
]


@pytest.mark.parametrize("overrides, field, table, by_check", [c[1:] for c in BAD],
                         ids=[c[0] for c in BAD])
def test_degenerate_input_exits_2_naming_the_field(tmp_path, capsys, table_scene, overrides,
                                                   field, table, by_check):
    scene = table_scene if table else GEAR_PAIR
    if not table and not any(o.startswith("runup.rpm_start") for o in overrides):
        overrides = ["runup.rpm_start=5000", *overrides]
    out = tmp_path / "out"
    with_runup = ['scene.analyses=["runup"]', *overrides]
    assert main(_args("check", scene, out, with_runup)) == (2 if by_check else 0)
    if by_check:
        assert f"invalid input: {field}" in capsys.readouterr().err
    assert main(_args("runup", scene, out, overrides)) == 2
    err = capsys.readouterr().err
    assert f"invalid input: {field}" in err, err
    assert not out.exists()


LENGTH = [
    ("shorter-than-a-mesh-period", ["runup.rpm_end=5100", "runup.rate=1e9"], "runup.rate",
     "the run lasts 1e-07 s: 0.000337 mesh periods, less than the one whole mesh period"),
    ("rate-1e-6-rpm-per-s", ["runup.rpm_end=5010", "runup.rate=1e-6"], "runup.rate",
     "the run lasts 1e+07 s: 3.337e+10 mesh periods x 64 samples x 1 meshes x 2 runs need "
     "1.91e+05 GiB; at most 16 GiB"),
]


@pytest.mark.parametrize("overrides, field, message", [c[1:] for c in LENGTH],
                         ids=[c[0] for c in LENGTH])
def test_check_reports_the_run_length_from_the_config(tmp_path, capsys, monkeypatch, overrides,
                                                      field, message):
    """The run's length is decided from [gearbox] and [runup] alone: `vibrogear check` (with
    runup among the analyses) and the `vibrogear runup` verb (which runs it unlisted) exit 2
    with the numbers, before any model is built."""
    import vibrogear.analyses.study as study

    def no_build(*_a, **_k):
        raise AssertionError("the model was built")
    monkeypatch.setattr(study, "build_study", no_build)
    out = tmp_path / "out"
    overrides = ["runup.rpm_start=5000", *overrides]
    assert main(_args("check", GEAR_PAIR, out, ['scene.analyses=["runup"]', *overrides])) == 2
    err = capsys.readouterr().err
    assert f"invalid input: {field}" in err and message in err, err
    # gear_pair does not list runup: check leaves [runup] alone, the verb checks it
    assert main(_args("check", GEAR_PAIR, out, overrides)) == 0
    capsys.readouterr()
    assert main(_args("runup", GEAR_PAIR, out, overrides)) == 2
    err = capsys.readouterr().err
    assert f"invalid input: {field}" in err and message in err, err
    assert not out.exists()


def test_mesh_periods_from_the_config_match_the_model():
    """RunupConfig.mesh_periods (rpm / 60 x teeth x |speed ratio| of meshes[0].gear_a)
    equals the count of the model's excitation phase (omega_per_param = teeth RPM /
    OMEGA_REF per rpm, in model time units of 1 / OMEGA_REF s) for gear_pair's short run:
    66.68 periods, of which the run reports 66 whole ones (test below)."""
    from vibrogear.config.scene import scene_from_dict
    from vibrogear.models.gearbox.model import OMEGA_REF, RPM

    data = read_toml(GEAR_PAIR)
    data["runup"].update(rpm_start=5000.0, rpm_end=5002.0, rate=100.0)
    scene = scene_from_dict(data)
    teeth = 40
    model = np.trapz([5000.0, 5002.0], [0.0, 0.02 * OMEGA_REF]) * teeth * RPM / OMEGA_REF \
        / (2 * np.pi)
    assert scene.runup.mesh_periods(scene.gearbox) == pytest.approx(model, rel=1e-12)
    assert scene.runup.check_gearbox(scene.gearbox) == pytest.approx(66.68, rel=1e-12)


# ------------------------------------------------------------------ extreme but valid input

def _check_runs(s, z, rows, lo=5000.0, hi=5002.0):
    """Per run: the mesh periods of the profile, speeds inside it, envelope min <= max."""
    assert s["status"] == "ok"
    assert len(rows) == sum(r["mesh_periods"] for r in s["runs"].values())
    for key, r in s["runs"].items():
        rpm = z[f"{key}_rpm"]
        assert rpm.size == r["mesh_periods"] >= 1
        assert np.all((rpm >= lo) & (rpm <= hi))
        assert np.all(z[f"{key}_env_min_G1"] <= z[f"{key}_env_max_G1"])
        assert np.all(z[f"{key}_losses_G1"] >= 0)
        assert r["steps"] > 0 and r["error_estimate"]["accumulated_local_error"] >= 0


def _periods(n):
    def check(s, z, rows):
        assert [r["mesh_periods"] for r in s["runs"].values()] == [n] * len(s["runs"])
    return check


def _envelope(lo, hi):
    """Bounds of the G1 deformation envelope [um] over the run."""
    def check(s, z, rows):
        assert z["up_env_min_G1"].min() >= lo and z["up_env_max_G1"].max() <= hi
    return check


def _tolerance(rtol):
    def check(s, z, rows):
        assert s["rtol"] <= rtol and s["atol"] == pytest.approx(1e-6 * s["rtol"])
    return check


def _no_windows(s, z, rows):
    """Windows of 10000 revolutions and a 100 s segment: longer than the 0.02 s run; the
    order tracks are empty, the envelopes are there."""
    assert z["up_track_rpm"].size == 0 and z["up_order_G1_G1_1x"].size == 0
    assert z["up_rpm"].size == 66


def _both(s, z, rows):
    assert set(s["runs"]) == {"down", "down_no_inertia"}
    assert set(s["inertia_effect"]) >= {"down", "mesh", "unit"}
    assert np.all(np.diff(z["down_rpm"]) < 0)


def _coarse_chunks(s, z, rows):
    r = s["runs"]["up"]
    assert r["error_estimate"]["chunks_per_period"] == 1 and not r["error_estimate"]["midpoint"]


VALID = [
    ("one-mesh-period", ["runup.rpm_end=5001", "runup.rate=3300", "runup.settle_periods=0",
                         'runup.directions=["up","down"]'], _periods(1), 5001.0),
    ("zero-load", ["gearbox.couplings[0].twist=0", "gearbox.couplings[1].twist=0"],
     _envelope(-110.0, 20.0), None),
    ("zero-backlash", ["gearbox.meshes[0].backlash=0"], None, None),
    ("stiff-mesh", ["gearbox.meshes[0].stiffness=1e10"], _envelope(-110.0, 1.0), None),
    ("soft-mesh", ["gearbox.meshes[0].stiffness=1e3"], _envelope(100.0, 1e5), None),
    ("no-damping", ["gearbox.meshes[0].damping=0", "gearbox.couplings[0].damping=0",
                    "gearbox.couplings[1].damping=0"], None, None),
    ("rtol-0.5", ["runup.rtol=0.5"], _tolerance(0.5), None),
    ("constant-speed-table", "table", _periods(66), 5002.0),
    ("one-chunk-8-samples-start-speed", ["runup.chunks_per_period=1",
                                         "runup.samples_per_period=8", "runup.midpoint=false",
                                         "runup.settle_periods=0"], _coarse_chunks, None),
    ("windows-longer-than-the-run", ["runup.window_revs=10000", "runup.spectrogram_s=100"],
     _no_windows, None),
    ("run-down-with-and-without-inertia", ['runup.inertia_torque="both"',
                                           'runup.directions=["down"]'], _both, None),
    ("order-just-below-nyquist", ["runup.mesh_orders=[31]"], None, None),
    pytest.param("huge-mesh-damping", ["gearbox.meshes[0].damping=1e7"], None, None,
                 marks=pytest.mark.slow, id="huge-mesh-damping"),           # ~4 s
    pytest.param("rtol-1e-13", ["runup.rtol=1e-13"], _tolerance(1e-13), None,
                 marks=pytest.mark.slow, id="rtol-1e-13"),                  # ~3 s
]


_cases = cases


@pytest.mark.parametrize("overrides, check, hi", _cases(VALID, ci=(
    "zero-load", "stiff-mesh", "rtol-0.5")))       # the rest: make test-system
def test_extreme_input_gives_finite_runs(tmp_path, table_scene, overrides, check, hi):
    out = tmp_path / "out"
    if overrides == "table":            # a constant speed: the table's two equal speeds
        args = _args("runup", table_scene, out, ["runup.table=[[0,5002],[0.02,5002]]",
                                                 "runup.settle_periods=0"])
        lo = 5002.0
    else:
        args = _args("runup", GEAR_PAIR, out, SHORT + overrides)
        lo = 5000.0
    assert main(args) == 0
    s, z, rows = read_outputs(out, "runup", text_columns=("direction", "inertia_torque"))
    _check_runs(s, z, rows, lo=lo, hi=hi or 5002.0)
    if check is not None:
        check(s, z, rows)


def test_step_budget_exits_1_with_the_reason(tmp_path, capsys):
    """max_steps 100: the settling integration runs out of steps: exit 1 naming where, no
    run-up files."""
    out = tmp_path / "out"
    assert main(_args("runup", GEAR_PAIR, out, SHORT + ["integration.max_steps=100"])) == 1
    err = capsys.readouterr().err
    assert "runup up: settling at the start speed: maximum number of steps" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["results"]["runup"]["status"] == "failed"
    assert not (out / "runup.npz").exists() and not (out / "runup.csv").exists()
