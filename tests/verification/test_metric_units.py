"""The contact metrics of a gearbox in SI units: approach speeds in m/s and impact energies
in J.  The reference clock is the mesh frequency from the gear data (rpm / 60 x teeth x
speed ratio), not the model's time unit: the approach speeds at the drive-flank onsets
of a settled gear_pair motion, measured by finite differences of the mesh deformation
on the integrator's dense output, agree with the sweep's metrics; the impact energy is
m_eff v^2 / 2 per onset with m_eff = 1 / (c . c) in kg (modal coordinates mass-normalised
in kg, as the rotor and housing modes are)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.analyses.runup.runup import shaft_orders
from vibrogear.analyses.study import build_study
from vibrogear.config import load_scene
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.sequential.sweep import sweep
from vibrogear.config.options import SweepOptions

GEAR_PAIR = Path(__file__).resolve().parents[2] / "configs" / "gear_pair.toml"
OPT = IntegrationOptions(rtol=1e-9, atol=1e-15)
RPM = 5300.0           # one drive-flank impact per mesh period (contact loss, no back flank)


def _deformation(model, rpm, t, x):
    """delta(t) = c . x - e(t) of the monitored mesh (model units of time)."""
    ct, j = model.contacts, model.monitor
    W = model.excitation_frequency(rpm)
    e = sum(ct.error_cos[j, h] * np.cos((h + 1) * W * t) + ct.error_sin[j, h]
            * np.sin((h + 1) * W * t) for h in range(ct.error_cos.shape[1]))
    return x @ ct.directions[j] - e


@pytest.fixture(scope="module")
def case():
    scene = load_scene(GEAR_PAIR)
    study = build_study(scene)
    model = study.model
    P = 16
    T = model.excitation_period(RPM)
    u0 = integrate(model, RPM, study.start(RPM), 0.0, 300 * T, options=OPT).u_end
    s = sweep(model, [RPM], SweepOptions(directions=("up",), transient_periods=1, record_periods=P, max_period=4, lyapunov=False, extra_transient_periods=0), options=OPT, u0=u0, settle=False)
    assert s.transient_used[0] == 1
    start = integrate(model, RPM, u0, 0.0, T, options=OPT).u_end    # the record's start
    names, orders, _ = shaft_orders(scene, (1,))
    f_mesh = RPM / 60.0 * orders[names.index(f"{scene.gearbox.meshes[0].name}_1x")]
    return scene, study, model, s, P, f_mesh, start


def test_approach_speeds_in_metres_per_second(case):
    scene, study, model, s, P, f_mesh, start = case
    g = s.metrics
    assert study.energy_unit == "J" and model.length_unit == "m"
    assert g["impacts_drive_G1"][0] == 1.0 and g["impacts_back_G1"][0] == 0.0
    # the sweep's record window again, sampled finely: the onsets where delta rises through
    # the drive-flank gap (gap_hi), their slopes per model time, then per second through
    # the mesh period in seconds (1 / f_mesh) against the model's period
    T = model.excitation_period(RPM)
    t = np.linspace(0.0, P * T, P * 4000 + 1)
    tr = integrate(model, RPM, start, 0.0, P * T, t_eval=t, options=OPT)
    d = _deformation(model, RPM, t, tr.u[:, :model.n_modes])
    gap = model.contacts.gap_hi[model.monitor]
    up = np.flatnonzero((d[:-1] <= gap) & (d[1:] > gap))
    assert up.size == P
    slope = (d[up + 1] - d[up]) / (t[up + 1] - t[up])     # per model time, O(dt) accurate
    per_second = slope * T * f_mesh
    assert g["impact_velocity_max_G1"][0] == pytest.approx(per_second.max(), rel=2e-3)
    assert g["impact_velocity_rms_G1"][0] == pytest.approx(
        np.sqrt(np.mean(per_second ** 2)), rel=2e-3)
    assert 0.05 < per_second.max() < 5.0                  # m/s: a tooth impact, not mm/s


def test_impact_energy_in_joule(case):
    _, _, model, s, _, _, _ = case
    g = s.metrics
    m_eff = 1.0 / np.sum(model.contacts.directions[model.monitor] ** 2)     # kg
    v_rms = g["impact_velocity_rms_G1"][0]
    per_period = g["impacts_drive_G1"][0] + g["impacts_back_G1"][0]
    assert g["rattle_G1"][0] == pytest.approx(0.5 * m_eff * v_rms ** 2 * per_period, rel=1e-9)
