"""Pseudo-arclength continuation of the impact pair against independent references:
the exact piecewise-linear orbits, finite differences, and the sequential sweep."""
from __future__ import annotations

import numpy as np
import pytest
from finite_differences import fd_shooting_jacobian

from vibrogear.analyses.sweep.sweep import jumps
from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.periodic.continuation import (ContinuationOptions, PeriodicOrbitProblem,
                                            PseudoArclength, continuation)
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.periodic.shooting import periodic_flow
from vibrogear.status import Status
from vibrogear.solvers.sequential.sweep import sweep
from vibrogear.config.options import SweepOptions
from vibrogear.verification.impact_exact import ImpactParams
from vibrogear.verification.impact_orbits import periodic_orbit

# the default scene (configs/impact_pair.toml)
PAR = dict(zeta=0.015, kappa=0.5, f_m=0.55, f_p=0.12, b_r=1.0)
OPT = IntegrationOptions(rtol=1e-9, atol=1e-11)


@pytest.fixture(scope="module")
def model():
    return impact_pair_model(**PAR)


@pytest.fixture(scope="module")
def branches(model):
    p0 = 1.3
    warm = integrate(model, p0, np.array([1.05, 0.0]), 0.0, 300 * 2 * np.pi / p0, options=OPT)
    co = ContinuationOptions(param_min=0.45, param_max=1.3, ds=0.02, ds_max=0.05)
    res = continuation(PeriodicOrbitProblem(model, warm.u_end, p0, direction=-1),
                       PseudoArclength(integration=OPT, tol=1e-9), co)
    assert res.status == Status.LEFT_RANGE, res.message
    # the special points listed in the result are the labelled points of the branches
    assert [(s.label, s.param) for s in res.special_points] == [
        (p.label, p.param) for b in res.branches for p in b.points if p.label]
    return res.branches


def _labelled(branch, label):
    return [p for p in branch.points if p.label == label]


def test_branch_reaches_range_and_finds_main_folds(branches):
    b1 = branches[0]
    assert b1.status == Status.LEFT_RANGE and b1.points[-1].param < 0.45 + 0.05
    lps = sorted(p.param for p in _labelled(b1, "LP") if p.param > 0.8)
    assert len(lps) == 2 and lps[0] < lps[1]
    # the impact pair has a restoring force: no orbit family, no trivial multiplier
    assert all(p.neutral == 0 for b in branches for p in b.points)


def test_special_points_have_their_multiplier(branches):
    """At an LP a multiplier sits at +1, at a PD at -1 (located to the bisection tolerance)."""
    b1 = branches[0]
    for p in _labelled(b1, "LP"):
        assert np.min(np.abs(p.floquet - 1.0)) < 2e-2
    pds = _labelled(b1, "PD")
    assert len(pds) == 2
    for p in pds:
        assert np.min(np.abs(p.floquet + 1.0)) < 2e-2


def test_orbits_match_exact_piecewise_linear_solution(branches):
    """u0 and Floquet multipliers of branch points equal the exact orbit's."""
    ip = ImpactParams(**PAR)
    pts = [p for p in branches[0].points if not p.label][::25]
    assert len(pts) >= 4
    for p in pts:
        ex = periodic_orbit(ip, p.param, p.u0)
        assert ex.converged
        assert np.max(np.abs(ex.u0 - p.u0)) < 1e-6 * (1 + np.max(np.abs(p.u0)))
        assert np.max(np.abs(np.sort_complex(ex.floquet) - np.sort_complex(p.floquet))) < 1e-6
        assert abs(ex.q_max - p.qmax) < 1e-6 * (1 + abs(p.qmax))


def test_period_two_branch_is_genuine_and_exact(model, branches):
    assert len(branches) == 2
    b2 = branches[1]
    assert b2.n_periods == 2 and len(b2.points) > 5
    assert b2.status == Status.REJOINED and "rejoined" in b2.message
    pd = sorted(p.param for p in _labelled(branches[0], "PD"))
    ip = ImpactParams(**PAR)
    for p in [q for q in b2.points if not q.label][1:-1:4]:
        # inside the PD interval of the period-1 branch ...
        assert pd[0] - 1e-3 <= p.param <= pd[1] + 1e-3
        # ... not a period-1 orbit ...
        half = integrate(model, p.param, p.u0, 0.0, 2 * np.pi / p.param, options=OPT)
        assert np.linalg.norm(half.u_end - p.u0) > 1e-4
        # ... and the exact period-2 orbit
        ex = periodic_orbit(ip, p.param, p.u0, n_periods=2)
        assert ex.converged
        assert np.max(np.abs(ex.u0 - p.u0)) < 1e-6 * (1 + np.max(np.abs(p.u0)))


def test_shooting_jacobian_against_finite_differences(model):
    """dG/du0 (monodromy - I) and dG/dOmega (incl. the period change) vs central FD."""
    opt = IntegrationOptions(rtol=1e-12, atol=1e-13)
    u0, om = np.array([0.3, 0.2]), 0.9
    f = periodic_flow(model, om, u0, options=opt)
    assert f.trajectory.events >= 2
    J, dp = fd_shooting_jacobian(model, om, u0, opt)
    assert np.max(np.abs(J - f.dG_du0)) < 1e-6 * (1 + np.max(np.abs(J)))
    assert np.max(np.abs(dp - f.dG_dparam)) < 1e-5 * (1 + np.max(np.abs(dp)))


