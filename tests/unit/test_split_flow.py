"""Orbits with the variational equations on two cores (solvers/integrator/split_flow.py): the tangent's
columns integrated in two processes along one trajectory give the monodromy and the
parameter sensitivity of the whole integration (same steps, same numbers up to the
round-off of BLAS blocking), and each half alone is those columns of the whole; the
continuation traces the same branch with and without the split.  On the gear pair (68
states; the split is forced on below its size threshold)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.config import load_scene
from vibrogear.models.gearbox.model import build_gearbox
from vibrogear.solvers.integrator import split_flow
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.integrator.split_flow import ColumnSplit
from vibrogear.solvers.static import static_equilibrium

GEAR_PAIR = Path(__file__).resolve().parents[2] / "configs" / "gear_pair.toml"
OPTS = IntegrationOptions(rtol=1e-8, atol=1e-14)


@pytest.fixture(scope="module")
def case():
    scene = load_scene(GEAR_PAIR)
    model = build_gearbox(scene).reduced
    p = 0.5 * (scene.sweep.param_min + scene.sweep.param_max)
    u0 = static_equilibrium(model, p).u0
    T = model.excitation_period(p)
    u1 = integrate(model, p, u0, 0.0, 20 * T, options=OPTS).u_end   # in the steady motion
    return model, p, u1, T


def test_column_ranges_are_the_columns_of_the_whole_tangent(case):
    model, p, u, T = case
    n = model.n_states
    whole = integrate(model, p, u, 0.0, T, options=OPTS, variational=True)
    assert whole.events > 0                     # saltations act on every column
    full = np.column_stack([whole.monodromy, whole.dparam])
    for c0, c1 in ((0, 1), (5, 40), (n - 3, n + 1), (n, n + 1)):
        part = integrate(model, p, u, 0.0, T, options=OPTS, variational=True, columns=(c0, c1))
        assert part.monodromy is None and part.tangent_columns.shape == (n, c1 - c0)
        assert part.steps == whole.steps and np.array_equal(part.u_end, whole.u_end)
        np.testing.assert_allclose(part.tangent_columns, full[:, c0:c1], rtol=0,
                                   atol=1e-12 * np.abs(full).max())
    with pytest.raises(ValueError, match="columns"):
        integrate(model, p, u, 0.0, T, options=OPTS, variational=True, columns=(3, 3))


def test_split_integration_equals_the_whole(case, monkeypatch):
    model, p, u, T = case
    monkeypatch.setattr(split_flow, "SPLIT_MIN_STATES", 0)
    whole = integrate(model, p, u, 0.0, T, options=OPTS, variational=True)
    with ColumnSplit(model) as split:
        assert split.active and split.proc.is_alive()
        got = [split.integrate(p, u, T, OPTS) for _ in range(2)]
        proc = split.proc
    assert not proc.is_alive()                  # the worker ends with the context
    assert split.fallbacks == 0
    scale = np.abs(whole.monodromy).max()
    for tr in got:
        assert tr.steps == whole.steps and np.array_equal(tr.u_end, whole.u_end)
        assert np.abs(tr.monodromy - whole.monodromy).max() <= 1e-12 * scale
        np.testing.assert_allclose(tr.dparam, whole.dparam, rtol=0,
                                   atol=1e-12 * np.abs(whole.dparam).max())


def test_split_is_off_for_small_models_and_when_disabled(case):
    model = case[0]
    assert model.n_states < split_flow.SPLIT_MIN_STATES
    with ColumnSplit(model) as split:
        assert not split.active and split.proc is None
    with ColumnSplit(model, enabled=False) as split:
        assert not split.active


def test_continuation_traces_the_same_branch_with_the_split(monkeypatch):
    """The impact pair's branch over a fold, with the split forced on and off: the same
    points (the corrector sees the same monodromies up to round-off)."""
    from vibrogear.models.impact_pair import impact_pair_model
    from vibrogear.solvers.periodic.continuation import (ContinuationOptions, PeriodicOrbitProblem,
                                                PseudoArclength, continuation)

    monkeypatch.setattr(split_flow, "SPLIT_MIN_STATES", 0)
    model = impact_pair_model(0.015, 0.5, 0.55, 0.12, 1.0)
    p0 = 1.3
    warm = integrate(model, p0, np.array([1.05, 0.0]), 0.0, 300 * 2 * np.pi / p0)
    orbit = PeriodicOrbitProblem(model, warm.u_end, p0, direction=-1)
    options = ContinuationOptions(param_min=0.45, param_max=1.3, ds=0.02, ds_max=0.05,
                                  max_points=40)
    runs = [continuation(orbit, PseudoArclength(split_columns=on), options) for on in (True, False)]
    assert runs[0].counters["split_columns"] and not runs[1].counters["split_columns"]
    assert runs[0].counters["split_fallbacks"] == 0
    a, b = (r.branches[0] for r in runs)
    assert len(a.points) == len(b.points) == 40
    np.testing.assert_allclose(a.array("param"), b.array("param"), rtol=1e-10)
    assert [p.label for p in a.points] == [p.label for p in b.points]


def test_a_dead_worker_falls_back_to_the_whole_orbit(case, monkeypatch):
    """The worker killed between two orbits: the orbit is integrated here, whole, and the
    split is dropped for the rest of the run (no hang, no exception)."""
    model, p, u, T = case
    monkeypatch.setattr(split_flow, "SPLIT_MIN_STATES", 0)
    whole = integrate(model, p, u, 0.0, T, options=OPTS, variational=True)
    with ColumnSplit(model) as split:
        split.proc.kill()
        split.proc.join()
        tr = split.integrate(p, u, T, OPTS)
        assert split.fallbacks == 1 and split.proc is None
        again = split.integrate(p, u, T, OPTS)
    for got in (tr, again):
        assert np.array_equal(got.monodromy, whole.monodromy)
        assert np.array_equal(got.dparam, whole.dparam)
