"""Motion classes at engineering resolution (solvers/sequential/motion.py).

* The imported FVA two-stage gearbox (tests/data/rexs), its second stage's excitation
  switched off (``excite = false``) so that the forcing repeats every mesh period: 60
  rolling elements at zero radial clearance switch contact at the edge of each load zone,
  so the full state never repeats within period_tol; both meshes stay in contact and their
  deformations and forces repeat within 1 nm / 1 N.  The point is periodic, not chaotic (it was called chaotic,
  Lyapunov exponent > 0, before the resolution rule).  The reference is the record itself:
  each mesh's stroboscopic deformation, computed here from the kept states by the contact
  directions and the transmission error, spreads by less than 1 nm.
* A linear oscillator forced at two frequencies whose ratio 21/13 approximates the golden
  ratio: the closed-form steady state repeats every 13 base periods and not every base
  period (its samples one base period apart spread by far more than the resolution):
  "multi-frequency forced", period 1 of the common excitation period, its extrema the
  closed form's.
* The chaotic impact pair stays chaotic (tests/verification/test_sweep_evidence.py), with
  the exponent's lower bound above its noise floor (the change at rtol / 10).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from vibrogear.config import load_scene
from vibrogear.config.base import ConfigError
from vibrogear.config.options import IntegrationOptions, SweepOptions
from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel
from vibrogear.solvers.sequential.motion import (CHAOTIC, MULTI_FREQUENCY, PERIODIC,
                                                 classify_period, resolved_period)
from vibrogear.solvers.sequential.sweep import sweep

REXS = Path(__file__).resolve().parents[1] / "data" / "rexs" / \
    "FVA-Industriegetriebe_2stufig_1-4.rexs"


def test_resolved_period_reads_each_quantity_at_its_resolution():
    """A period-2 splitting of 0.5 nm (+-0.25 nm) on a 1 um range is below the 1 nm
    resolution (period 1); 20 nm is above it (period 2: its period-1 difference exceeds 10
    resolutions); a 0.5 N force splitting is below
    1 N."""
    k = np.arange(16)
    base = 7e-6 + np.zeros(16)
    for split, n in ((0.25e-9, 1), (10e-9, 2)):
        q = {"delta_G1": base + split * (-1.0) ** k, "force_G1": 2000.0 + 0.25 * (-1.0) ** k}
        res = {"delta_G1": max(1e-3 * 1e-6, 1e-9), "force_G1": max(1e-3 * 300.0, 1.0)}
        got, defect = resolved_period(q, res, 8)
        assert got == n and defect <= 1.0
    # no period: the samples spread by 30 resolutions (the least over n of the worst)
    q = {"x": np.random.default_rng(0).uniform(0, 30e-9, 32)}
    n, spread = resolved_period(q, {"x": 1e-9}, 8)
    assert n == 0 and 10 < spread <= 30


def test_resolution_settings_are_validated():
    for field, bad in (("resolution_rel", 0.0), ("resolution_rel", 1.5),
                       ("resolution_length", -1e-9), ("resolution_force", -1.0)):
        with pytest.raises(ConfigError, match=field):
            SweepOptions(**{field: bad})


def _fva(overrides=()):
    from vibrogear.analyses.study import build_study, integration_options

    scene = load_scene(REXS, overrides)
    study = build_study(scene)
    opts = integration_options(scene, record=True, period_tol=scene.sweep.period_tol,
                               study=study)
    return study, opts


@pytest.fixture(scope="module")
def fva():
    return _fva(("gearbox.meshes[1].excite=false",))


def test_fva_both_stages_excited_is_multi_frequency_forced_not_chaotic():
    """With both stages excited (27/51 and 23/34 teeth: the forcing repeats only after 51
    mesh periods of the first stage, beyond the period limit) the samples are per mesh
    period and do not repeat; the response follows the forcing: multi-frequency forced."""
    study, opts = _fva()
    model = study.model
    assert model.multi_frequency
    s = sweep(model, [543.0], SweepOptions(directions=("up",), workers=1), options=opts,
              u0=study.start(543.0))
    assert s.status[0] == 0
    assert s.motion_class[0] == MULTI_FREQUENCY


def test_fva_gearbox_with_zero_clearance_bearings_is_periodic(fva):
    study, opts = fva
    model, rpm = study.model, 543.0
    ct = model.contacts
    one_sided = ~np.isfinite(ct.gap_lo)
    # the case: many rolling elements at zero clearance beside two meshes
    assert np.sum(one_sided & (ct.gap_hi == 0.0)) >= 50
    meshes = np.flatnonzero(~one_sided)
    assert meshes.size == 2
    s = sweep(model, [rpm], SweepOptions(directions=("up",), workers=1), options=opts,
              u0=study.start(rpm), keep_states=True)
    assert s.status[0] == 0
    states = s.states[0]
    # the full state does not repeat within period_tol (the rolling elements) ...
    assert classify_period(states, 8, 1e-5, split=model.n_modes)[0] == 0
    # ... the meshes do, within 1 nm: deformation = c . x - e(t) at the period ends (t = 0
    # phase), computed here from the contact directions and the error harmonics
    x = states[:, :model.n_modes]
    for j in meshes:
        e0 = float(np.sum(ct.error_cos[j]))            # e(0): cosines at phase 0
        delta = x @ ct.directions[j] - e0
        assert np.all(delta > ct.gap_hi[j])            # in contact on the drive flank
        assert np.ptp(delta) < 1e-9, np.ptp(delta)
    assert s.motion_class[0] == PERIODIC and s.period_n[0] == 1
    assert s.motion_class[0] != CHAOTIC
    assert s.metrics["resolution_period_n"][0] == 1
    assert s.metrics["qmax_res"][0] == pytest.approx(1e-9, rel=0.05)


def _two_frequency_oscillator(ratio=(21, 13), zeta=0.05):
    """q'' + 2 zeta q' + q = cos(W t) + 0.5 cos(r W t), r = 21/13: no contacts."""
    r = ratio[0] / ratio[1]
    z1 = np.zeros((2, 1))
    forcing = Forcing(F0=np.zeros(1), Fc=np.array([[1.0], [0.5]]), Fs=z1.copy())
    return ReducedModel(omega2=np.ones(1), damping=np.array([2 * zeta]),
                        coupling=LinearCoupling.none(1), forcing=forcing,
                        contacts=ContactSet.empty(1, 2), harmonic_orders=np.array([1.0, r]),
                        name="two-frequency oscillator"), r


