"""Nonlinear normal modes (``nnm``): the exact impact-pair backbone, the continuation against
it, a linear model's modes, identities of the conservative system, the [nnm] section and a
run through the CLI.

References: the closed-form backbone of :mod:`vibrogear.verification.impact_backbone`
(checked itself against scipy quadrature of the period integral and the symmetric formula
written out here), numpy eigenvalues of a linear model's stiffness, finite differences of
the energy, Liouville's formula det M = 1 and energy conservation along an integrated orbit.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from vibrogear.cli import main
from vibrogear.config.base import ConfigError
from vibrogear.config.sections.nnm import NnmConfig
from vibrogear.config.options import IntegrationOptions
from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel
from vibrogear.solvers.integrator.integrate import integrate
from vibrogear.solvers.periodic.nnm import NnmMethod, nnm_branch, rational_near
from vibrogear.solvers.periodic.nnm_problem import (conservative_model, energy,
                                                    energy_gradient, linear_modes_at)
from vibrogear.solvers.static import static_equilibrium
from vibrogear.verification.impact_backbone import ImpactBackbone

ROOT = Path(__file__).resolve().parents[2]
OPTS = IntegrationOptions(rtol=1e-10, atol=1e-12)


# ------------------------------------------------------------------ the exact reference
@pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")
@pytest.mark.parametrize("f_m", [0.0, 0.3, 0.55, -0.8])
def test_exact_backbone_equals_the_period_integral(f_m):
    """T = 2 int dq / sqrt(2 (L - V(q))) between the turning points, by adaptive quadrature
    (the square-root endpoint singularities removed by q = mid + half sin(theta))."""
    ex = ImpactBackbone(0.5, 1.0, f_m)
    for e in (1e-4, 0.01, 0.3, 2.0, 20.0):
        p = ex.at_energy(e)
        level = ex.potential(ex.static) + e
        assert ex.potential(p.q_min) == pytest.approx(level, rel=1e-12, abs=1e-12)
        assert ex.potential(p.q_max) == pytest.approx(level, rel=1e-12, abs=1e-12)
        mid, half = 0.5 * (p.q_max + p.q_min), 0.5 * (p.q_max - p.q_min)

        def g(th):
            q = mid + half * math.sin(th)
            return half * math.cos(th) / math.sqrt(max(2 * (level - ex.potential(q)), 1e-300))
        pts = [math.asin(max(-1, min(1, (s - mid) / half))) for s in (-1.0, 1.0)
               if p.q_min < s < p.q_max]
        T = 2 * quad(g, -math.pi / 2, math.pi / 2, points=pts or None, epsabs=0,
                     epsrel=1e-12, limit=200)[0]
        assert p.period == pytest.approx(T, rel=1e-9)


def test_exact_backbone_without_static_load():
    """f_m = 0: omega = sqrt(kappa) up to A = b, then T = 4 [asin(b / R_in) / sqrt(kappa) +
    pi / 2 - asin((b - c) / (A - c))], c = (1 - kappa) b, R_in = sqrt(2 V(A) / kappa)."""
    k, b = 0.3, 0.7
    ex = ImpactBackbone(k, b)
    for A in (0.1, 0.69):
        assert ex.at_q_max(A).omega == pytest.approx(math.sqrt(k), rel=1e-13)
    for A in (0.8, 1.5, 6.0):
        c = (1 - k) * b
        V = 0.5 * k * b * b + k * b * (A - b) + 0.5 * (A - b) ** 2
        T = 4 * (math.asin(b / math.sqrt(2 * V / k)) / math.sqrt(k)
                 + math.pi / 2 - math.asin((b - c) / (A - c)))
        p = ex.at_q_max(A)
        assert p.period == pytest.approx(T, rel=1e-12)
        assert p.q_min == pytest.approx(-A, rel=1e-12)


# ------------------------------------------------------------------ the continuation
def _impact_backbone(f_m, e_lo, e_hi, **kw):
    cm, _ = conservative_model(impact_pair_model(0.02, 0.5, f_m, 0.1, 1.0))
    us = static_equilibrium(cm, 1.0).u0
    om, phi, rigid = linear_modes_at(cm, us[:1])
    method = NnmMethod(energy_min=e_lo, energy_max=e_hi, integration=OPTS, **kw)
    return cm, nnm_branch(cm, us, om[0], phi[:, 0], method, rigid=rigid)


@pytest.mark.parametrize("f_m, e_hi", [(0.55, 1.25), (0.0, 20.0)])
def test_impact_pair_backbone_is_the_exact_one(f_m, e_hi):
    """100+ points over six decades of energy, through the contact loss (f_m = 0.55: the
    loaded pair softens) or the clearance's end (f_m = 0: it hardens): frequency and max |q|
    equal the closed form at the point's energy to 1e-6; every point is stable and its
    trivial multipliers are 1 (the one-DOF pair has no other)."""
    ex = ImpactBackbone(0.5, 1.0, f_m)
    e_on = ex.onset_energy()
    cm, br = _impact_backbone(f_m, 1e-3 * e_on, e_hi, ds=0.05, ds_max=0.05, max_points=400,
                              tol=1e-10)
    assert br.status.success, br.message
    assert len(br.points) >= 100
    assert br.points[-1].energy > e_hi
    err_w = max(abs(p.omega - ex.at_energy(p.energy).omega) for p in br.points)
    err_a = max(abs(p.amplitude - ex.at_energy(p.energy).amplitude) for p in br.points)
    assert err_w < 1e-6 and err_a < 1e-6, (err_w, err_a)
    # below the onset the linear frequency (outer stiffness 1, or kappa inside the clearance)
    lin = ex.linear_omega
    below = [p for p in br.points if p.energy < 0.99 * e_on]
    assert below and all(abs(p.omega - lin) < 1e-10 for p in below)
    assert all(p.stable for p in br.points)
    assert all(np.allclose(p.trivial, 1.0, atol=1e-4) for p in br.points)
    assert max(p.liouville_det_error for p in br.points) < 1e-6


def test_linear_model_nnms_are_its_modes():
    """A 3-DOF linear model (modal diagonal + a low-rank symmetric coupling, no contact):
    the NNM of each mode keeps its frequency, sqrt of an eigenvalue of the stiffness
    W + P^T Kc P from numpy, to 1e-10 over four decades of energy."""
    W = np.array([1.0, 2.5, 7.0])
    P = np.array([[1.0, -1.0, 0.0], [0.0, 1.0, 0.5]])
    Kc = np.array([[0.8, 0.1], [0.1, 0.4]])
    z = np.zeros((2, 2))
    model = ReducedModel(omega2=W, damping=np.full(3, 0.05),
                         coupling=LinearCoupling(P, Kc, z, z, z),
                         forcing=Forcing(np.array([0.2, 0.0, -0.1]), np.zeros((1, 3)),
                                         np.zeros((1, 3))),
                         contacts=ContactSet.empty(3, 1))
    cm, _ = conservative_model(model)
    ref = np.sqrt(np.linalg.eigvalsh(np.diag(W) + P.T @ Kc @ P))
    us = static_equilibrium(cm, 1.0).u0
    om, phi, rigid = linear_modes_at(cm, us[:3])
    for j in range(3):
        method = NnmMethod(energy_min=1e-4, energy_max=1.0, integration=OPTS, ds=0.3,
                           ds_max=1.0, phase="mode")
        br = nnm_branch(cm, us, om[j], phi[:, j], method, rigid=rigid, mode=j,
                        other_omegas=np.delete(om, j))
        assert br.status.success and br.points[-1].energy > 1.0
        w = br.array("omega")
        assert np.max(np.abs(w - ref[j])) < 1e-10 * ref[j]


def test_energy_gradient_and_conservation():
    """grad E against central differences; E constant along an integrated orbit of the
    conservative gear-like model (contacts separating and impacting)."""
    cm, _ = conservative_model(impact_pair_model(0.05, 0.5, 0.55, 0.2, 1.0, 0.3))
    rng = np.random.default_rng(1)
    for _ in range(5):
        u = rng.normal(size=2) * 2
        g = energy_gradient(cm, u)
        fd = [(energy(cm, u + h) - energy(cm, u - h)) / 2e-6 for h in np.eye(2) * 1e-6]
        assert np.allclose(g, fd, rtol=1e-6, atol=1e-8)
    u0 = np.array([3.0, 0.4])
    tr = integrate(cm, 1.0, u0, 0.0, 40.0, t_eval=np.linspace(0, 40, 400), options=OPTS)
    assert tr.ok and tr.events > 4
    e = [energy(cm, u) for u in tr.u]
    assert np.ptp(e) < 1e-8 * energy(cm, u0)


def test_conservative_model_drops_damping_and_excitation_only():
    m = impact_pair_model(0.05, 0.5, 0.55, 0.2, 1.0, 0.3)
    cm, skew = conservative_model(m)
    assert skew == 0.0 and np.all(cm.damping == 0) and np.all(cm.contacts.damping == 0)
    assert np.all(cm.forcing.Fc == 0) and np.array_equal(cm.forcing.F0, m.forcing.F0)
    assert np.array_equal(cm.contacts.gap_hi, m.contacts.gap_hi)


def test_rational_near_and_fold_labels():
    from vibrogear.solvers.periodic.nnm import _fold_label
    assert rational_near(3.004, 5, 0.01) == 3
    assert str(rational_near(0.6655, 5, 0.01)) == "2/3"
    assert rational_near(2.71828, 3, 0.01) is None
    m = NnmMethod(energy_min=1.0, energy_max=2.0, rational_tol=0.015)
    # 3.0275 (1 % off 3:1) and 0.6039 (0.65 % off 3:5): the lower order is the label
    assert _fold_label(1.0, np.array([3.0275, 0.6039]), m) == "IR 3:1"
    assert _fold_label(1.0, np.array([2.71828]), m) == "LP"


# ------------------------------------------------------------------ the [nnm] section
def _cfg(**kw):
    from vibrogear.config.base import build
    return build(NnmConfig, {"energy_min": 0.1, "energy_max": 2.0, **kw}, "nnm")


@pytest.mark.parametrize("kw, field", [
    ({"mode": 1, "mesh": "G1"}, "nnm.mesh"),
    ({"energy_max": None}, "nnm.energy_max"),
    ({"energy_max": 0.05}, "nnm.energy_max"),
    ({"amplitude_min": 1.0, "amplitude_max": 2.0}, "nnm.amplitude_min"),
    ({"ds": 1.0, "ds_max": 0.5}, "nnm.ds"),
    ({"energy_unit": "kJ"}, "nnm.energy_unit"),
    ({"rtol": 0.1}, "nnm.rtol"),
])
def test_bad_nnm_section(kw, field):
    data = {"energy_min": 0.1, "energy_max": 2.0, **kw}
    data = {k: v for k, v in data.items() if v is not None}
    from vibrogear.config.base import build
    with pytest.raises(ConfigError) as exc:
        build(NnmConfig, data, "nnm")
    assert exc.value.path == field


def test_nnm_through_the_cli(tmp_path):
    """``vibrogear nnm`` on the impact pair: the files and keys of the README, the orbit at a
    chosen energy, the summary's onset energy ((q_s - b)^2 / 2, q_s = f_m + (1 - kappa) b)."""
    out = tmp_path / "ip"
    code = main(["nnm", str(ROOT / "configs" / "impact_pair_nnm.toml"), "--out", str(out),
                 "--quiet", "--set", "nnm.energy_max=100"])
    assert code == 0
    for f in ("nnm.npz", "nnm.csv", "nnm_fep.png", "nnm_backbone.png"):
        assert (out / f).stat().st_size > 500, f
    with np.load(out / "nnm.npz") as z:
        for k in ("omega", "amplitude", "energy", "period", "stable", "u0", "branch", "label"):
            assert k in z.files
        assert z["shape_x"].shape[0] == 1
    s = json.loads((out / "summary.json").read_text())["results"]["nnm"]
    assert s["branches"][0]["onset_energy_model_units"] == pytest.approx(0.05 ** 2 / 2)


