"""Operating maps over speed x load (issue 12, item 1): the load as one number, a map row
against a sweep of a model built at that load, bad [map] input, resuming, the files."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from vibrogear.analyses.map.load_scaling import load_scaling
from vibrogear.analyses.static_load import static_load
from vibrogear.analyses.map.map import PARTIAL_NAME, compute_map
from vibrogear.analyses.study import build_study
from vibrogear.cli import main
from vibrogear.config import ConfigError, load_scene
from vibrogear.config.options import SweepOptions
from vibrogear.solvers.sequential.sweep import sweep

GEAR_PAIR = str(Path(__file__).resolve().parents[2] / "configs" / "gear_pair.toml")
#: a short sweep: enough for the gear pair's period-1 points to settle on the map
SETTINGS = SweepOptions(transient_periods=100, extra_transient_periods=150, record_periods=16,
                        max_period=4, period_tol=1e-4, directions=("up",), workers=1,
                        lyapunov=False)


def _twists(value: float) -> tuple[str, ...]:
    return (f"gearbox.couplings[0].twist={value!r}", f"gearbox.couplings[1].twist={value!r}")


@pytest.fixture(scope="module")
def nominal():
    scene = load_scene(GEAR_PAIR)
    study = build_study(scene)
    return scene, study, load_scaling(study.gearbox, scene.gearbox)


def _carried(overrides=()) -> float:
    """The motor coupling's torque [N m] in the load path of the scene rebuilt with
    ``overrides`` (the full scene's static state: vibrogear.analyses.static_load)."""
    lp = static_load(load_scene(GEAR_PAIR, overrides)).load_path
    return next(c["torque_Nm"] for c in lp.couplings if c["role"] == "motor")


def test_the_torque_is_the_one_the_static_state_carries(nominal):
    """The map's torque is the load path's, not stiffness x twist (62.5 N m at the motor's
    spring, 250 N m at the load's: the gear ratio 2 balances neither, the static state carries
    90.98 N m): at the nominal twists and at 0.6 and 1.6 x them, against the load path of the
    scene rebuilt with those twists; the twist scales the motor coupling's."""
    scene, _, ls = nominal
    assert ls.torque_nominal == pytest.approx(_carried(), rel=1e-9)
    assert 80.0 < ls.torque_nominal < 93.75     # rigid shafts and teeth would carry 93.75
    assert ls.twist_nominal == 0.025
    for s in (0.6, 1.6):
        assert ls.torque(s) == pytest.approx(_carried(_twists(s * 0.025)), rel=1e-9)
        assert ls.scale_of_torque(ls.torque(s)) == pytest.approx(s, rel=1e-12)
        assert ls.twist(s) == pytest.approx(s * 0.025, rel=1e-15)
    assert ls.torque_law_error_rel < 1e-9


def test_f0_of_the_decomposition_equals_a_model_built_with_the_twists(nominal):
    """F0(s) = F0_rest + s F0_couplings against two models built with --set twists (gear_pair's
    basis does not depend on the load, so the models must agree entirely)."""
    scene, study, ls = nominal
    for twist in (0.0, 0.04):
        other = build_study(load_scene(GEAR_PAIR, _twists(twist))).model
        f0 = ls.f0(ls.scale_of_twist(twist))
        ref = other.forcing.F0
        assert np.max(np.abs(f0 - ref)) <= 1e-12 * np.max(np.abs(study.model.forcing.F0))
        assert np.array_equal(other.omega2, study.model.omega2)
        assert np.array_equal(other.contacts.directions, study.model.contacts.directions)
    assert np.linalg.norm(ls.f0_couplings) > 0.1 * np.linalg.norm(study.model.forcing.F0)


def test_a_map_row_equals_a_sweep_of_the_model_built_at_that_load(nominal):
    """Row at twist 0.028 rad against `sweep` of the scene rebuilt with twist 0.028
    (speeds below the jump region, where the loaded mesh settles on period-1 orbits): same
    period at every point, extrema of the periodic points within 1e-6 relative."""
    scene, study, ls = nominal
    rpm = np.array([4850.0, 4900.0, 4950.0, 5000.0])
    s = float(ls.scale_of_twist(0.028))
    m = compute_map(study, ls, rpm, [s], SETTINGS, scene.integration, force_periods=1,
                    force_samples=32)
    row = m.rows[0]
    other = build_study(load_scene(GEAR_PAIR, _twists(0.028)))
    ref = sweep(other.model, rpm, SweepOptions.of(SETTINGS), u0=other.start(rpm[0]),
                options=scene.integration)
    assert np.array_equal(row.param, ref.param)
    assert np.array_equal(row.period_n, ref.period_n)
    per = ref.period_n > 0
    assert per.sum() >= 2
    for q in ("qmin", "qmax"):
        a, b = getattr(row, q)[per], getattr(ref, q)[per]
        assert np.all(np.abs(a - b) <= 1e-6 * np.abs(b))
    assert np.array_equal(row.motion_class[per], ref.motion_class[per])
    # the largest mesh force, sampled 32 times per period: from below, within 2 %, of the
    # same period sampled 1024 times (the orbit is periodic: one period is all of it)
    from vibrogear.analyses.map.map import _max_mesh_force
    from vibrogear.solvers.sequential.record_metrics import contact_groups
    model = ls.model_at(study.model, s)
    mesh = {"G1": contact_groups(model)["G1"][1]}
    for k in np.flatnonzero(per):
        fine = _max_mesh_force(model, row.param[k], row.u_end[k], mesh, 1,
                               1024, scene.integration, study.force_unit_n)["max_force_G1"]
        coarse = row.metrics["max_force_G1"][k]
        assert fine * 0.98 <= coarse <= fine * (1 + 1e-9)


@pytest.mark.parametrize("override, field", [
    (("map.twist_min=0.01", "map.twist_max=0.03"), "map.twist_min"),       # both given
    (("map.torque_min=120.0",), "map.torque_max"),                         # empty range
    (("map.n_speeds=0",), "map.n_speeds"),
    (("map.n_loads=0",), "map.n_loads"),
    (("map.n_loads=-3",), "map.n_loads"),
    (("map.rpm_max=4000.0",), "map.rpm_max"),
])
def test_bad_map_input_names_the_field_and_check_exits_2(override, field, capsys):
    overrides = tuple(override)
    with pytest.raises(ConfigError) as exc:
        load_scene(GEAR_PAIR, overrides)
    assert exc.value.path == field
    args = ["check", GEAR_PAIR]
    for o in overrides:
        args += ["--set", o]
    assert main(args) == 2
    assert field in capsys.readouterr().err


def test_a_map_needs_a_loaded_motor_coupling(tmp_path, capsys):
    """The load is scaled from the motor coupling's twist: none, or twist 0, is bad input
    of `vibrogear map` (exit 2, nothing written); other verbs of the scene are not blocked."""
    out = tmp_path / "none"
    assert main(["map", GEAR_PAIR, "--out", str(out), "--set",
                 "gearbox.couplings[0].twist=0"]) == 2
    assert "gearbox.couplings[0].twist" in capsys.readouterr().err and not out.exists()
    assert main(["check", GEAR_PAIR, "--set", "gearbox.couplings[0].role=\"load\"",
                 "--set", "scene.analyses=[\"map\"]"]) == 2
    assert "gearbox.couplings:" in capsys.readouterr().err
    assert main(["check", GEAR_PAIR, "--set", "gearbox.couplings[0].twist=0"]) == 0


def test_a_load_range_needs_both_ends():
    from vibrogear.config.scene import read_toml, scene_from_dict
    data = read_toml(GEAR_PAIR)
    del data["map"]["torque_max"]
    with pytest.raises(ConfigError) as exc:
        scene_from_dict(data)
    assert exc.value.path == "map.torque_max"
    del data["map"]["torque_min"]
    with pytest.raises(ConfigError) as exc:
        scene_from_dict(data)
    assert exc.value.path == "map.torque_min" and "twist_min" in str(exc.value)


def test_an_interrupted_map_reuses_its_finished_points(nominal, tmp_path):
    scene, study, ls = nominal
    rpm = np.array([4850.0, 4900.0, 4950.0])
    scales = [1.0, 1.12]
    kw = dict(force_periods=1, force_samples=16)
    seen = []

    def stop_after_three(_row, rec):
        seen.append(rec)
        if len(seen) == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        compute_map(study, ls, rpm, scales, SETTINGS, scene.integration, out=tmp_path,
                    callback=stop_after_three, **kw)
    lines = (tmp_path / PARTIAL_NAME).read_text().splitlines()
    assert len(lines) == 1 + 3                  # header + three finished points
    again = []
    m = compute_map(study, ls, rpm, scales, SETTINGS, scene.integration, out=tmp_path,
                    callback=lambda _r, rec: again.append(rec), **kw)
    assert m.resumed == 3 and len(again) == 3   # only the other three are computed
    clean = compute_map(study, ls, rpm, scales, SETTINGS, scene.integration, **kw)
    for a, b in zip(m.rows, clean.rows):
        assert np.array_equal(a.qmax, b.qmax) and np.array_equal(a.period_n, b.period_n)
        assert np.array_equal(a.metrics["max_force_G1"], b.metrics["max_force_G1"])


def test_the_map_verb_writes_both_load_units_and_the_grids(tmp_path):
    out = tmp_path / "map"
    code = main(["map", GEAR_PAIR, "--quiet", "--out", str(out), "--set", "map.n_speeds=3",
                 "--set", "map.n_loads=2", "--set", "map.curves=false",
                 "--set", "map.transient_periods=40", "--set", "map.extra_transient_periods=0",
                 "--set", "map.record_periods=8", "--set", "map.max_period=4",
                 "--set", "map.workers=1"])
    assert code == 0
    with np.load(out / "map.npz") as z:
        assert np.allclose(z["torque"], [55.0, 110.0])
        # the twist at which the static state carries that torque (gear_pair: linear)
        assert np.allclose(z["twist"], 0.025 * z["torque"] / _carried(), rtol=1e-9)
        z_twist = z["twist"].copy()
        shape = (2, 2, 3)                       # directions x loads x speeds
        for key in ("motion_class", "impacts_G1", "rattle_G1", "max_force_G1", "status",
                    "wall_time", "contact_fraction_G1"):
            assert z[key].shape == shape, key
        assert np.array_equal(z["impacts_G1"], z["impacts_drive_G1"] + z["impacts_back_G1"])
    summary = json.loads((out / "summary.json").read_text())["results"]["map"]
    assert summary["loads"]["twist_rad"] == pytest.approx(list(z_twist), rel=1e-15)
    assert summary["loads"]["torque_law_error_rel"] < 1e-9
    assert summary["points"] == 12 and summary["cost"]["point_wall_s_mean"] > 0
    (walks,) = summary["parallel_phases"]           # 2 loads x 2 directions, one unit each
    assert walks["units"] == 4 and summary["serial_wall_s"] >= 0 and summary["serial_part"]
    assert not (out / PARTIAL_NAME).exists()
    rows = (out / "map.csv").read_text().splitlines()
    assert len(rows) == 1 + 12
    assert (out / "map_class.png").stat().st_size > 0
