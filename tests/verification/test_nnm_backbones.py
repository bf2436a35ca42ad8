"""NNM backbones against independent references: the gear pair's mesh mode against its
linearised modes and the contact-loss energy computed from the static state alone, and the
impact pair's lightly damped forced primary resonance against the backbone.

References: :func:`vibrogear.solvers.linear.linear_modes` (the damped/undamped modes of the
original model linearised at its static equilibrium, a code path the NNM solver does not
use), the contact-loss energy E_on = omega^2 a_on^2 / 2, a_on = (delta_s - g) / |c . phi|
of the linear mode, and the closed-form backbone of
:mod:`vibrogear.verification.impact_backbone`.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.analyses.study import build_study
from vibrogear.config import load_scene
from vibrogear.config.options import ContinuationOptions, IntegrationOptions
from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.linear import linear_modes
from vibrogear.solvers.periodic.continuation import (PeriodicOrbitProblem, PseudoArclength,
                                                     continuation)
from vibrogear.solvers.periodic.nnm import NnmMethod, nnm_branch
from vibrogear.solvers.periodic.nnm_problem import conservative_model, linear_modes_at
from vibrogear.solvers.static import static_equilibrium
from vibrogear.verification.impact_backbone import ImpactBackbone

ROOT = Path(__file__).resolve().parents[2]


def test_gear_pair_mesh_mode_backbone():
    """gear_pair's G1 mesh mode to 3.2 x its contact-loss energy: at low energy the
    frequency is the linearised model's mode (1e-8); below the contact-loss energy it stays
    there (1e-10) and the orbit's minimum mesh deformation is delta_s - a |c . phi| of the
    linear mode; the contact-loss energy extrapolated from those orbits equals E_on from the
    static state (1e-6), the first orbit with a loss lies above it and the last without
    below; beyond it the mode softens; within 30 s."""
    study = build_study(load_scene(ROOT / "configs" / "gear_pair.toml"))
    cm, _ = conservative_model(study.model)
    us = static_equilibrium(cm, 0.0).u0
    m = cm.n_modes
    om, phi, rigid = linear_modes_at(cm, us[:m])
    ct = cm.contacts
    c, k = ct.directions[0], ct.k_hi[0]
    j = int(np.argmax(k * (c @ phi) ** 2 / om ** 2))          # the mesh mode
    # the independent linearisation: the original (damped) model's undamped frequencies
    st = static_equilibrium(study.model, 0.0)
    ref = linear_modes(study.model, st.u0, 0.0).undamped * 2 * np.pi
    w_ref = ref[np.argmin(np.abs(ref - om[j]))]
    d_s = float(c @ us[:m])
    cphi = abs(float(c @ phi[:, j]))
    a_on = (d_s - ct.gap_hi[0]) / cphi
    e_on = 0.5 * w_ref ** 2 * a_on ** 2
    method = NnmMethod(energy_min=0.01 * e_on, energy_max=3.2 * e_on,
                       integration=IntegrationOptions(rtol=1e-9, atol=1e-15), tol=1e-7,
                       ds=0.1, ds_max=0.3)
    br = nnm_branch(cm, us, om[j], phi[:, j], method, rigid=rigid, mode=j,
                    other_omegas=np.delete(om, j))
    assert br.status.success, br.message
    assert br.points[-1].energy >= 3.0 * e_on
    P = br.points
    assert abs(P[0].omega - w_ref) < 1e-8 * w_ref
    lin = [p for p in P if p.energy < e_on]
    loss = [p for p in P if p.energy > e_on]
    assert len(lin) >= 4 and loss
    for p in lin:
        assert abs(p.omega - w_ref) < 1e-10 * w_ref
        assert p.qmin == pytest.approx(d_s - np.sqrt(2 * p.energy) / w_ref * cphi,
                                       rel=1e-7)
    # qmin = d_s - cphi sqrt(2 E) / w on the linear orbits: its zero from the last two
    s = np.sqrt([lin[-2].energy, lin[-1].energy])
    q = np.array([lin[-2].qmin, lin[-1].qmin])
    s0 = s[1] - q[1] * (s[1] - s[0]) / (q[1] - q[0])
    assert s0 ** 2 == pytest.approx(e_on, rel=1e-6)
    assert lin[-1].qmin > ct.gap_hi[0] > loss[0].qmin
    # softening once the mesh separates
    w = np.array([p.omega for p in loss])
    assert w[-1] < w_ref * (1 - 1e-3) and np.all(w < w_ref)


@pytest.mark.slow
def test_forced_primary_resonance_peaks_on_the_backbone():
    """zeta = 1e-3, f_p = 0.002: the forced period-1 branch's largest max q (the peak of
    the turned-over primary resonance, continuation) lies on the backbone: its frequency
    equals the NNM continuation's (interpolated at the same max q) and the closed form's to
    1e-2 (measured 3e-7)."""
    kap, b, fm = 0.5, 1.0, 0.55
    mod = impact_pair_model(1e-3, kap, fm, 0.002, b)
    opts = IntegrationOptions(rtol=1e-10, atol=1e-12)
    us = static_equilibrium(mod, 0.7).u0
    res = continuation(PeriodicOrbitProblem(mod, us, 0.7, direction=1),
                       PseudoArclength(integration=opts, tol=1e-10),
                       ContinuationOptions(param_min=0.7, param_max=1.2, ds=0.01, ds_max=0.02,
                                           max_points=3000))
    br = res.branches[0]
    qmax = br.array("qmax")
    k = int(np.argmax(qmax))
    peak_w, peak_q = br.array("param")[k], qmax[k]
    ex = ImpactBackbone(kap, b, fm)
    assert abs(peak_w - ex.at_q_max(peak_q).omega) < 1e-2
    cm, _ = conservative_model(mod)
    om, phi, rigid = linear_modes_at(cm, us[:1])
    nb = nnm_branch(cm, us, om[0], phi[:, 0],
                    NnmMethod(energy_min=1e-6, energy_max=2.0, integration=opts, tol=1e-10,
                              ds_max=0.05), rigid=rigid)
    q_bb, w_bb = nb.array("qmax"), nb.array("omega")
    assert q_bb.min() < peak_q < q_bb.max()
    assert abs(peak_w - np.interp(peak_q, q_bb, w_bb)) < 1e-2
