"""The time response's contact-loss count (``contact_losses_second_half``) against counts
that do not come from the sampled trajectory it reads.

* a forced linear oscillator (the impact pair with kappa = 1: no contact stiffness, so the
  motion is q = f_m + A cos(Omega t - phi) + a decaying transient): the working flank
  (q > b_r) is left once per period, at the closed-form down-crossings of b_r;
* the impacting pair (kappa = 0.5, the paper's scene): the exact piecewise-linear flow
  (:mod:`vibrogear.verification.impact_exact`, which shares no code with the integrator)
  gives the switch times out of the upper contact region.

Before the fix the count was ``np.diff`` of a boolean (XOR, never negative): always 0.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.analyses import time_response
from vibrogear.analyses.study import build_study
from vibrogear.analyses.time_response import working_flank_losses
from vibrogear.config import load_scene
from vibrogear.pipeline.outcome import RunContext
from vibrogear.verification.impact_exact import ImpactParams, exact_flow

ROOT = Path(__file__).resolve().parents[2]


def _time_response(tmp_path, *overrides):
    scene = load_scene(ROOT / "configs" / "impact_pair.toml",
                       ("scene.analyses=['time_response']",) + overrides)
    outcome = time_response.run(build_study(scene), scene, RunContext(out=tmp_path, quiet=True))
    return scene, outcome


def _second_half_start(t) -> float:
    """The first sample of the second half (the analysis counts from there)."""
    return float(t[t >= 0.5 * t[-1]][0])


def test_working_flank_losses_by_hand():
    # gaps (0, -1): modes +1 +1 0 -1 0 +1 +1 0 +1 -> two departures from +1
    delta = [0.5, 0.2, -0.3, -2.0, -0.5, 0.1, 0.3, -0.1, 0.2]
    assert working_flank_losses(delta, 0.0, -1.0) == 2
    # leaving the back flank is not a loss of the working flank
    assert working_flank_losses([-2.0, -0.5, -2.0, -0.5], 0.0, -1.0) == 0
    assert working_flank_losses([0.1, 0.2, 0.3], 0.0, -1.0) == 0
    assert working_flank_losses([-0.5, 0.1], 0.0, -1.0) == 0          # an onset, no loss


def test_forced_linear_oscillator_closed_form(tmp_path):
    """kappa = 1: q'' + 2 zeta q' + q = f_m + f_p cos(Omega t) whatever the region, so
    q(t) -> f_m + A cos(Omega t - phi), A = f_p / sqrt((1 - Omega^2)^2 + (2 zeta Omega)^2),
    tan phi = 2 zeta Omega / (1 - Omega^2).  With f_m - A < b_r < f_m + A the working flank
    q > b_r is left at Omega t - phi = arccos((b_r - f_m) / A) + 2 pi k: once per period,
    30 times in the second half of 60 periods."""
    zeta, f_m, f_p, b_r, Om = 0.05, 0.55, 0.12, 1.0, 0.9
    scene, out = _time_response(tmp_path, "impact_pair.kappa=1.0", f"impact_pair.zeta={zeta}",
                                f"time_response.omega={Om}", "time_response.periods=60")
    r = out.result
    A = f_p / np.hypot(1.0 - Om ** 2, 2.0 * zeta * Om)
    phi = np.arctan2(2.0 * zeta * Om, 1.0 - Om ** 2)
    assert f_m - A < b_r < f_m + A                      # the flank is crossed
    # the recorded motion is the closed form (transient decayed by exp(-zeta t) ~ 3e-5)
    half = r.t >= 0.5 * r.t[-1]
    exact_q = f_m + A * np.cos(Om * r.t[half] - phi)
    assert np.max(np.abs(r.u[half, 0] - exact_q)) < 1e-3 * A
    k = np.arange(0, 200)
    t_down = (np.arccos((b_r - f_m) / A) + phi + 2 * np.pi * k) / Om
    t0, t1 = _second_half_start(r.t), r.t[-1]
    expected = int(np.count_nonzero((t_down > t0) & (t_down <= t1)))
    assert expected == 30
    assert out.summary["contact_losses_second_half"] == {"clearance": expected}


@pytest.mark.parametrize("omega", [0.9, 0.8])
def test_impacting_pair_against_exact_flow(tmp_path, omega):
    """The paper's impact pair (zeta 0.015, kappa 0.5, f_m 0.55, f_p 0.12, b_r 1): the
    count equals the exact flow's switches out of region +1 over the same window
    (Omega 0.9: 30, once per period; Omega 0.8: 30, with back-flank impacts as well)."""
    scene, out = _time_response(tmp_path, f"time_response.omega={omega}",
                                "time_response.periods=60", "time_response.samples_per_period=64")
    r = out.result
    c = scene.impact_pair
    p = ImpactParams(zeta=c.zeta, kappa=c.kappa, f_m=c.f_m, f_p=c.f_p, b_r=c.b_r)
    flow = exact_flow(p, omega, r.u[0], 0.0, float(r.t[-1]))
    t0 = _second_half_start(r.t)
    window = flow.switch_times > t0
    expected = int(np.count_nonzero(window & (flow.switch_from == 1)))
    assert expected >= 30
    if omega == 0.8:                                     # the back flank is hit too
        assert np.any(window & (flow.switch_to == -1))
    assert out.summary["contact_losses_second_half"] == {"clearance": expected}


def test_gear_pair_against_dense_sign_changes(tmp_path):
    """gear_pair at 5800 rpm, where G1 loses contact every mesh period (the figure shows
    delta down to about -10 um): the count from 16 samples per period equals the
    downward sign changes of delta - g_hi on the same motion integrated again and
    sampled 32 times more densely (10 in the 10 periods of the second half; 0 before
    the fix)."""
    from vibrogear.analyses.study import integration_options
    from vibrogear.solvers.integrator.contact_eval import contact_history
    from vibrogear.solvers.integrator.integrate import integrate

    scene = load_scene(ROOT / "configs" / "gear_pair.toml",
                       ("scene.analyses=['time_response']", "time_response.rpm=5800",
                        "time_response.periods=20", "time_response.samples_per_period=16"))
    study = build_study(scene)
    out = time_response.run(study, scene, RunContext(out=tmp_path, quiet=True))
    r, model = out.result, study.model
    dense_t = np.linspace(0.0, r.t[-1], 20 * 512 + 1)
    tr = integrate(model, r.param, r.u[0], 0.0, r.t[-1], t_eval=dense_t,
                   options=integration_options(scene, record=True, study=study))
    delta, _, _ = contact_history(model, r.param, tr.t, tr.u)
    t0 = _second_half_start(r.t)
    expected = {}
    for j in study.contact_groups["mesh"]:
        above = (delta[j] - model.contacts.gap_hi[j] > 0)[tr.t >= t0]
        expected[model.contacts.names[j]] = int(np.count_nonzero(above[:-1] & ~above[1:]))
    assert expected == {"G1": 10}
    assert out.summary["contact_losses_second_half"] == expected
