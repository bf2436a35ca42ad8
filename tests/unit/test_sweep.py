"""Sequential continuation (sweep): classification, linear limit, period 2 against scipy,
hysteresis, failed points, resume, files and plots."""
from __future__ import annotations

import dataclasses
import csv
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel
from vibrogear.analyses.sweep.sweep import PARTIAL_NAME, resumable_sweep
from vibrogear.pipeline.resume import read_items
from vibrogear.report.sweep_files import csv_header, read_sweep_npz, write_sweep
from vibrogear.solvers.integrator.integrate import IntegrationOptions
from vibrogear.solvers.sequential.sweep import classify_period, count_clusters, sweep
from vibrogear.config.options import SweepOptions

# impact pair with a stiff outer spring (hardening): a resonance that bends to the
# right, coexisting large / small responses for Omega ~ 0.7-0.9, period 2 near 0.45-0.5
HYST = dict(zeta=0.015, kappa=0.2, f_m=0.1, f_p=0.2, b_r=1.0)
HYST_GRID = np.round(np.arange(0.65, 0.951, 0.05), 10)
OPTS = IntegrationOptions(rtol=1e-9, atol=1e-11)
SETTINGS = SweepOptions(transient_periods=120, extra_transient_periods=0, record_periods=12,
                        max_period=4, period_tol=1e-5)