@pytest.fixture(scope="module")
def fold_sweep(model):
    params = np.arange(0.80, 1.0001, 0.004)
    return params, sweep(model, params, SweepOptions(transient_periods=150, record_periods=8, max_period=4, extra_transient_periods=0), options=IntegrationOptions(rtol=1e-8, atol=1e-10), u0=np.array([1.05, 0.0]))


def test_sweep_jumps_at_the_folds(branches, fold_sweep):
    """Up sweep falls at the upper fold, down sweep rises at the lower fold."""
    params, res = fold_sweep
    lp = sorted(p.param for p in _labelled(branches[0], "LP") if p.param > 0.8)
    up = res.direction == "up"
    j_up = jumps(res.param[up], res.qmax[up])
    j_dn = jumps(res.param[~up], res.qmax[~up])
    step = params[1] - params[0]
    assert len(j_up) == 1 and len(j_dn) == 1
    # the jump happens between the last point before the fold and the first beyond it
    assert abs(j_up[0] - lp[1]) <= step
    assert abs(j_dn[0] - lp[0]) <= step


def test_stable_sweep_orbits_lie_on_stable_branch_segments(branches, fold_sweep):
    _, res = fold_sweep
    b1 = [p for p in branches[0].points if not p.label]
    par = np.array([p.param for p in b1])
    q = np.array([p.qmax for p in b1])
    st = np.array([p.stable for p in b1])
    checked = 0
    for om, qs, n in zip(res.param, res.qmax, res.period_n):
        if n != 1:
            continue
        # stable branch segments that bracket this Omega, interpolated there
        cands = []
        for k in range(len(b1) - 1):
            lo, hi = sorted((par[k], par[k + 1]))
            if st[k] and st[k + 1] and lo <= om <= hi and hi > lo:
                w = (om - par[k]) / (par[k + 1] - par[k])
                cands.append((q[k] + w * (q[k + 1] - q[k]), abs(q[k + 1] - q[k])))
        assert cands, f"no stable branch segment at Omega = {om}"
        err = min(abs(qs - qb) / (1e-3 + dq) for qb, dq in cands)
        assert err < 1.0, (om, qs, cands)
        checked += 1
    assert checked > 30


def _exact_pd(point, lo, hi):
    """The exact PD of the period-1 branch between parameters lo and hi: bisection on
    det(M + I) = prod(mu + 1) of the exact orbit (exact piecewise-linear solution)."""
    ip = ImpactParams(**PAR)

    def g(om):
        ex = periodic_orbit(ip, om, point.u0)
        assert ex.converged
        return float(np.prod(ex.floquet + 1.0).real)

    g_lo = g(lo)
    assert np.sign(g_lo) != np.sign(g(hi))
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        if np.sign(g(mid)) == np.sign(g_lo):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _pd_checks(branch):
    """(located, within, exact) per PD of the period-1 branch."""
    pts = branch.points
    out = []
    for k, p in enumerate(pts):
        if p.label == "PD":
            lo, hi = sorted((pts[k - 1].param, pts[k + 1].param))
            out.append((p.param, p.located_within, _exact_pd(p, lo, hi)))
    return out


def test_special_points_lie_within_their_reported_bracket(model, branches, monkeypatch):
    """Every PD's reported ``located_within`` holds the exact crossing; where a crossing
    changes no stability (here forced: every orbit counted unstable), one regula-falsi
    orbit locates it and its wider bracket still holds the exact PD."""
    from vibrogear.solvers.periodic import continuation as cont

    exact = _pd_checks(branches[0])
    assert len(exact) == 2
    for p, within, ref in exact:
        assert 0 < within < 1e-3 and abs(p - ref) <= within + 1e-9
    monkeypatch.setattr(cont, "stability", lambda *a, **k: False)
    p0 = 1.3
    warm = integrate(model, p0, np.array([1.05, 0.0]), 0.0, 300 * 2 * np.pi / p0, options=OPT)
    co = ContinuationOptions(param_min=0.45, param_max=1.3, ds=0.02, ds_max=0.05,
                             period_doubling_branch=False)
    res = continuation(PeriodicOrbitProblem(model, warm.u_end, p0, direction=-1),
                       PseudoArclength(integration=OPT, tol=1e-9), co)
    coarse = _pd_checks(res.branches[0])
    assert len(coarse) == 2
    for (p, within, ref), (_, within_exact, _) in zip(coarse, exact):
        assert abs(p - ref) <= within + 1e-9
        assert within > within_exact            # one orbit: a wider bracket
    assert res.counters["flows"] < sum(b.counters["flows"] for b in branches[:1])


def test_corrector_start_from_the_tangents_qr_is_the_inverse():
    """tangent_and_start: the tangent of tangent() and H = inv([J; t^T]) from the same QR
    (an identity of the factors, checked against LAPACK's inverse); bordered Jacobians
    (more columns than the tangent has entries) fall back to H = None."""
    from vibrogear.solvers.periodic.corrector import tangent, tangent_and_start

    rng = np.random.default_rng(4)
    for n in (3, 40, 150):
        J = rng.standard_normal((n, n + 1))
        prev = rng.standard_normal(n + 1)
        t, H = tangent_and_start(J, prev)
        np.testing.assert_allclose(t, tangent(J, prev), atol=1e-14)
        assert t @ prev > 0
        A = np.vstack([J, t[None, :]])
        np.testing.assert_allclose(H, np.linalg.inv(A), rtol=1e-10, atol=1e-12)
    J = rng.standard_normal((6, 7))                 # n = 5 states, k = 1 bordered direction
    t, H = tangent_and_start(J, rng.standard_normal(6))
    assert H is None and t.size == 6