def test_two_frequency_forced_linear_oscillator_is_multi_frequency_forced():
    zeta, W = 0.05, 0.7
    model, r = _two_frequency_oscillator(zeta=zeta)
    assert model.period_multiple == 13
    T = model.excitation_period(W)
    assert T == pytest.approx(13 * 2 * math.pi / W)

    def exact(t):
        out = 0.0
        for F, w in ((1.0, W), (0.5, r * W)):
            out += np.real(F * np.exp(1j * w * t) / (1 - w ** 2 + 2j * zeta * w))
        return out

    # the closed form at the base periods spreads: it would look quasi-periodic there
    base = exact(np.arange(64) * 2 * math.pi / W)
    t_fine = np.linspace(0.0, T, 200001)
    q = exact(t_fine)
    assert np.ptp(base) > 100 * 1e-3 * np.ptp(q)
    opts = IntegrationOptions(rtol=1e-9, atol=1e-12)
    s = sweep(model, [W], SweepOptions(directions=("up",), transient_periods=30,
                                       extra_transient_periods=0, record_periods=16,
                                       max_period=4, workers=1), options=opts)
    assert s.status[0] == 0
    assert s.motion_class[0] == MULTI_FREQUENCY and s.period_n[0] == 1
    assert s.motion_legend[MULTI_FREQUENCY] == "multi-frequency forced"
    # its stroboscopic samples (one per common period) are the closed form's at t = 0
    assert np.allclose(s.poincare[0], exact(0.0), atol=1e-6)
