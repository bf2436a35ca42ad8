"""The sweep's vectorised helpers against their plain forms: the contact fractions of many
contacts at once (meshes, unloaded rolling elements) against the one-contact computation, including
events at the window's start and contacts without events; the greedy Poincare clusters
against the loop over centres; the monitored deformation against the contact kinematics."""
from __future__ import annotations

import numpy as np

from pathlib import Path

from vibrogear.solvers.sequential.motion import block_scaled, count_clusters, monitored_deformation
from vibrogear.solvers.sequential.record_metrics import _fractions


def _fraction(mode0: int, times, modes, t0: float, t1: float) -> float:
    """The plain form, one contact: the window's length in contact (mode != 0) from the
    initial mode and the contact's own switches."""
    edges = np.concatenate([[t0], times, [t1]])
    states = np.concatenate([[mode0], modes])
    return float(np.sum(np.diff(edges) * (states != 0)) / (t1 - t0))


def test_fractions_equal_the_one_contact_form():
    rng = np.random.default_rng(1)
    for _ in range(300):
        nc = 12
        ne = int(rng.integers(0, 60))
        t = np.sort(rng.uniform(0.0, 10.0, ne))
        if ne:
            t[0] = 0.0                      # an event right at the window's start
        j = rng.integers(0, nc, ne)
        md = rng.integers(-1, 2, ne)
        mode0 = rng.integers(-1, 2, nc)
        rows = np.sort(rng.choice(nc, int(rng.integers(1, nc)), replace=False))
        one = [_fraction(int(mode0[c]), t[j == c], md[j == c], 0.0, 10.0) for c in rows]
        np.testing.assert_allclose(_fractions(mode0, t, j, md, 0.0, 10.0, rows), one,
                                   atol=1e-14)


def test_fraction_by_hand():
    # contact 0 closed on [0, 2) and [5, 10): 0.7; contact 1 never touches: 0
    t, j, md = np.array([2.0, 5.0]), np.array([0, 0]), np.array([0, 1])
    np.testing.assert_allclose(_fractions(np.array([1, 0]), t, j, md, 0.0, 10.0, [0, 1]),
                               [0.7, 0.0])


def _clusters_by_loop(samples, rel_tol, split):
    z = block_scaled(np.asarray(samples, dtype=float), split)
    centres = []
    for p in z:
        if not any(float(np.max(np.abs(p - c))) <= rel_tol for c in centres):
            centres.append(p)
    return len(centres)


def test_clusters_equal_the_loop_over_centres():
    rng = np.random.default_rng(2)
    for n in (1, 2, 3, 5):
        base = rng.standard_normal((n, 6))
        # period-n samples with noise below and above the radius, and noise alone
        for noise in (1e-5, 3e-3, 1.0):
            s = base[np.arange(40) % n] + noise * rng.standard_normal((40, 6))
            for split in (None, 3):
                assert count_clusters(s, 1e-3, split=split) == _clusters_by_loop(s, 1e-3, split)
    assert count_clusters(np.tile(base[:1], (10, 1))) == 1


def test_monitored_deformation_equals_the_contact_kinematics():
    from vibrogear.analyses.study import build_study
    from vibrogear.config import load_scene
    from vibrogear.solvers.integrator.contact_eval import contact_kinematics

    scene = Path(__file__).resolve().parents[2] / "configs" / "gear_pair.toml"
    model = build_study(load_scene(scene)).model
    rng = np.random.default_rng(0)
    x = 1e-5 * rng.standard_normal((30, model.n_states))
    t = rng.uniform(0.0, 1e-3, 30)
    np.testing.assert_allclose(monitored_deformation(model, 4000.0, t, x),
                               contact_kinematics(model, 4000.0, t, x, rows=[model.monitor])[0][0],
                               rtol=1e-13, atol=1e-20)
