"""Run-up / run-down by chunks of constant speed (solvers/sequential/ramp.py), order tracking and the
[runup] section.

References: the closed-form frequency response of a linear oscillator, one integrate()
run at constant speed, synthetic signals of known order content, and the convergence
order of the chunking measured against a fine chunking."""
from __future__ import annotations

import numpy as np
import pytest

from vibrogear.analyses.runup.order_tracking import order_tracks, waterfall
from vibrogear.cli import main
from vibrogear.config import ConfigError
from vibrogear.config.base import build
from vibrogear.config.sections.runup import RunupConfig
from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.sequential.ramp import SpeedProfile, ramp

OPTS = IntegrationOptions(rtol=1e-10, atol=1e-13)


def _linear(zeta: float, force: float):
    """q'' + 2 zeta q' + q = force cos(Omega t): the impact pair with kappa = 1 (no
    stiffness change at the clearance) and a clearance it never reaches."""
    return impact_pair_model(zeta, 1.0, 0.0, force, 1e6)


def test_slow_ramp_first_order_equals_frequency_response():
    """A run-up at dOmega/dt = 5e-5 (Omega 0.5 -> 1.5) of a linear oscillator (zeta 0.1):
    the 1x order amplitude, tracked over windows of 8 revolutions, equals the steady
    |H(Omega)| F = F / sqrt((1 - W^2)^2 + (2 zeta W)^2) at the window's speed: measured
    max relative error 0.35 % (at W = 1.05, where |H| changes fastest), 1 % asked."""
    zeta, F = 0.1, 0.3
    prof = SpeedProfile(np.array([0.0, 2e4]), np.array([0.5, 1.5]))
    r = ramp(_linear(zeta, F), prof, np.zeros(2), options=IntegrationOptions(rtol=1e-9,
             atol=1e-12), settle_periods=100, samples_per_period=32)
    assert r.ok and r.periods > 3000
    revs = r.phase / (2 * np.pi)
    tr = order_tracks(revs, r.delta[0], [1.0, 2.0], samples_per_rev=32, window_revs=8)
    W = np.interp(tr.revs, revs, r.param)
    H = F / np.sqrt((1 - W ** 2) ** 2 + (2 * zeta * W) ** 2)
    assert np.max(np.abs(tr.amplitude[0] / H - 1.0)) < 1e-2
    assert np.max(tr.amplitude[1]) < 1e-3 * np.max(H)      # a linear response has no 2x


@pytest.mark.parametrize("midpoint, order", [(True, 2.0), (False, 1.0)])
def test_chunking_error_converges_at_the_claimed_order(midpoint, order):
    """A fast ramp (Omega 0.6 -> 1.4 in 300 time units, through the resonance, zeta 0.05):
    the sampled response with 2, 4, 8 chunks per period against 64.  Midpoint speed:
    errors 7.3e-3, 1.4e-3, 3.4e-4 (observed order 2.0-2.4); start speed: 7.9e-2, 3.8e-2,
    2.0e-2 (order 1.0)."""
    model = _linear(0.05, 0.3)
    prof = SpeedProfile(np.array([0.0, 300.0]), np.array([0.6, 1.4]))
    opts = IntegrationOptions(rtol=1e-11, atol=1e-13)

    def samples(cpp):
        r = ramp(model, prof, np.zeros(2), options=opts, chunks_per_period=cpp,
                 samples_per_period=64, midpoint=midpoint)
        return r.delta[0, :r.periods * 64]

    ref = samples(64)
    cpps = np.array([2, 4, 8])
    errs = []
    for c in cpps:
        s = samples(c)
        n = min(s.size, ref.size)
        errs.append(np.max(np.abs(s[:n] - ref[:n])))
    slope = np.polyfit(np.log(1.0 / cpps), np.log(errs), 1)[0]    # err ~ h^slope
    assert order - 0.15 < slope < order + 0.5, (errs, slope)


