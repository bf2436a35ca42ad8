"""A slow transient is not a torus: a point without a period is shot from its settled state
before it is called quasi-periodic (solvers/sequential/orbit_check.py).

Reference: the impact pair in permanent contact (f_m > kappa b_r, small forcing) is the
linear oscillator q'' + 2 zeta q' + q = f_m + (1 - kappa) b_r + f_p cos(Omega t): its
periodic orbit is q_s + Re(A e^{i Omega t}), q_s = f_m + (1 - kappa) b_r,
A = f_p / (1 - Omega^2 + 2 i zeta Omega), and its Floquet multipliers have modulus
exp(-zeta T) (natural frequency 1).  With zeta = 1e-3 the free vibration decays by only
exp(-zeta t) ~ 4 % of its start over 300 excitation periods, so the stroboscopic samples
still drift when the transient budget ends.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from vibrogear.config.options import IntegrationOptions, SweepOptions
from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.sequential.motion import PERIODIC
from vibrogear.solvers.sequential.sweep import sweep

ZETA, KAPPA, F_M, F_P, B_R = 1e-3, 0.5, 0.55, 0.01, 1.0
OMEGA = 0.6
Q_S = F_M + (1 - KAPPA) * B_R
AMP = F_P / abs(1 - OMEGA**2 + 2j * ZETA * OMEGA)
OPTS = IntegrationOptions(rtol=1e-10, atol=1e-12)


def _point(shoot: bool):
    settings = SweepOptions(directions=("up",), transient_periods=300, extra_transient_periods=0,
                            record_periods=32, shoot=shoot)
    return sweep(impact_pair_model(ZETA, KAPPA, F_M, F_P, B_R), [OMEGA], settings, options=OPTS,
                 u0=np.array([Q_S, 0.0]))


def test_lightly_damped_mode_is_periodic_after_300_transient_periods():
    r = _point(shoot=True)
    assert r.motion_class[0] == PERIODIC and r.period_n[0] == 1
    assert r.settled_by[0] == "shooting"
    # the record is taken on the orbit: its extrema are the closed form's
    assert r.qmin[0] == pytest.approx(Q_S - AMP, abs=1e-9)
    assert r.qmax[0] == pytest.approx(Q_S + AMP, abs=1e-9)
    # the multipliers reported with it: |mu| = exp(-zeta T)
    T = 2 * math.pi / OMEGA
    assert r.metrics["orbit_max_multiplier"][0] == pytest.approx(math.exp(-ZETA * T), rel=1e-7)
    assert r.metrics["orbit_stable"][0] == 1.0


def test_without_the_check_the_same_point_has_no_period():
    """The case the check exists for: the stroboscopic map alone finds no period."""
    r = _point(shoot=False)
    assert r.period_n[0] == 0 and r.motion_class[0] != PERIODIC
    # the recorded extrema are off the orbit by the undecayed free vibration
    assert abs(r.qmax[0] - (Q_S + AMP)) > 1e-5


def test_a_large_models_slow_transient_is_found_by_extrapolation(monkeypatch):
    """Above NEWTON_MAX_STATES (a gearbox) no Newton iteration is paid: the fixed point of
    the record's stroboscopic map is extrapolated (RRE) and checked by one plain period.
    The same closed-form orbit, and the decay rate of the record towards it estimates the
    largest multiplier exp(-zeta T)."""
    from vibrogear.solvers.sequential import orbit_check
    monkeypatch.setattr(orbit_check, "NEWTON_MAX_STATES", 0)
    r = _point(shoot=True)
    assert r.motion_class[0] == PERIODIC and r.period_n[0] == 1
    assert r.settled_by[0] == "shooting" and r.metrics["orbit_newton"][0] == 0.0
    assert r.qmin[0] == pytest.approx(Q_S - AMP, abs=1e-9)
    assert r.qmax[0] == pytest.approx(Q_S + AMP, abs=1e-9)
    T = 2 * math.pi / OMEGA
    assert r.metrics["orbit_max_multiplier"][0] == pytest.approx(math.exp(-ZETA * T), rel=2e-3)
