"""Extreme and degenerate ``vibrogear map`` input (issue 24, item 6): each case gives exit 2
naming the field with nothing written, or runs to an explicit outcome per point: status 0
with finite values, or a non-zero status with its message (its metrics blank in map.csv,
``ok`` False in map.npz); the map "ok" or "partial", or exit 1 when every point failed.
Never a NaN written as a number beside status 0 (map.npz stores missing values as 0).

gear_pair, two speeds x one load, one direction, 20 transient periods: ~0.5 s a map."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from cli_cases import cases, cli_args, read_outputs

from vibrogear.analyses.map import map as operating_map
from vibrogear.analyses.study import build_study
from vibrogear.cli import main
from vibrogear.config import load_scene
from vibrogear.pipeline.outcome import RunContext

GEAR_PAIR = str(Path(__file__).resolve().parents[2] / "configs" / "gear_pair.toml")

SMALL = ["map.n_speeds=2", "map.n_loads=1", "map.torque_min=91", "map.torque_max=91",
         "map.curves=false", "map.transient_periods=20", "map.extra_transient_periods=0",
         "map.record_periods=4", "map.max_period=2", "map.workers=1", 'map.directions=["up"]',
         "map.force_periods=1", "map.force_samples=16", "map.lyapunov=false"]
#: the per-point values map.csv and map.npz write
WRITTEN = ("qmin", "qmax", "impacts_drive_G1", "impacts_back_G1", "rattle_G1",
           "contact_fraction_G1", "max_force_G1")


def _args(verb, out, overrides):
    return cli_args(verb, GEAR_PAIR, out, overrides)


# ------------------------------------------------------------------ rejected input (exit 2)

BAD = [
    ("speed-range-of-one-point", ["map.rpm_max=4500"], "map.rpm_max"),
    ("speed-range-reversed", ["map.rpm_max=4000"], "map.rpm_max"),
    ("one-speed", ["map.n_speeds=1"], "map.n_speeds"),
    ("no-load", ["map.n_loads=0"], "map.n_loads"),
    ("one-load-two-torques", ["map.n_loads=1"], "map.n_loads"),
    ("torque-range-reversed", ["map.torque_min=80", "map.torque_max=40"], "map.torque_max"),
    ("torque-range-of-one-point", ["map.torque_min=40", "map.torque_max=40"], "map.torque_max"),
    ("negative-torque", ["map.torque_min=-1"], "map.torque_min"),
    ("nan-torque", ["map.torque_max=nan"], "map.torque_max"),
    ("torque-and-twist", ["map.twist_min=0.01", "map.twist_max=0.02"], "map.twist_min"),
    ("force-periods-0", ["map.force_periods=0"], "map.force_periods"),
    ("force-samples-4", ["map.force_samples=4"], "map.force_samples"),
    ("curve-ds-above-max", ["map.curve_ds=100"], "map.curve_ds_max"),
    ("rtol-0", ["map.rtol=0"], "map.rtol"),
    ("rtol-1", ["map.rtol=1"], "map.rtol"),
    ("max-period-above-record", ["map.max_period=64"], "map.max_period"),
    ("direction-twice", ['map.directions=["up","up"]'], "map.directions"),
    ("workers-0", ["map.workers=0"], "map.workers"),
    ("segments-0", ["map.segments=0"], "map.segments"),
    ("period-tol-1", ["map.period_tol=1"], "map.period_tol"),
    ("curve-margin-0", ["map.curve_margin=0"], "map.curve_margin"),
    ("unloaded-motor-coupling", ["gearbox.couplings[0].twist=0"], "gearbox.couplings[0].twist"),
]


@pytest.mark.parametrize("overrides, field", [c[1:] for c in BAD], ids=[c[0] for c in BAD])
def test_degenerate_input_exits_2_naming_the_field(tmp_path, capsys, overrides, field):
    out = tmp_path / "out"
    with_map = ['scene.analyses=["map"]', *overrides]
    assert main(_args("check", out, with_map)) == 2
    assert f"invalid input: {field}" in capsys.readouterr().err
    assert main(_args("map", out, overrides)) == 2
    err = capsys.readouterr().err
    assert f"invalid input: {field}" in err, err
    assert not out.exists()


# ------------------------------------------------------------------ extreme but valid input

def _check_files(s, z, rows):
    """Statuses agree between summary, npz and csv; an ok row has every value finite, a
    failed one its metrics blank; npz has no NaN."""
    for k, v in z.items():
        if v.dtype.kind == "f":
            assert np.all(np.isfinite(v)), k
    status = z["status"].ravel()
    assert np.array_equal(z["ok"].ravel(), status == 0)
    assert s["failed_points"] == int(np.sum(status != 0)) == sum(r["status"] != "0"
                                                                 for r in rows)
    assert s["status"] == ("ok" if s["failed_points"] == 0 else "partial")
    for r in rows:
        metrics = [r[k] for k in r if k.endswith("_G1")]
        if r["status"] == "0":
            assert r["motion_class"] != "failed"
            for k in ("qmin_m", "qmax_m", *(k for k in r if k.endswith("_G1"))):
                assert math.isfinite(float(r[k])), (k, r)
            assert float(r["qmin_m"]) <= float(r["qmax_m"])
        else:
            assert all(v == "" for v in metrics), r


def _deformation(lo, hi):
    """Bounds of the monitored mesh deformation [m] at every point."""
    def check(s, z, rows):
        assert np.all(z["qmin"] >= lo) and np.all(z["qmax"] <= hi)
    return check


def _no_load(s, z, rows):
    """Zero torque: the loads in both units are 0; the transmission error alone moves the
    gears, within the 0.1 mm backlash and a few um of tooth deformation."""
    assert s["loads"]["torque_N_m"] == pytest.approx([0.0], abs=1e-9)
    assert s["loads"]["twist_rad"] == pytest.approx([0.0], abs=1e-12)
    assert np.all(z["qmin"] > -1e-4 - 1e-5) and np.all(z["qmax"] < 1e-5)


def _from_zero(s, z, rows):
    """torque_min = 0 up to torque_max (SMALL: 91 N m)."""
    assert s["loads"]["torque_N_m"] == pytest.approx([0.0, 91.0], abs=1e-9)


def _stiff(s, z, rows):
    """k = 1e10 N/m (29 x the nominal 3.5e8): the drive-flank deformation F/k ~ 1e-7 m plus
    the dynamic part stays below half the nominal mesh's ~1.4e-5 m (5.07e-6 m measured
    with numba 0.6x; the earlier 5 um bound had no margin); where the stiff mesh separates
    it rattles inside the 0.1 mm backlash."""
    assert np.all(z["qmin"] > -1e-4 - 1e-5) and np.all(np.abs(z["qmax"]) < 0.5 * 1.4e-5)


def _twists(s, z, rows):
    assert s["loads"]["given_as"] == "twist" and s["loads"]["twist_rad"] == [0.0, 10.0]
    # the carried torque, linear in the twist on gear_pair: 400 x the nominal 90.98 N m
    T1 = s["loads"]["nominal_torque_N_m"]
    assert s["loads"]["torque_N_m"] == pytest.approx([0.0, 400.0 * T1], abs=1e-9)


def _tolerance(rtol):
    """The rtol asked for, or a tighter one the model needs, said in the notes."""
    def check(s, z, rows):
        used = s["error_estimate"]["rtol"]
        assert used == rtol or (used < rtol and any("rtol" in n for n in s["notes"]))
        assert s["error_estimate"]["atol"] == pytest.approx(1e-6 * used)
    return check


VALID = [
    ("zero-load", ["map.torque_min=0", "map.torque_max=0"], _no_load),
    ("loads-from-zero", ["map.torque_min=0", "map.n_loads=2"], _from_zero),
    # 1e9 N m on a linear mesh spring: a deformation of ~1e2 m, absurd but finite
    ("torque-1e9", ["map.torque_min=1e9", "map.torque_max=1e9"], _deformation(1.0, 1e4)),
    ("twist-0-to-10-rad", ["map.twist_min=0", "map.twist_max=10", "map.n_loads=2"],
     _twists),
    ("zero-backlash", ["gearbox.meshes[0].backlash=0"], None),
    ("stiff-mesh", ["gearbox.meshes[0].stiffness=1e10"], _stiff),
    ("soft-mesh", ["gearbox.meshes[0].stiffness=1"], None),
    ("no-damping", ["gearbox.meshes[0].damping=0", "gearbox.couplings[0].damping=0",
                    "gearbox.couplings[1].damping=0"], None),
    pytest.param("huge-mesh-damping", ["gearbox.meshes[0].damping=1e7"], None,
                 marks=pytest.mark.slow),                                      # ~8 s
    pytest.param("rtol-1e-13", ["map.rtol=1e-13"], _tolerance(1e-13),
                 marks=pytest.mark.slow),                                      # ~5 s
    ("rtol-0.5", ["map.rtol=0.5"], _tolerance(0.5)),
    ("no-transient-one-record", ["map.transient_periods=0", "map.record_periods=1",
                                 "map.max_period=1"], None),
    ("1e5-to-1e6-rpm", ["map.rpm_min=1e5", "map.rpm_max=1e6"], None),
    ("curves-tiny-windows", ["map.curves=true", "map.curve_max_points=3",
                             "map.curve_transient_periods=0"], None),
]


_cases = cases


@pytest.mark.parametrize("overrides, check", _cases(VALID, ci=(
    "zero-load", "twist-0-to-10-rad", "stiff-mesh", "rtol-0.5")))   # the rest: make test-system
def test_extreme_input_gives_a_status_per_point(tmp_path, overrides, check):
    out = tmp_path / "out"
    args = _args("map", out, SMALL + overrides)
    if any(o.startswith("map.twist_") for o in overrides):      # the load as twists
        args = _args("map", out, [o for o in SMALL + overrides if "torque" not in o])
        args[1] = _twist_scene(tmp_path)
    assert main(args) == 0
    s, z, rows = read_outputs(out, "map")
    _check_files(s, z, rows)
    if check is not None:
        check(s, z, rows)


def _twist_scene(tmp_path) -> str:
    """gear_pair with its [map] load range removed (given as twists by the case)."""
    text = Path(GEAR_PAIR).read_text()
    assert "torque_min = 55.0\n" in text and "torque_max = 110.0\n" in text
    text = text.replace("torque_min = 55.0\n", "").replace("torque_max = 110.0\n", "")
    p = tmp_path / "twist.toml"
    p.write_text(text)
    return str(p)


def test_partial_map_failed_point_carries_status_and_message(tmp_path):
    """A step budget that the 100 rpm point exceeds (its 20 transient periods are long) and
    the 7000 rpm point does not: the map is 'partial', the failed point says why."""
    out = tmp_path / "out"
    assert main(_args("map", out, SMALL + ["map.rpm_min=100",
                                           "integration.max_steps=3000"])) == 0
    s, z, rows = read_outputs(out, "map")
    assert s["status"] == "partial" and s["failed_points"] == 1
    assert s["message"] == "1 of 2 points failed"
    _check_files(s, z, rows)
    failed = [r for r in rows if r["status"] != "0"]
    assert float(failed[0]["rpm"]) == 100.0 and failed[0]["motion_class"] == "failed"
    assert z["ok"].ravel().tolist() == [False, True]


@pytest.mark.parametrize("overrides, reason", [
    (["integration.max_steps=100"], "maximum number of steps"),
    (["map.rpm_min=1", "map.rpm_max=2", "integration.max_steps=20000"],
     "maximum number of steps"),
    # regression: the largest-mesh-force run failed and the point kept status 0 with its
    # force NaN, written as 0 N in map.npz and map.csv
    (["map.force_periods=1000", "integration.max_steps=5000"], "largest mesh force"),
], ids=["step-budget-100", "1-to-2-rpm", "force-run-fails"])
def test_every_point_failing_exits_1_with_the_reason(tmp_path, capsys, overrides, reason):
    out = tmp_path / "out"
    assert main(_args("map", out, SMALL + overrides)) == 1
    err = capsys.readouterr().err
    assert "map: all 2 points failed" in err and reason in err, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and reason in summary["results"]["map"]["message"]
    assert not (out / "map.npz").exists()


def test_force_failure_marks_the_point_not_ok_in_process(tmp_path):
    """The raw map (before the files replace NaN): a point whose largest mesh force could
    not be computed has a non-zero status and its message; no point with status 0 has a
    non-finite written value."""
    for extra, all_failed in (([], False), (["map.force_periods=1000",
                                             "integration.max_steps=5000"], True)):
        scene = load_scene(GEAR_PAIR, tuple(SMALL + extra))
        study = build_study(scene)
        ctx = RunContext(out=tmp_path / f"o{len(extra)}", quiet=True)
        ctx.out.mkdir()
        if all_failed:
            from vibrogear.pipeline.outcome import NumericalFailure
            with pytest.raises(NumericalFailure, match="largest mesh force"):
                operating_map.run(study, scene, ctx)
            continue
        res = operating_map.run(study, scene, ctx).result
        for row in res.rows:
            ok = row.status == 0
            assert ok.all()
            for name in WRITTEN:
                vals = getattr(row, name, None)
                vals = row.metrics[name] if vals is None else vals
                assert np.all(np.isfinite(np.asarray(vals, float)[ok])), name
