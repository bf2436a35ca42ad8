"""``[nvh] branch_spectra``: line spectra of the continuation's branch points, one orbit
period each, on the gear pair (continuation windows of a few points: 4500-4700 rpm, stable
period-1 orbits; 5900-6200 rpm, unstable period-1 orbits inside the rattle range).

References: the spectrum of a long integration settled from the static equilibrium at the
branch's start speed (the [nvh] own grid, independent of shooting); the orbit's closure
u(n T) = u0 re-integrated here; Parseval against the time signal recomputed here."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from vibrogear.analyses import continuation
from vibrogear.analyses.nvh import nvh
from vibrogear.analyses.invoke import with_needs
from vibrogear.analyses.study import build_study, integration_options
from vibrogear.config import load_scene
from vibrogear.pipeline.outcome import RunContext
from vibrogear.report.writers import nvh as nvh_report
from vibrogear.solvers.integrator.contact_eval import contact_history
from vibrogear.solvers.integrator.integrate import integrate

ROOT = Path(__file__).resolve().parents[2]
GEAR_PAIR = ROOT / "configs" / "gear_pair.toml"
R = 4                        # settled record of the reference: 4 mesh periods


def _run(tmp_path, lo: float, hi: float, transient: int):
    """(scene, study, continuation outcome, nvh outcome): a continuation from ``hi`` down
    to ``lo`` (4 points), then nvh with its own grid {hi - 50, hi} and the branch spectra."""
    scene = load_scene(GEAR_PAIR, (
        'scene.analyses=["continuation", "nvh"]',
        f"continuation.rpm_min={lo}", f"continuation.rpm_max={hi}", "continuation.ds=40",
        "continuation.ds_max=60", "continuation.max_points=4",
        "continuation.transient_periods=100",
        f"nvh.rpm_min={hi - 50}", f"nvh.rpm_max={hi}", "nvh.n_speeds=2",
        f"nvh.transient_periods={transient}", f"nvh.record_periods={R}",
        "nvh.branch_spectra=true"))
    study = build_study(scene)
    ctx = RunContext(out=tmp_path, quiet=True)
    cont = continuation.run(study, scene, ctx)
    out = nvh.run(study, scene, ctx, previous=with_needs("nvh", "gearbox", study, scene, ctx,
                                                        {"continuation": cont}))
    assert out.result.branch is not None and not out.warnings, out.warnings
    return scene, study, cont, out


def _closure_and_parseval(scene, study, cont, br):
    """(2) one orbit period closes, re-integrated here from each point's u0; (3) Parseval:
    the mean square of the DTE over that period = the power of its stored line spectrum."""
    pts = [p for b in cont.result.branches for p in b.points]
    assert br.rpm.size == len(pts) >= 3
    assert np.array_equal(br.rpm, [p.param for p in pts])
    opts = integration_options(scene, record=True)
    S = scene.nvh.samples_per_period
    mesh = study.contact_groups["mesh"]
    for k, (p, n) in enumerate(zip(pts, br.n_periods)):
        T = study.model.excitation_period(p.param)
        t = np.arange(n * S) * (T / S)
        tr = integrate(study.model, p.param, p.u0, 0.0, n * T, t_eval=t, options=opts)
        gap = np.linalg.norm(tr.u_end - p.u0) / np.linalg.norm(p.u0)
        assert gap < 1e-5 and np.isclose(gap, br.closure[k], rtol=1e-3, atol=1e-12)
        x = contact_history(study.model, p.param, t, tr.u)[0][mesh]
        a = br.amplitudes["dte"][k]
        power = a[:, 0] ** 2 + 0.5 * np.sum(a[:, 1:-1] ** 2, axis=1) + a[:, -1] ** 2
        assert np.allclose(power, np.mean(x ** 2, axis=1), rtol=1e-10)
    assert max(br.parseval.values()) < 1e-10


def test_stable_branch_spectra_equal_the_settled_spectra(tmp_path):
    scene, study, cont, out = _run(tmp_path, 4500.0, 4700.0, transient=1500)
    res, br = out.result, out.result.branch
    # (1) the stable period-1 start point at 4700 rpm against the settled long record
    i = int(np.argmin(np.abs(br.rpm - 4700.0)))
    assert br.rpm[i] == 4700.0 and br.stable[i] and br.n_periods[i] == 1
    j = int(np.argmin(np.abs(res.rpm - 4700.0)))
    assert res.rpm[j] == 4700.0
    N = int(round(1.0 / br.order[1]))
    for q in ("dte", "mesh_force"):
        line = br.amplitudes[q][i, 0]                      # bins at orders k / N
        ref = res.amplitudes[q][j, 0]                      # bins at orders k / R
        for h in (1, 2, 3):
            assert abs(line[h * N] - ref[h * R]) <= 1e-5 * ref[R], (q, h, line[h * N],
                                                                      ref[h * R])
        # between the orbit's lines the common grid is exactly zero
        assert np.all(line[np.arange(line.size) % (N // br.n_periods[i]) != 0] == 0.0)

    _closure_and_parseval(scene, study, cont, br)
    files = nvh_report.write(scene, out, tmp_path)
    with np.load(files["branch_npz"]) as z:
        assert np.array_equal(z["rpm"], br.rpm) and z["amp_dte"].shape == br.amplitudes[
            "dte"].shape
        assert set(z["stable"].tolist()) <= {True, False}
    assert Path(files["waterfall_branch_dte"]).stat().st_size > 0


def test_unstable_branch_orbits_close_and_keep_parseval(tmp_path):
    """Inside the rattle range the period-1 orbits are unstable (no settled reference), but
    shooting converged on them: one period still closes and carries the line spectrum."""
    scene, study, cont, out = _run(tmp_path, 5900.0, 6200.0, transient=10)
    br = out.result.branch
    assert not np.any(br.stable)
    _closure_and_parseval(scene, study, cont, br)
    assert out.summary["branch_spectra"]["stable"] == 0
