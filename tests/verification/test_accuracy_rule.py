"""The accuracy -> tolerance rule (vibrogear.analyses.study.integration_options): a gearbox
sweep or time response asked for an error of ``[sweep] accuracy`` in the monitored mesh
deformation (max |delta - delta_exact| over the record window / the range of delta) gets it.

Independent reference: the same settled gear_pair point integrated at rtol = 1e-10 (error
~1e-11 by the calibration's measured err ~ 0.24 rtol, five orders below what is checked), at a
speed (5500 rpm) that is not one of the calibration points.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.analyses.study import (ATOL_PER_RTOL, integration_options, rtol_given,
                                      tolerances_for)
from vibrogear.config.scene import read_toml, scene_from_dict
from vibrogear.models.gearbox.model import build_gearbox
from vibrogear.solvers.integrator.contact_eval import contact_history
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.static import static_equilibrium

ROOT = Path(__file__).resolve().parents[2]
GEAR_PAIR = ROOT / "configs" / "gear_pair.toml"
RPM = 5500.0
TRANSIENT, RECORD = 100, 20


def _scene(rtol=None, accuracy=None):
    data = read_toml(GEAR_PAIR)
    data["integration"].pop("rtol", None)
    data["integration"].pop("atol", None)
    if rtol is not None:
        data["integration"]["rtol"] = rtol
    if accuracy is not None:
        data["sweep"]["accuracy"] = accuracy
    return scene_from_dict(data, base_dir=GEAR_PAIR.parent)


@pytest.fixture(scope="module")
def reference():
    scene = _scene()
    model = build_gearbox(scene).reduced
    u0 = static_equilibrium(model, RPM).u0
    T = model.excitation_period(RPM)
    t_eval = np.linspace(TRANSIENT * T, (TRANSIENT + RECORD) * T, 32 * RECORD + 1)

    def delta(opts):
        tr = integrate(model, RPM, u0, 0.0, (TRANSIENT + RECORD) * T, t_eval=t_eval,
                       options=opts)
        assert tr.ok, tr.message
        return contact_history(model, RPM, tr.t, tr.u)[0][model.monitor], tr.steps

    ref, _ = delta(IntegrationOptions(rtol=1e-10, atol=1e-16, max_steps=10_000_000))
    return delta, ref


@pytest.mark.parametrize("accuracy", [1e-2, 1e-3, 1e-5])
def test_rule_delivers_the_accuracy_asked_for(reference, accuracy):
    delta, ref = reference
    scene = _scene(accuracy=accuracy)
    opts = integration_options(scene, record=True)
    assert opts.rtol == pytest.approx(tolerances_for(accuracy)[0])
    got, steps = delta(opts)
    err = np.max(np.abs(got - ref)) / np.ptp(ref)
    assert err <= accuracy
    # and the rule is not needlessly tight: a 30x looser accuracy would have been missed
    # or met only at the loosest rung (the error is within a factor ~100 of the target)
    assert err >= accuracy / 300 or opts.rtol == 1e-3


def test_explicit_rtol_wins_and_shooting_keeps_the_section():
    given = _scene(rtol=1e-6)
    assert rtol_given(given)
    assert integration_options(given, record=True).rtol == 1e-6
    free = _scene(accuracy=1e-3)
    assert not rtol_given(free)
    # shooting / continuation take the section as written
    assert integration_options(free).rtol == IntegrationOptions().rtol
    # the sweep's Poincare tolerance caps the rule
    loose = integration_options(free, record=True)
    assert integration_options(free, record=True, period_tol=1e-5).rtol == \
        min(loose.rtol, 1e-5)


def test_an_analysis_section_rtol_comes_first():
    """[continuation]/[reduction_accuracy]/[map]/[runup] rtol: that analysis's tolerance,
    whether or not [integration] rtol is given; a section without one follows the rule."""
    from types import SimpleNamespace
    for scene in (_scene(accuracy=1e-3), _scene(rtol=1e-6)):
        own = SimpleNamespace(rtol=3e-7)
        for record in (False, True):
            opts = integration_options(scene, record=record, section=own)
            assert (opts.rtol, opts.atol) == (3e-7, pytest.approx(3e-7 * ATOL_PER_RTOL))
        unset = SimpleNamespace(rtol=None)
        assert integration_options(scene, record=True, section=unset) == \
            integration_options(scene, record=True)
    # a section's own accuracy is the one the rule serves
    free = _scene(accuracy=1e-3)
    acc = SimpleNamespace(rtol=None, accuracy=1e-5)
    assert integration_options(free, record=True, section=acc).rtol == \
        pytest.approx(tolerances_for(1e-5)[0])


def test_tolerances_for_is_monotone_and_bounded():
    acc = np.logspace(-9, -0.5, 20)
    r = np.array([tolerances_for(a)[0] for a in acc])
    assert np.all(np.diff(r) >= 0)
    assert r.min() >= 1e-10 and r.max() <= 1e-3
    # the fitted error of the chosen rtol times the safety factor is the accuracy asked for
    assert tolerances_for(1e-3)[0] == pytest.approx((1e-3 / 2.38) ** (1 / 0.991), rel=1e-12)