def test_constant_speed_equals_one_integration():
    """A 'ramp' at constant speed (a table of equal speeds) with impacts (the impact pair
    of paper Fig. 4 at Omega = 0.8): chunk by chunk, each started at the local time
    (phase mod 2 pi) / Omega, equals one integrate() run at the same sample times to the
    integrator's tolerance (measured 1.6e-11 in q, 1.3e-13 in the end state, at rtol 1e-10;
    161 impacts)."""
    model = impact_pair_model(0.015, 0.5, 0.1, 0.2, 0.3)
    W = 0.8
    T = 2 * np.pi / W
    prof = SpeedProfile(np.array([0.0, 40 * T]), np.array([W, W]))
    u0 = np.array([0.2, 0.0])
    r = ramp(model, prof, u0, options=OPTS, chunks_per_period=4, samples_per_period=16)
    assert r.ok and r.periods == 40 and r.events > 0
    one = integrate(model, W, u0, 0.0, 40 * T, t_eval=r.t, options=OPTS)
    assert np.allclose(r.t, np.arange(r.t.size) * T / 16, rtol=0, atol=1e-12 * 40 * T)
    assert np.max(np.abs(r.delta[0] - one.u[:, 0])) < 1e-8
    assert np.allclose(r.u_end, one.u_end, rtol=0, atol=1e-8)


def test_constant_speed_gear_pair_keeps_the_excitation_phase():
    """The same on the gear pair (mesh stiffness and transmission-error harmonics, spin):
    a wrong chunk start time would shift the transmission error e(t) by a fraction of a
    mesh period (the deformation spans 37 um here); the chunked run equals one integration
    to 1e-6 um (measured 9e-10 um at rtol 1e-9)."""
    from vibrogear.analyses.study import build_study
    from vibrogear.config import load_scene

    study = build_study(load_scene("configs/gear_pair.toml"))
    model = study.model
    rpm = 5600.0
    T = model.excitation_period(rpm)
    prof = SpeedProfile(np.array([0.0, 30 * T]), np.array([rpm, rpm]))
    u0 = study.start(rpm)
    opts = IntegrationOptions(rtol=1e-9, atol=1e-15)
    r = ramp(model, prof, u0, options=opts, chunks_per_period=4, samples_per_period=32,
             rows=[model.monitor])
    one = integrate(model, rpm, u0, 0.0, 30 * T, t_eval=r.t, options=opts)
    from vibrogear.solvers.integrator.contact_eval import contact_history
    delta = contact_history(model, rpm, one.t, one.u)[0][model.monitor]
    assert np.ptp(delta) * 1e6 > 1.0
    assert np.max(np.abs(r.delta[0] - delta)) * 1e6 < 1e-6


def test_order_tracking_recovers_known_orders():
    """A signal of orders 1 (amplitude 2), 3.3 (0.5, off the bins of an 8-rev window) and
    40 (1.0) of a shaft accelerating from 10 to 30 rev/s, sampled uniformly in time:
    resampled in angle, each order's amplitude is recovered to 1e-3 (measured errors
    2.8e-5, 1.1e-4, 4e-8; 6e-6 for an absent order 7)."""
    t = np.linspace(0.0, 4.0, 400_001)
    revs = 10 * t + 2.5 * t ** 2                      # speed 10 + 5 t rev/s
    x = (2.0 * np.cos(2 * np.pi * revs) + 0.5 * np.sin(2 * np.pi * 3.3 * revs + 0.3)
         + 1.0 * np.cos(2 * np.pi * 40 * revs - 1.0) + 0.7)
    tr = order_tracks(revs, x, [1.0, 3.3, 40.0, 7.0], samples_per_rev=256, window_revs=8)
    assert tr.amplitude.shape[1] >= 19      # 80 revolutions, windows of 8 half-overlapping
    assert np.allclose(tr.amplitude[0], 2.0, atol=1e-3)
    assert np.allclose(tr.amplitude[1], 0.5, atol=1e-3)
    assert np.allclose(tr.amplitude[2], 1.0, atol=1e-3)
    assert np.max(tr.amplitude[3]) < 1e-3                 # an absent order


def test_waterfall_of_a_pure_tone():
    """A 1 kHz tone of amplitude 3 on a 100 Hz grid of bins: the waterfall's peak is at
    1 kHz with amplitude 3 (to 1e-9) in every segment."""
    fs = 20_000.0
    t = np.arange(int(fs)) / fs
    wf = waterfall(t, 3.0 * np.sin(2 * np.pi * 1000.0 * t), segment_s=0.01, fs=fs)
    k = np.argmax(wf.amplitude, axis=0)
    assert np.all(wf.frequency_hz[k] == 1000.0)
    assert np.allclose(wf.amplitude[k, np.arange(k.size)], 3.0, rtol=1e-9)


# ---------------------------------------------------------------- bad input