def test_amplitude_range_ends_at_its_excursion(tmp_path):
    """An amplitude range: the branch leaves its range at the first point whose excursion of
    the monitored deformation from the static state exceeds amplitude_max, and no earlier."""
    text = (ROOT / "configs" / "impact_pair_nnm.toml").read_text()
    text = "\n".join(line for line in text.splitlines()
                     if not line.startswith(("energy_min", "energy_max")))
    scene = tmp_path / "amp.toml"
    scene.write_text(text.replace("[nnm]", "[nnm]\namplitude_min = 0.01\namplitude_max = 0.2", 1))
    out = tmp_path / "out"
    assert main(["nnm", str(scene), "--out", str(out), "--quiet"]) == 0
    (b,) = json.loads((out / "summary.json").read_text())["results"]["nnm"]["branches"]
    assert b["status"] == "left_range" and "amplitude_max" in b["message"]
    with np.load(out / "nnm.npz") as z:
        exc = z["excursion"]
    assert exc[-1] > 0.2 and np.all(exc[:-1] <= 0.2)


def test_the_steps_rule_is_written_once_and_names_the_field():
    """[nnm] and the solver's settings share :class:`NnmSteps`: one ds rule, one field name,
    and the section builds the solver's NnmMethod with every step it holds."""
    from vibrogear.config.base import build
    from vibrogear.config.options import NnmSteps

    assert issubclass(NnmConfig, NnmSteps) and issubclass(NnmMethod, NnmSteps)
    with pytest.raises(ConfigError) as exc:
        NnmMethod(energy_min=1.0, energy_max=2.0, ds=0.5, ds_max=0.3)
    assert exc.value.path == "ds"
    with pytest.raises(ConfigError) as exc:
        NnmMethod(energy_min=2.0, energy_max=1.0)
    assert exc.value.path == "energy_max"
    cfg = build(NnmConfig, {"energy_min": 0.1, "energy_max": 2.0, "ds": 0.2, "ds_max": 0.4,
                            "phase": "mode", "tol": 1e-6, "rational_max": 7}, "nnm")
    opts = IntegrationOptions(rtol=1e-8, atol=1e-10)
    m = cfg.method(energy_min=1.0, energy_max=3.0, integration=opts, delta_static=0.5)
    assert (m.ds, m.ds_max, m.phase, m.rational_max, m.tol, m.delta_static, m.excursion_max,
            m.integration, m.energy_min, m.energy_max) == \
        (0.2, 0.4, "mode", 7, 1e-6, 0.5, None, opts, 1.0, 3.0)
    assert {k: getattr(m, k) for k in cfg.steps()} == cfg.steps()


