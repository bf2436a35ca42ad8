"""Sweep results of the two-stage gearbox at the default reduction level and tolerance
(frequency-criterion master modes with static correction, m = 146; rtol by the accuracy
rule for [sweep] accuracy = 1e-3) against the former setting as the reference (the
scene's master counts, m = 162, rtol 1e-6), point by point on the same speeds.

* Points periodic in both runs (none on these grids: the rattle here is quasi-periodic or
  chaotic): extrema of the monitored mesh deformation within twice the requested error
  (1e-3 of its range), integration plus reduction error (the reduction's alone is within
  1e-3 on gear_pair: tests/verification/test_reduction_response.py).
* Points without a period: every mean contact metric (impacts per period, impact speed
  rms, contact fraction, rattle energy, unloaded elements) with error bars agrees within
  3 combined errors (batch-means errors of both runs and their tolerance errors,
  ``second_tolerance``); metrics with zero error bars (a flank never hit, a mesh always in
  contact) are equal, but for one rolling element at the edge of a bearing's load zone.
  A value without a batch-means error in one run (an impact speed from one impact) is not
  weighed.
The fast test takes two speeds; the slow one eight across the scene's range.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.analyses.study import integration_options, rtol_given
from vibrogear.config.scene import read_toml, scene_from_dict
from vibrogear.solvers.integrator.integrate import IntegrationOptions
from vibrogear.solvers.static import static_equilibrium
from vibrogear.solvers.sequential.sweep import sweep
from vibrogear.config.options import SweepOptions

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "configs" / "two_stage.toml"
ACCURACY = 1e-3


def _scene_asking_for_accuracy():
    """configs/two_stage.toml as shipped: it sets no [integration] rtol, so the sweep's
    tolerance comes from [sweep] accuracy (analyses.study.integration_options)."""
    scene = scene_from_dict(read_toml(SCENE), base_dir=SCENE.parent)
    assert not rtol_given(scene)
    return scene


def _run(scene, rpms, level, options):
    from vibrogear.models.gearbox.model import build_gearbox
    model = build_gearbox(scene, master_level=level).reduced
    sw = scene.sweep
    return model.n_modes, sweep(model, rpms, SweepOptions(directions=("up",), transient_periods=sw.transient_periods, extra_transient_periods=sw.extra_transient_periods, record_periods=sw.record_periods, max_period=sw.max_period, period_tol=sw.period_tol, workers=1, second_tolerance=True), options=options, u0=static_equilibrium(model, rpms[0]).u0)


def _compare(rpms):
    pytest.importorskip("dolfinx")              # the housing (cached after the first build)
    scene = _scene_asking_for_accuracy()
    assert scene.sweep.accuracy == ACCURACY
    m_new, new = _run(scene, rpms, "frequency",
                      integration_options(scene, record=True, period_tol=scene.sweep.period_tol))
    m_ref, ref = _run(scene, rpms, "count", IntegrationOptions(rtol=1e-6, atol=1e-12))
    assert (m_new, m_ref) == (146, 162) and new.ok.all() and ref.ok.all()
    assert new.rtol > 50 * ref.rtol                 # the rule's tolerance is the looser one
    # means over the window (not the largest impact speed: an extreme value, whose
    # batch-means spread is no error bar of the window's maximum)
    names = [k for k in ref.metrics if f"{k}_err" in ref.metrics and "_max_" not in k]
    assert any(k.startswith("impacts_drive") for k in names)
    compared = 0
    for i in range(rpms.size):
        if new.period_n[i] > 0 and ref.period_n[i] > 0:
            span = ref.qmax[i] - ref.qmin[i]
            for q in ("qmin", "qmax"):
                assert abs(getattr(new, q)[i] - getattr(ref, q)[i]) <= 2 * ACCURACY * span
            compared += 1
            continue
        for k in names:
            a, b = new.metrics[k][i], ref.metrics[k][i]
            errs = [d.metrics.get(f"{k}{s}", np.full(rpms.size, np.nan))[i]
                    for d in (new, ref) for s in ("_err", "_tol_err")]
            own = [d.metrics.get(f"{k}_err", np.full(rpms.size, np.nan))[i] for d in (new, ref)]
            errs = [e for e in errs if np.isfinite(e)]
            if len(errs) < 2 or not (np.isfinite(a) and np.isfinite(b)):
                continue                             # no error bars here: nothing to weigh
            if not np.all(np.isfinite(own)):
                # one run's value has no sampling error: an impact speed from a single
                # impact in the window (the housing's modes, rebuilt, take another rotation
                # in their degenerate pairs; a chaotic walk then meets a rare impact in one
                # run and not the other: measured at 1929 rpm, one impact in 32 periods)
                continue
            bar = np.sqrt(np.sum(np.square(errs)))
            if bar == 0.0 and k.startswith("unloaded_"):
                # rolling elements out of contact all the window long: the element at the
                # edge of the load zone may sit just inside or outside its clearance
                # depending on the reduction (measured: 6 / 7 at 1500 rpm)
                assert abs(a - b) <= 1.0, (rpms[i], k, a, b)
            elif bar == 0.0:
                assert a == b, (rpms[i], k, a, b)    # e.g. never or always in contact
            else:
                assert abs(a - b) <= 3.0 * bar, (rpms[i], k, a, b, bar)
            compared += 1
    assert compared >= 4 * rpms.size


def test_default_level_and_tolerance_agree_with_the_count_level_at_rtol_1e6():
    _compare(np.array([1600.0, 2300.0]))


@pytest.mark.slow
def test_default_level_and_tolerance_agree_over_the_speed_range():
    _compare(np.linspace(1500.0, 3000.0, 8))
