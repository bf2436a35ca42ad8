"""The inertia torque of the acceleration in the run-up (solvers/sequential/ramp.py ``inertia_force``,
GearboxModel.rigid_inertia, ``[runup] inertia_torque``).

References, all from the scene's geometry (not from the code's Phi^T M r): the polar
inertias of the shafts (rho pi D^4 L / 32 per section) and gear rings
(rho pi w (R^4 - R_i^4) / 2, R the pitch radius), the speed ratios (-z_a / z_b), and the
quasi-static torque balance of a two-gear train under a constant acceleration.

Closed form (gear_pair, constant mesh stiffness k, no transmission error, load coupling
softened to k_l = 10 N m/rad): the deviations from the prescribed rigid rotation are
static under a constant acceleration alpha of the driving shaft (a linear, time-invariant
system started from its static equilibrium stays there).  With theta the rigid deviation of
the train (driving-shaft angle, in its sense of rotation; the driven shaft |p| theta,
p = -z1 / z2), J1 / J2 the shafts' polar inertias with their gears, k_m / k_l the motor /
load couplings and dF the extra mesh force:

    driving shaft:  -k_m theta - dF r_b1 = J1 alpha
    driven shaft:    dF r_b2 - k_l |p| theta = J2 |p| alpha

and r_b1 = |p| r_b2, so dF r_b2 = |p| alpha (J2 k_m - k_l J1) / (k_m + p^2 k_l)
(= J_eff alpha with J_eff = |p| (J2 k_m - k_l J1) / (k_m + p^2 k_l): the driven inertia,
less what the load coupling carries), and the mesh deformation shifts by
delta_shift = dF / k = J_eff alpha / (k r_b2), towards the loaded flank in a run-up."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from vibrogear.analyses.study import build_study
from vibrogear.config import ConfigError, load_scene
from vibrogear.config.base import build
from vibrogear.config.sections.runup import RunupConfig
from vibrogear.config.scene import read_toml, scene_from_dict
from vibrogear.models.gearbox.model import build_gearbox
from vibrogear.models.reduced import Forcing
from vibrogear.solvers.integrator.integrate import IntegrationOptions
from vibrogear.solvers.sequential.ramp import SpeedProfile, ramp
from vibrogear.solvers.static import static_equilibrium

RHO = 7850.0
OPTS = IntegrationOptions(rtol=1e-9, atol=1e-15)
RPM = 2 * math.pi / 60


def _shaft_inertia(sections) -> float:
    """Polar inertia of a solid stepped shaft [(D, L), ...]."""
    return RHO * math.pi / 32 * sum(d ** 4 * length for d, length in sections)


def _ring_inertia(pitch_d, inner_d, width) -> float:
    return RHO * math.pi * width * ((pitch_d / 2) ** 4 - (inner_d / 2) ** 4) / 2


#: gear_pair's driving shaft with z1, driven shaft with z2 (configs/gear_pair.toml)
J_DRIVING = (_shaft_inertia([(0.035, 0.04), (0.045, 0.20), (0.035, 0.04)])
             + _ring_inertia(0.080, 0.045, 0.025))
J_DRIVEN = (_shaft_inertia([(0.040, 0.04), (0.050, 0.20), (0.040, 0.04)])
            + _ring_inertia(0.160, 0.050, 0.025))


def test_rigid_rotation_inertia_of_gear_pair():
    """Phi^T M r of gear_pair: the rigid rotation at the speed ratios does not strain the
    mesh (d_G1 . Phi^T M r = 0, the mesh direction d = Phi^T v and Phi Phi^T M r = r: the
    rigid modes are kept), and |Phi^T M r|^2 = r^T M r = J1 + (z1/z2)^2 J2 from the
    geometry (measured 9e-14 relative)."""
    gm = build_gearbox(load_scene("configs/gear_pair.toml"))
    g = gm.rigid_inertia
    d = gm.reduced.contacts.directions[0]
    assert abs(d @ g) < 1e-10 * np.linalg.norm(d) * np.linalg.norm(g)
    assert g @ g == pytest.approx(J_DRIVING + 0.25 * J_DRIVEN, rel=1e-10)


def test_rigid_rotation_inertia_with_a_free_gear():
    """two_stage's train without the housing (gear_pair's spring bearings to ground): the
    free gear z4 turns
    at its own ratio -z3/z4 (not its shaft's -z1/z2); neither mesh is strained by the
    rigid rotation, and |Phi^T M r|^2 = J1 + (z1/z2)^2 J2 + (z3/z4)^2 J4 (z4's ring
    inertia on its own DOF, only its mass on the driven shaft)."""
    data = read_toml("configs/two_stage.toml")
    data.pop("housing")
    for sh, x in zip(data["gearbox"]["shafts"], (0.12, 0.24)):
        sh.pop("bore")
        sh.update(x=x, z=0.18)
    data["gearbox"].pop("master_modes")
    data["gearbox"]["bearings"] = read_toml("configs/gear_pair.toml")["gearbox"]["bearings"]
    gm = build_gearbox(scene_from_dict(data))
    g = gm.rigid_inertia
    dirs = gm.reduced.contacts.directions[gm.contact_indices("mesh")]
    assert dirs.shape[0] == 2
    assert np.all(np.abs(dirs @ g) < 1e-10 * np.linalg.norm(dirs, axis=1) * np.linalg.norm(g))
    j1 = J_DRIVING + _ring_inertia(0.110, 0.045, 0.020)
    j4 = _ring_inertia(0.130, 0.050, 0.020)
    assert g @ g == pytest.approx(j1 + 0.25 * J_DRIVEN + (55 / 65) ** 2 * j4, rel=1e-10)


@pytest.fixture(scope="module")
def quiet_pair():
    """gear_pair with a constant mesh stiffness, no transmission error and a nearly free
    load (k_l = 10 N m/rad, twist 0.9 rad: ~9 N m, 0.35 um of mesh deformation)."""
    return build_study(load_scene("configs/gear_pair.toml", (
        "gearbox.meshes[0].stiffness_cos=[]", "gearbox.meshes[0].te_cos=[]",
        "gearbox.couplings[1].stiffness=10.0", "gearbox.couplings[1].twist=0.9")))


@pytest.mark.parametrize("rate", [2.0e4, -1.0e4])
def test_quasi_static_mesh_shift_equals_the_closed_form(quiet_pair, rate):
    """Run-up at 2e4 rpm/s (5000 -> 5200 rpm in 10 ms, 34 mesh periods) and run-down at
    1e4 rpm/s: started from the static equilibrium under the inertia load, every sample of
    the G1 deformation is shifted from the run without it by delta_shift =
    J_eff alpha / (k r_b2) (module docstring; J_eff = 6.80e-3 kg m^2: +0.542 / -0.271 um,
    beside 0.346 um of static load, so the mesh stays in contact), with the sign of alpha.
    Measured 3.6e-5 relative: the rigid-train approximation of the load coupling's share
    (0.6 % of J_eff at k_l = 10 N m/rad; the error scales with k_l, 3.6e-8 at 0.01)."""
    study = quiet_pair
    model, gm = study.model, study.gearbox
    k_m, k_l, k = 2.5e3, 10.0, 3.5e8
    p = 0.5
    r_b2 = 0.080 * math.cos(math.radians(20.0))
    alpha = rate * RPM
    j_eff = p * (J_DRIVEN * k_m - k_l * J_DRIVING) / (k_m + p * p * k_l)
    expected = j_eff * alpha / (k * r_b2)

    duration = 0.01
    prof = SpeedProfile.of([0.0, duration], [5000.0, 5000.0 + rate * duration],
                           study.time_unit_s)
    slope = rate * study.time_unit_s                   # rpm per model time unit
    force = gm.inertia_force()
    loaded = replace(model, forcing=Forcing(model.forcing.F0 + slope * force,
                                            model.forcing.Fc, model.forcing.Fs))
    st = static_equilibrium(loaded, 5000.0)
    assert st.converged
    rows = [model.monitor]
    plain = ramp(model, prof, study.start(5000.0), options=OPTS, rows=rows,
                 samples_per_period=16)
    inert = ramp(model, prof, st.u0, options=OPTS, rows=rows, samples_per_period=16,
                 inertia_force=force)
    assert plain.ok and inert.ok and inert.inertia_torque and not plain.inertia_torque
    assert plain.periods >= 33
    d0 = plain.delta[0]
    assert np.ptp(d0) < 1e-6 * abs(expected) and d0[0] > 0      # static, on the drive flank
    shift = inert.delta[0] - d0
    assert np.max(np.abs(shift / expected - 1.0)) < 1e-4, (shift.min(), shift.max(), expected)


def test_constant_speed_is_bit_for_bit_the_run_without():
    """gear_pair as shipped (mesh stiffness and transmission-error harmonics, backlash):
    5600 rpm held for 12 mesh periods, then a ramp to 5700 rpm.  With the inertia force
    every chunk of the constant part equals the run without it bit for bit (deformations,
    rates, counters); once accelerating the two differ; a profile at a constant speed
    throughout gives the same result and end state, bit for bit."""
    study = build_study(load_scene("configs/gear_pair.toml"))
    model = study.model
    force = study.gearbox.inertia_force()
    T = model.excitation_period(5600.0)
    u0 = study.start(5600.0)
    kw = dict(options=IntegrationOptions(rtol=1e-7, atol=1e-13), samples_per_period=16,
              chunks_per_period=4)
    prof = SpeedProfile(np.array([0.0, 12 * T, 20 * T]), np.array([5600.0, 5600.0, 5700.0]))
    a = ramp(model, prof, u0, **kw)
    b = ramp(model, prof, u0, inertia_force=force, **kw)
    assert a.ok and b.ok
    held = int(np.sum(a.chunk_t[1:] <= 12 * T * (1 + 1e-12))) * 4    # samples of whole chunks
    assert held == 12 * 16
    assert np.array_equal(a.delta[:, :held], b.delta[:, :held])
    assert np.array_equal(a.delta_dot[:, :held], b.delta_dot[:, :held])
    assert np.max(np.abs(a.delta[:, held:] - b.delta[:, held:])) > 1e-9

    flat = SpeedProfile(np.array([0.0, 10 * T]), np.array([5600.0, 5600.0]))
    a = ramp(model, flat, u0, **kw)
    b = ramp(model, flat, u0, inertia_force=force, **kw)
    assert np.array_equal(a.delta, b.delta) and np.array_equal(a.u_end, b.u_end)
    assert (a.steps, a.rejected, a.events) == (b.steps, b.rejected, b.events)


def test_inertia_force_must_match_the_model():
    study = build_study(load_scene("configs/gear_pair.toml"))
    prof = SpeedProfile(np.array([0.0, 1.0]), np.array([5000.0, 5001.0]))
    with pytest.raises(ValueError, match="inertia_force"):
        ramp(study.model, prof, study.start(5000.0), inertia_force=np.zeros(3))


@pytest.mark.parametrize("value, ok", [(True, (True,)), (False, (False,)),
                                       ("both", (True, False)), ("yes", None), (1, None)])
def test_inertia_torque_option(value, ok):
    data = {"rpm_start": 1.0, "rpm_end": 2.0, "rate": 1.0, "inertia_torque": value}
    if ok is None:
        with pytest.raises(ConfigError) as exc:
            build(RunupConfig, data, "runup")
        assert exc.value.path == "runup.inertia_torque"
    else:
        assert build(RunupConfig, data, "runup").inertia_variants == ok
    assert build(RunupConfig, {"table": [[0, 1], [1, 2]]}, "runup").inertia_torque is True


def test_runup_both_writes_both_runs(tmp_path):
    """`vibrogear runup` with inertia_torque = "both" (gear_pair, 5000 -> 5010 rpm at
    100 rpm/s): runup.npz holds up / up_no_inertia (333 mesh periods each, floor of
    40 x 5005 / 60 x 0.1), flagged; the summary compares the two peaks."""
    import json

    from vibrogear.cli import main

    out = tmp_path / "gp"
    code = main(["runup", "configs/gear_pair.toml", "--quiet", "--out", str(out),
                 "--set", "runup.rpm_start=5000", "--set", "runup.rpm_end=5010",
                 "--set", "runup.settle_periods=20", "--set", "runup.window_revs=2",
                 "--set", "runup.directions=['up']", "--set", 'runup.inertia_torque="both"'])
    assert code == 0
    with np.load(out / "runup.npz") as z:
        assert list(z["runs"]) == ["up", "up_no_inertia"]
        assert list(z["inertia_torque"]) == [True, False]
        assert list(z["directions"]) == ["up"]
        assert z["up_rpm"].size == z["up_no_inertia_rpm"].size == 333
        assert not np.array_equal(z["up_env_max_G1"], z["up_no_inertia_env_max_G1"])
    assert (out / "runup_envelope.png").is_file()
    summary = json.loads((out / "summary.json").read_text())
    text = json.dumps(summary)
    assert '"inertia_effect"' in text and '"up_no_inertia"' in text