def test_a_bad_ds_exits_2_naming_the_field(tmp_path, capsys):
    out = tmp_path / "out"
    scene = str(ROOT / "configs" / "impact_pair_nnm.toml")
    assert main(["nnm", scene, "--out", str(out), "--quiet", "--set", "nnm.ds=0.5"]) == 2
    err = capsys.readouterr().err
    assert "invalid input: nnm.ds: must satisfy ds_min <= ds <= ds_max" in err, err
    assert not out.exists()


def test_nnm_takes_its_integrator_options_from_the_one_tolerance_rule(tmp_path, monkeypatch):
    """The options the backbone is integrated with are ``integration_options(scene,
    section=[nnm], study)``: rtol from [nnm], atol = 1e-2 rtol on the impact pair."""
    from vibrogear.analyses import nnm as nnm_analysis
    from vibrogear.analyses.study import build_study, integration_options
    from vibrogear.config import load_scene
    from vibrogear.pipeline.outcome import RunContext

    class Seen(Exception):
        pass

    def spy(model, u_static, omega0, phi, method, **kw):
        raise Seen(method)

    monkeypatch.setattr(nnm_analysis, "nnm_branch", spy)
    scene = load_scene(ROOT / "configs" / "impact_pair_nnm.toml", ("nnm.rtol=2e-8",))
    study = build_study(scene)
    with pytest.raises(Seen) as exc:
        nnm_analysis.run(study, scene, RunContext(out=tmp_path, quiet=True))
    used = exc.value.args[0].integration
    assert used == integration_options(scene, section=scene.nnm, study=study)
    assert (used.rtol, used.atol) == pytest.approx((2e-8, 2e-10), rel=1e-12)
    assert used.max_steps == scene.integration.max_steps
