"""Failures name their cause (issue 39, item 3): the integrator's tolerance advice never
repeats or recommends the tolerance in use or a looser one, and a divergence of a free or
unloaded model says so and advises no tolerance."""
from __future__ import annotations

import re

import numpy as np

from vibrogear.analyses.study import integration_options
from vibrogear.config import load_scene
from vibrogear.config.options import IntegrationOptions
from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel
from vibrogear.solvers.integrator.trust import DEFAULT_RTOL, _tighten, assess
from vibrogear.status import Status

SCENE = "configs/gear_pair.toml"


def _advice(opts) -> float:
    return float(re.search(r"e\.g\. to ([0-9.e+-]+)", _tighten(opts)).group(1))


def test_the_advice_loop_of_the_issue_is_broken():
    """What happened: a sweep at the accuracy rule's rtol advised 1e-07; at 1e-07 it
    advised 1e-09, the built-in default, which reads as "not given", so the sweep ran at the
    rule's rtol again and advised 1e-07 once more.  Here each advice is written into the
    scene as [integration] rtol and the sweep's options are taken again: every advised
    value is the one then used, strictly tighter than the last, never the default."""
    sc = load_scene(SCENE, ("integration.rtol=1e-9",))
    opts = integration_options(sc, record=True, section=sc.sweep)
    used = [opts.rtol]
    assert opts.rtol > DEFAULT_RTOL          # the default counts as not given: the rule's rtol
    for _ in range(4):
        advised = _advice(opts)
        assert advised < opts.rtol and advised != DEFAULT_RTOL
        sc = load_scene(SCENE, (f"integration.rtol={advised!r}",))
        opts = integration_options(sc, record=True, section=sc.sweep)
        assert opts.rtol == advised           # the advice is what runs next
        used.append(opts.rtol)
    assert all(b < a for a, b in zip(used, used[1:]))
    assert "not given" in _tighten(opts)
    # the step that looped: from 1e-07 the advice skips the default
    assert _advice(IntegrationOptions(rtol=1e-7, atol=1e-13)) == 1e-10


def _free_model() -> ReducedModel:
    """Mode 0: a rigid body under a constant force (no equilibrium); mode 1: an oscillator
    with a clearance contact."""
    m, H = 2, 1
    ct = ContactSet(directions=np.array([[0.0, 1.0]]), k_hi=np.array([1.0]),
                    k_lo=np.array([1.0]), gap_hi=np.array([0.5]), gap_lo=np.array([-0.5]),
                    exponent=np.array([1.0]), damping=np.array([0.0]),
                    stiffness_cos=np.zeros((1, H)), stiffness_sin=np.zeros((1, H)),
                    error_cos=np.zeros((1, H)), error_sin=np.zeros((1, H)), names=("mesh",))
    return ReducedModel(omega2=np.array([0.0, 1.0]), damping=np.array([0.0, 0.1]),
                        coupling=LinearCoupling.none(m),
                        forcing=Forcing(np.array([1.0, 0.0]), np.zeros((H, m)),
                                        np.zeros((H, m))),
                        contacts=ct, omega_per_param=1.0)


def test_a_free_model_diverges_with_its_cause_and_no_tolerance_advice():
    model = _free_model()
    opts = IntegrationOptions(rtol=1e-9, atol=1e-15)
    u0 = np.zeros(4)
    u_end = np.array([1e6, 1e6, 0.0, 0.0])
    status, msg, _ = assess(model, 1.0, u0, u_end, np.zeros((0, 4)), 0.0, 10.0, 1e-12, 0,
                            (np.nan, np.nan), opts)
    assert status == Status.DIVERGED
    assert "no static equilibrium under its mean load" in msg
    assert "vibrogear check" in msg
    assert "rtol" not in msg and "tighten" not in msg
