"""A slow run-up reproduces the steady state; a fast one jumps late (gear_pair).

References: the sequential continuation (solvers/sequential/sweep.py: settled steady states, one
speed at a time) and the folds of the period-1 branch found by shooting + pseudo-arclength
continuation (5126.6 and 5233.7 rpm, ``vibrogear continue configs/gear_pair.toml``): two
computations independent of the chunked transient."""
from __future__ import annotations

import numpy as np
import pytest

from vibrogear.analyses.runup.runup import jump_speed, period_table
from vibrogear.analyses.study import build_study
from vibrogear.config import load_scene
from vibrogear.solvers.integrator.integrate import IntegrationOptions
from vibrogear.solvers.sequential.ramp import SpeedProfile, ramp
from vibrogear.solvers.sequential.sweep import sweep
from vibrogear.config.options import SweepOptions

pytestmark = pytest.mark.slow

OPTS = IntegrationOptions(rtol=1e-7, atol=1e-13)
FOLD_LOW, FOLD_HIGH = 5126.6, 5233.7


@pytest.fixture(scope="module")
def study():
    return build_study(load_scene("configs/gear_pair.toml"))


def _envelope(study, rpm_a, rpm_b, rate):
    """(rpm, min, max) per mesh period of the monitored mesh along a ramp rpm_a -> rpm_b."""
    m = study.model
    prof = SpeedProfile.of([0.0, abs(rpm_b - rpm_a) / rate], [rpm_a, rpm_b], study.time_unit_s)
    r = ramp(m, prof, study.start(rpm_a), options=OPTS, settle_periods=1000,
             rows=[m.monitor])
    assert r.ok, r.message
    _, lo, hi, _ = period_table(r, 0, (m.contacts.gap_hi[[m.monitor]],
                                       m.contacts.gap_lo[[m.monitor]]))
    P = r.periods
    rpm = r.param[:P * r.samples_per_period].reshape(P, -1).mean(axis=1)
    return rpm, lo[0], hi[0]


@pytest.mark.parametrize("rpm_a, rpm_b, speeds", [
    (4960.0, 5080.0, (4990.0, 5020.0, 5050.0)),      # below the hysteresis
    (5600.0, 5720.0, (5630.0, 5660.0, 5690.0)),      # above it
])
def test_slow_ramp_reproduces_sweep_extrema(study, rpm_a, rpm_b, speeds):
    """At 40 rpm/s, the envelope of the mesh period nearest each sweep speed equals the
    settled sweep's extrema to 1e-2 of their range (measured 3.4e-4 at most, below the
    folds; 3e-6 above; at 20 rpm/s half of that: the error is the quasi-static lag)."""
    m = study.model
    sw = sweep(m, np.array(speeds), SweepOptions(directions=("up",), transient_periods=300, extra_transient_periods=400, record_periods=32, period_tol=1e-5, workers=1, lyapunov=False), options=OPTS, u0=study.start(speeds[0]))
    assert np.all(sw.status == 0)
    rpm, lo, hi = _envelope(study, rpm_a, rpm_b, 40.0)
    for k, p in enumerate(speeds):
        i = int(np.argmin(np.abs(rpm - p)))
        assert abs(rpm[i] - p) < 0.1
        span = sw.qmax[k] - sw.qmin[k]
        assert abs(hi[i] - sw.qmax[k]) < 1e-2 * span
        assert abs(lo[i] - sw.qmin[k]) < 1e-2 * span


def test_jumps_come_after_the_folds_and_later_at_a_faster_ramp(study):
    """Across the hysteresis (folds 5126.6 / 5233.7 rpm): the run-up jumps above the upper
    fold, the run-down below the lower one, and four times the rate delays both jumps
    further (measured: up 5235.1 / 5237.4 rpm, down 5123.3 / 5119.1 rpm at 100 / 400
    rpm/s: delays 1.4 / 3.7 rpm and 3.3 / 7.5 rpm)."""
    found = {}
    for rate in (100.0, 400.0):
        rpm, _, hi = _envelope(study, 5050.0, 5300.0, rate)
        up = jump_speed(rpm, hi)
        rpm, _, hi = _envelope(study, 5300.0, 5050.0, rate)
        down = jump_speed(rpm, hi)
        assert up is not None and down is not None
        assert up["after"] > up["before"] and down["after"] < down["before"]
        found[rate] = (up["rpm"], down["rpm"])
    for rate, (up, down) in found.items():
        assert up > FOLD_HIGH and down < FOLD_LOW, (rate, up, down)
    assert found[400.0][0] > found[100.0][0] and found[400.0][1] < found[100.0][1], found