def _eq(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


@pytest.fixture(scope="module")
def hyst_result():
    return sweep(impact_pair_model(**HYST), HYST_GRID, SETTINGS, options=OPTS)


# ---------------------------------------------------------------- classifier (synthetic)

def test_classify_synthetic_periods():
    rng = np.random.default_rng(1)
    cycle = rng.normal(size=(3, 4))
    for n in (1, 2, 3):
        samples = np.tile(cycle[:n], (12 // n + 1, 1))[:12]
        samples = samples + 1e-9 * rng.normal(size=samples.shape)
        got, defect = classify_period(samples, 8, 1e-6, split=2)
        assert got == n and defect < 1e-6
        assert count_clusters(samples, 1e-3, split=2) == n
    # quasi-periodic: rotation by an irrational angle never repeats
    k = np.arange(40)
    qp = np.column_stack([np.cos(2 * np.pi * k * (np.sqrt(5) - 1) / 2),
                          np.sin(2 * np.pi * k * (np.sqrt(5) - 1) / 2)])
    assert classify_period(qp, 8, 1e-5)[0] == 0
    assert count_clusters(qp, 1e-3) > 20
    # a slowly decaying transient must not pass as period 3 by aliasing
    decaying = 1.0 + 3e-5 * np.cos(2.1 * k[:12]) * 0.97 ** k[:12]
    assert classify_period(decaying, 8, 1e-5)[0] == 0
    n_nan, d_nan = classify_period(np.full((5, 2), np.nan), 4, 1e-5)
    assert n_nan == 0 and math.isnan(d_nan)


# ---------------------------------------------------------------- linear limit

def test_linear_limit_matches_frf():
    zeta, kappa, f_p = 0.05, 0.5, 0.2
    model = impact_pair_model(zeta, kappa, 0.0, f_p, 1e6)
    W = np.array([0.4, 0.7, 0.9])
    r = sweep(model, W, SweepOptions(directions=("up",), transient_periods=100, record_periods=6, max_period=3, period_tol=1e-6, extra_transient_periods=0), options=OPTS)
    amp = f_p / np.sqrt((kappa - W ** 2) ** 2 + (2 * zeta * W) ** 2)
    np.testing.assert_allclose(r.qmax - r.qmin, 2 * amp, rtol=1e-6)
    np.testing.assert_allclose(r.qmax, amp, rtol=1e-6)
    assert np.all(r.period_n == 1) and np.all(r.impacts == 0) and np.all(r.clusters == 1)
    assert r.status_code == 0 and np.all(r.defect < 1e-6)
    assert r.error_estimate["rtol"] == OPTS.rtol


def test_model_without_contacts_uses_the_samples():
    zeta, kappa, f_p, W = 0.05, 0.5, 0.2, 0.6
    base = impact_pair_model(zeta, kappa, 0.0, f_p, 1.0)
    model = ReducedModel(base.omega2, base.damping, base.coupling, base.forcing,
                         ContactSet.empty(1, 1))
    r = sweep(model, [W], SweepOptions(directions=("up",), transient_periods=100, record_periods=4, max_period=2, extra_transient_periods=0), options=OPTS)
    X = f_p / (kappa - W ** 2 + 2j * zeta * W)           # q = Re(X exp(i W t))
    assert r.status_code == 0 and r.period_n[0] == 1 and r.impacts[0] == 0
    np.testing.assert_allclose(r.poincare[0], X.real, rtol=1e-6)
    assert X.real * (1 - 1e-6) <= r.qmax[0] <= abs(X) * (1 + 1e-6)


# ---------------------------------------------------------------- period 2 vs scipy

def _scipy_impact_flow(u, t0, t1, W, zeta, kappa, f_m, f_p, b_r):
    """Piecewise-linear impact pair with DOP853 (tight tolerances), restarted at every
    switch located by a terminal event: independent of vibrogear."""
    def region(q):
        return 1 if q > b_r else (-1 if q < -b_r else 0)

    t, u, reg = t0, np.array(u, float), region(u[0])
    for _ in range(100_000):
        def rhs(tt, y, reg=reg):
            g = (1 - kappa) * (y[0] - reg * b_r) if reg else 0.0
            return [y[1], f_m + f_p * np.cos(W * tt) - 2 * zeta * y[1] - kappa * y[0] - g]
        events = []
        for side in (1, -1):
            if reg in (0, side):
                ev = (lambda tt, y, s=side: y[0] - s * b_r)
                ev.terminal = True
                ev.direction = -side if reg == side else side
                events.append(ev)
        s = solve_ivp(rhs, (t, t1), u, method="DOP853", rtol=1e-11, atol=1e-12,
                      events=events)
        t, u = s.t[-1], s.y[:, -1]
        if s.status != 1:
            return u
        reg = (1 if u[1] > 0 else -1) if reg == 0 else 0
    raise RuntimeError("too many switches")


def test_period_two_confirmed_by_scipy():
    W, n_tr, R = 0.5, 100, 8
    model = impact_pair_model(**HYST)
    r = sweep(model, [W], SweepOptions(directions=("up",), transient_periods=n_tr, record_periods=R, max_period=4, period_tol=1e-6, extra_transient_periods=0), options=IntegrationOptions(rtol=1e-10,
                                                                         atol=1e-12))
    assert r.period_n[0] == 2 and r.clusters[0] == 2 and r.impacts[0] > 0
    # the transient stopped once the stroboscopic map had converged, inside the budget
    n_tr = int(r.transient_used[0])
    assert r.settled_by[0] == "map" and 0 < n_tr < 100
    T = 2 * np.pi / W
    u = _scipy_impact_flow(np.zeros(2), 0.0, n_tr * T, W, **HYST)
    P = []
    for k in range(R):
        u = _scipy_impact_flow(u, (n_tr + k) * T, (n_tr + k + 1) * T, W, **HYST)
        P.append(u.copy())
    P = np.array(P)
    assert np.max(np.abs(P[2:] - P[:-2])) < 1e-7          # period 2 ...
    assert np.max(np.abs(P[1:] - P[:-1])) > 0.1           # ... and not period 1
    np.testing.assert_allclose(r.poincare[0], P[:, 0], atol=1e-6)
    assert r.qmin[0] <= P[:, 0].min() and r.qmax[0] >= P[:, 0].max()


# ---------------------------------------------------------------- hysteresis

def test_up_and_down_jump_at_different_parameters(hyst_result):
    r = hyst_result
    up = r.direction == "up"
    dn = r.direction == "down"
    a_up = dict(zip(r.param[up], (r.qmax - r.qmin)[up]))
    a_dn = dict(zip(r.param[dn], (r.qmax - r.qmin)[dn]))
    grid = sorted(a_up)
    jumps_up = [grid[i + 1] for i in range(len(grid) - 1)
                if a_up[grid[i + 1]] < 0.5 * a_up[grid[i]]]
    jumps_dn = [grid[i] for i in range(len(grid) - 1)
                if a_dn[grid[i]] > 2.0 * a_dn[grid[i + 1]]]
    assert len(jumps_up) == 1 and len(jumps_dn) == 1
    assert jumps_up[0] > jumps_dn[0] + 0.1             # up jumps down later than down jumps up
    coexist = [w for w in grid if a_up[w] > 2.0 * a_dn[w]]
    assert len(coexist) >= 2                            # two stable responses there
    assert r.status_code == 0 and r.steps > 0 and r.rhs_calls > r.steps


# ---------------------------------------------------------------- failures

def test_failed_point_reported_and_sweep_goes_on(tmp_path, hyst_result):
    # the limit is per integrator call: a transient block is 8 periods here
    per_period = np.array([rec.steps / (rec.transient_used + SETTINGS.record_periods)
                           for rec in hyst_result.records])
    limit = int(8 * 0.5 * (per_period.min() + per_period.max()))
    assert 8 * per_period.min() < limit < 8 * per_period.max()
    opts = IntegrationOptions(rtol=OPTS.rtol, atol=OPTS.atol, max_steps=limit)
    r = sweep(impact_pair_model(**HYST), HYST_GRID, SETTINGS, options=opts)
    bad = r.status != 0
    assert np.any(bad) and np.any(~bad) and r.status_code == 1
    assert np.all(r.status[bad] == -1)
    assert all("maximum number of steps" in r.message[i] for i in np.flatnonzero(bad))
    assert np.all(np.isnan(r.qmin[bad])) and np.all(r.period_n[bad] == 0)
    assert np.all(np.isfinite(r.qmin[~bad]))
    first_bad = int(np.flatnonzero(bad)[0])
    assert np.any(~bad[first_bad + 1:])                 # the sweep went on
    paths = write_sweep(r, tmp_path)
    z = read_sweep_npz(paths["npz"])
    for k, v in z.items():
        if v.dtype.kind == "f":
            assert np.all(np.isfinite(v)), k
    assert not np.any(z["ok"][bad]) and np.all(z["status"] == r.status)
    text = paths["csv"].read_text()
    assert "nan" not in text.lower() and "inf" not in text.lower()
    rows = list(csv.DictReader(paths["csv"].open()))
    assert len(rows) == r.param.size
    assert all(rows[i]["qmin"] == "" for i in np.flatnonzero(bad))


def test_bad_parameter_is_a_failed_point_not_an_exception():
    r = sweep(impact_pair_model(**HYST), [0.0, 0.9], SweepOptions(directions=("up",), transient_periods=5, record_periods=2, max_period=1, extra_transient_periods=0), options=OPTS)
    assert r.status[0] < 0 and r.status[1] == 0 and r.status_code == 1


# ---------------------------------------------------------------- resume

def test_resume_gives_identical_results(tmp_path, hyst_result):
    model = impact_pair_model(**HYST)
    part = tmp_path / PARTIAL_NAME
    half = HYST_GRID.size + 2                           # into the down sweep
    seen = []
    first, store, resumed = resumable_sweep(
        model, HYST_GRID, tmp_path, options=OPTS, root=True,
        callback=lambda rec: (seen.append(rec), len(seen) < half)[1], settings=SETTINGS)
    assert first.status_code == 2 and first.param.size == half and resumed == 0
    with part.open("a") as fh:                          # a torn line from the kill
        fh.write('{"kind":"point","direction":"do')
    assert len(read_items(part)) == half
    new = []
    res, store, resumed = resumable_sweep(model, HYST_GRID, tmp_path, options=OPTS, root=True,
                                          callback=new.append, settings=SETTINGS)
    assert resumed == half and len(new) == 2 * HYST_GRID.size - half
    for name in ("param", "direction", "index", "qmin", "qmax", "poincare", "period_n",
                 "impacts", "defect", "clusters", "status", "u_end", "motion_class",
                 "lyapunov", "lyapunov_ci", "transient_used", "settled_by"):
        assert _eq(getattr(res, name), getattr(hyst_result, name)), name
    assert sorted(res.metrics) == sorted(hyst_result.metrics)
    for name, v in res.metrics.items():
        assert _eq(v, hyst_result.metrics[name]), name
    assert len(read_items(part)) == 2 * HYST_GRID.size


@pytest.mark.parametrize("change", ["physics", "grid", "options", "settings"])
def test_partial_file_of_another_run_is_set_aside(tmp_path, change):
    """A partial file is reused only for the same physics, grid, integrator options and
    sweep settings; otherwise it is renamed aside (kept) and the sweep starts clean."""
    grid = HYST_GRID[:3]
    kw = dict(settings=SweepOptions(directions=("up",), transient_periods=20, extra_transient_periods=0,
                                    record_periods=4, max_period=2), options=OPTS)
    stop = iter([True, False])                           # stop after the second point
    resumable_sweep(impact_pair_model(**HYST), grid, tmp_path, root=True,
                    callback=lambda rec: next(stop), **kw)
    model = impact_pair_model(**HYST)
    if change == "physics":                              # a changed damping, same name
        model = impact_pair_model(**{**HYST, "zeta": 0.016})
    elif change == "grid":
        grid = grid + 1e-3
    elif change == "options":
        kw["options"] = IntegrationOptions(rtol=1e-9, atol=1e-11, max_steps=123_456)
    else:
        kw["settings"] = dataclasses.replace(kw["settings"], record_periods=5)
    new = []
    res, store, resumed = resumable_sweep(model, grid, tmp_path, root=True,
                                          callback=new.append, **kw)
    assert resumed == 0 and len(new) == grid.size
    assert "set aside" in store.note and change in store.note
    assert (tmp_path / f"{PARTIAL_NAME}.stale-1").exists()
    fresh = sweep(model, grid, **kw)
    assert _eq(res.qmax, fresh.qmax) and _eq(res.u_end, fresh.u_end)


# ---------------------------------------------------------------- files and plot

def test_files_and_plot(tmp_path, hyst_result):
    from matplotlib.figure import Figure

    from vibrogear.report.figure import save_figure
    from vibrogear.report.plots.sweep import plot_bifurcation

    paths = write_sweep(hyst_result, tmp_path)
    z = read_sweep_npz(paths["npz"])
    for key in ("param", "direction", "qmin", "qmax", "poincare", "period_n", "impacts"):
        assert key in z
    assert z["poincare"].shape == (2 * HYST_GRID.size, SETTINGS.record_periods)
    assert set(z["direction"].tolist()) == {"up", "down"}
    assert np.array_equal(z["period_n"], hyst_result.period_n)
    assert not list(tmp_path.glob(".*.tmp"))            # atomic writes leave no temp files
    rows = list(csv.DictReader(paths["csv"].open()))
    assert [float(r["Omega"]) for r in rows] == z["param"].tolist()   # the npz keeps "param"
    fig = plot_bifurcation(z, bounds=(-1.0, 1.0))
    assert isinstance(fig, Figure)                       # drawn, not written
    assert not list(tmp_path.glob("bifurcation*"))
    out = save_figure(fig, tmp_path / "bifurcation")
    assert [p.suffix for p in out] == [".png", ".svg"]
    assert all(p.stat().st_size > 1000 for p in out)
    assert math.isfinite(float(hyst_result.wall_time))


def test_csv_header_names_the_parameter_and_units():
    cols = ["direction", "param", "qmin", "qmax_tol_err", "impacts", "status", "wall_time",
            "lyapunov_lo", "transient_used", "impacts_back_G2", "impact_velocity_rms_G1_err",
            "rattle_G2", "contact_fraction_G1", "unloaded_A", "period_n_G1", "tol_err_measured"]
    gearbox = csv_header(cols, param_name="rpm", param_unit="rpm", length_unit="m",
                         time_unit_s=2.5e-5)
    assert gearbox == [
        "direction", "rpm", "qmin [m]", "qmax_tol_err [m]", "impacts [1/period]", "status",
        "wall_time [s]", "lyapunov_lo [1/(2.5e-05 s)]", "transient_used [periods]",
        "impacts_back_G2 [1/period]", "impact_velocity_rms_G1_err [m/s]", "rattle_G2 [J]",
        "contact_fraction_G1", "unloaded_A", "period_n_G1", "tol_err_measured"]
    # the impact pair is nondimensional: its lengths, rates and times carry no unit
    pair = csv_header(cols, param_name="Omega")
    assert pair[:6] == ["direction", "Omega", "qmin", "qmax_tol_err", "impacts [1/period]",
                        "status"]
    assert pair[7] == "lyapunov_lo" and pair[10:12] == ["impact_velocity_rms_G1_err",
                                                        "rattle_G2"]
    assert csv_header(["param"], param_name="speed", param_unit="rpm") == ["speed [rpm]"]


def test_resumable_sweep_helper(tmp_path):
    model = impact_pair_model(**HYST)
    grid = HYST_GRID[:3]
    kw = dict(settings=SweepOptions(directions=("up",), transient_periods=20, extra_transient_periods=0,
                                    record_periods=4, max_period=2), options=OPTS)
    stop = iter([True, False])                           # stop after the second point
    r1, st1, _ = resumable_sweep(model, grid, tmp_path, root=True,
                                 callback=lambda rec: next(stop), **kw)
    assert r1.status_code == 2 and st1.path.exists() and len(read_items(st1.path)) == 2
    r2, st2, resumed = resumable_sweep(model, grid, tmp_path, root=True, **kw)
    full = sweep(model, grid, **kw)
    assert resumed == 2 and _eq(r2.qmax, full.qmax) and _eq(r2.u_end, full.u_end)


# ---------------------------------------------------------------- classes and metrics

def test_motion_class_rules():
    from vibrogear.solvers.sequential.motion import (APERIODIC, CHAOTIC, FAILED, NOT_SETTLED, PERIODIC,
                                          QUASI_PERIODIC, motion_class)
    nan = math.nan
    assert motion_class(2, (0.1, 0.2)) == PERIODIC          # a period is the evidence
    assert motion_class(0, (0.01, 0.2)) == CHAOTIC
    assert motion_class(0, (0.01, 0.2), budget_used=True) == CHAOTIC
    assert motion_class(0, (-0.01, 0.2)) == QUASI_PERIODIC
    assert motion_class(0, (-0.01, 0.2), budget_used=True) == NOT_SETTLED
    assert motion_class(0, (-0.2, -0.01)) == NOT_SETTLED    # still converging
    assert motion_class(0, (nan, nan)) == APERIODIC
    assert motion_class(0, (nan, nan), budget_used=True) == NOT_SETTLED
    assert motion_class(1, failed=True) == FAILED


def test_contact_groups_and_window_metrics_by_hand():
    """Two meshes and a two-element bearing; switch times chosen so every metric is
    known by hand."""
    from vibrogear.solvers.sequential.record_metrics import contact_groups, metrics_with_errors
    inf = math.inf
    ct = ContactSet(directions=np.array([[1.0, 0, 0], [0, 2.0, 0], [0, 0, 1.0], [0, 0, -1.0]]),
                    k_hi=np.ones(4), k_lo=np.ones(4), gap_hi=np.zeros(4),
                    gap_lo=np.array([-1.0, -1.0, -inf, -inf]), exponent=np.ones(4),
                    damping=np.zeros(4), stiffness_cos=np.zeros((4, 1)),
                    stiffness_sin=np.zeros((4, 1)), error_cos=np.zeros((4, 1)),
                    error_sin=np.zeros((4, 1)), names=("G1", "G 2", "B1:0", "B1:1"))
    model = ReducedModel(omega2=np.ones(3), damping=np.zeros(3),
                         coupling=LinearCoupling.none(3),
                         forcing=Forcing(np.zeros(3), np.zeros((1, 3)), np.zeros((1, 3))),
                         contacts=ct)
    groups = contact_groups(model)
    assert {k: (kind, list(i)) for k, (kind, i) in groups.items()} == {
        "G1": ("mesh", [0]), "G_2": ("mesh", [1]), "bearing_B1": ("bearing", [2, 3])}
    T = 1.0
    # window [0, 2]: G1 in contact at start, loses it at 0.25, drive impact at 0.5 (v 2),
    # back impact at 1.5 (v 4) after a loss at 1.25, loses it at 1.75; G 2 never touches;
    # bearing element 0 loaded throughout, element 1 unloaded on [0.5, 2]
    ev = (np.array([0.25, 0.5, 0.5, 1.25, 1.5, 1.75]), np.array([0, 0, 3, 0, 0, 0]),
          np.array([0, 1, 0, 0, -1, 0]))
    speed = np.array([np.nan, 2.0, np.nan, np.nan, 4.0, np.nan])
    mode0 = np.array([1, 0, 1, 1])
    g = metrics_with_errors(model, groups, mode0, ev, speed, 0.0, 2 * T, T)
    assert g["impacts_drive_G1"] == 0.5 and g["impacts_back_G1"] == 0.5
    assert g["impact_velocity_max_G1"] == 4.0
    assert g["impact_velocity_rms_G1"] == pytest.approx(math.sqrt(10.0))
    assert g["contact_fraction_G1"] == pytest.approx((0.25 + 0.75 + 0.25) / 2)
    assert g["rattle_G1"] == pytest.approx((0.5 * 4 + 0.5 * 16) / 2)    # m_eff = 1
    assert g["rattle_power_G1"] == pytest.approx((0.5 * 4 + 0.5 * 16) / 2.0)  # per second
    assert g["impacts_drive_G_2"] == 0 and g["contact_fraction_G_2"] == 0
    assert g["unloaded_bearing_B1"] == pytest.approx(1.5 / 2)
    # halves: [0, 1] one drive impact, [1, 2] one back impact
    assert g["impacts_drive_G1_err"] == pytest.approx(0.5)
    assert g["contact_fraction_G1_err"] == pytest.approx(0.5 * abs(0.75 - 0.5))
    assert g["unloaded_bearing_B1_err"] == pytest.approx(0.5 * abs(0.5 - 1.0))