@pytest.mark.parametrize("data, field", [
    ({"rpm_start": 1.0, "rpm_end": 2.0, "rate": 1.0, "table": [[0, 1], [1, 2]]}, "runup.table"),
    ({"rpm_start": 1.0, "rpm_end": 2.0}, "runup.rate"),
    ({}, "runup.table"),
    ({"rpm_start": 1.0, "rpm_end": 1.0, "rate": 1.0}, "runup.rpm_end"),
    ({"rpm_start": 1.0, "rpm_end": 2.0, "rate": 0.0}, "runup.rate"),
    ({"table": [[0, 1], [0, 2]]}, "runup.table[1][0]"),
    ({"table": [[0.5, 1], [1, 2]]}, "runup.table[0][0]"),
    ({"table": [[0, 1], [1, -2]]}, "runup.table[1][1]"),
    ({"table": [[0, 1, 3], [1, 2]]}, "runup.table[0]"),
    ({"table": [[0, 1], [1, 2]], "samples_per_period": 30}, "runup.samples_per_period"),
    ({"table": [[0, 1], [1, 2]], "directions": ["sideways"]}, "runup.directions[0]"),
    ({"table": [[0, 1], [1, 2]], "rtol": 1.5}, "runup.rtol"),
])
def test_bad_runup_section_names_the_field(data, field):
    with pytest.raises(ConfigError) as exc:
        build(RunupConfig, data, "runup")
    assert exc.value.path == field


def test_check_rejects_a_bad_runup_section(tmp_path, capsys):
    out = tmp_path / "o"
    code = main(["check", "configs/gear_pair.toml", "--set", "runup.rate=-5", "--out", str(out)])
    assert code == 2
    assert "runup.rate" in capsys.readouterr().err
    assert not out.exists()
    assert main(["check", "configs/gear_pair.toml", "--set", "runup.rpm_end=4800",
                 "--out", str(out)]) == 2


def test_runup_verb_writes_its_files(tmp_path):
    """`vibrogear runup` on gear_pair, 5000 -> 5010 rpm at 100 rpm/s (0.1 s) and back: the
    files hold floor(integral of the mesh frequency dt) = floor(40 x 5005 / 60 x 0.1) = 333
    whole mesh periods per direction, speeds inside the ramp, and a 1x mesh order no larger
    than half the envelope's peak-to-peak (a harmonic cannot exceed the signal's swing)."""
    out = tmp_path / "gp"
    code = main(["runup", "configs/gear_pair.toml", "--quiet", "--out", str(out),
                 "--set", "runup.rpm_start=5000", "--set", "runup.rpm_end=5010",
                 "--set", "runup.settle_periods=20", "--set", "runup.window_revs=2"])
    assert code == 0
    for name in ("runup.npz", "runup.csv", "runup_envelope.png", "runup_orders.png",
                 "runup_waterfall.png"):
        assert (out / name).is_file(), name
    with np.load(out / "runup.npz") as z:
        for d in ("up", "down"):
            rpm = z[f"{d}_rpm"]
            assert rpm.size == 333
            assert np.all((rpm > 5000) & (rpm < 5010))
            assert np.all(np.diff(rpm) > 0) if d == "up" else np.all(np.diff(rpm) < 0)
            swing = z[f"{d}_env_max_G1"].max() - z[f"{d}_env_min_G1"].min()
            assert 0 < z[f"{d}_order_G1_G1_1x"].max() <= 0.5 * swing
    rows = (out / "runup.csv").read_text().splitlines()
    assert len(rows) == 1 + 2 * 333


def test_a_continued_run_starts_with_the_proposed_step():
    """integrate(first_step=h_next) of the run before: fewer steps than a fresh start from
    the tiny default step, the same end state within the tolerance, and a bad first step
    refused."""
    from vibrogear.models.impact_pair import impact_pair_model
    from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate

    model = impact_pair_model(0.05, 0.5, 0.55, 0.12, 1.0)
    om = 1.1
    T = 2 * np.pi / om
    opts = IntegrationOptions(rtol=1e-8, atol=1e-10)
    first = integrate(model, om, np.array([0.5, 0.0]), 0.0, 20 * T, options=opts)
    assert np.isfinite(first.h_next) and first.h_next > 0
    fresh = integrate(model, om, first.u_end, 0.0, T, options=opts)
    cont = integrate(model, om, first.u_end, 0.0, T, options=opts, first_step=first.h_next)
    assert cont.steps < fresh.steps
    assert np.allclose(cont.u_end, fresh.u_end, rtol=0, atol=1e-6)
    with pytest.raises(ValueError, match="first_step"):
        integrate(model, om, first.u_end, 0.0, T, options=opts, first_step=float("nan"))
