"""Mesh convergence of a housing: three nested levels (each tet split in 8, h halves exactly).

For nested conforming spaces every eigenvalue decreases monotonically (min-max principle), so
the first 10 frequencies must converge from above; the observed order is fitted per mode and
the Richardson-extrapolated error of the finest level is reported.  Re-entrant edges (wall/boss
junctions, 270 degree) cap the asymptotic eigenvalue order below the smooth-case 2k.
CI runs P1 (<= ~15k DOF); P2 (2k / 13k / 93k DOF) is marked slow.
"""
from __future__ import annotations

import numpy as np
import pytest

from vibrogear.analyses.housing.convergence import observed_order, richardson
from vibrogear.config.base import build
from vibrogear.config.model.housing import HousingConfig

MINI = dict(length=0.10, width=0.08, height=0.08, wall_thickness=0.02, base="none",
            bores=[dict(x=0.05, z=0.045, bore_radius=0.012, boss_radius=0.02, boss_length=0.0,
                        rolling_elements=8)],
            modes=dict(count=10, shapes=0))


def test_observed_order_and_richardson_on_exact_data():
    h = np.array([0.3, 0.17, 0.1])                   # non-constant ratios
    for p in (1.0, 1.6, 4.0):
        f = 100.0 + np.outer(h ** p, [3.0, -2.0])    # from above and from below
        assert np.allclose(observed_order(f, h), p, rtol=1e-8)
        assert np.allclose(richardson(f, h, observed_order(f, h)), 100.0, rtol=1e-10)
    f = np.array([[3.0], [1.0], [2.0]])              # not monotone: no order
    assert np.isnan(observed_order(f, h)[0])


def _levels(degree, tmp_path, monkeypatch):
    from vibrogear.models.housing.run import housing_modes
    monkeypatch.setenv("VIBROGEAR_CACHE_DIR", str(tmp_path))
    F, dofs = [], []
    for k in range(3):
        cfg = build(HousingConfig, {**MINI, "mesh": dict(size=0.04, bore_size=0.04, degree=degree, refine=k)},
                    "housing")
        res = housing_modes(cfg, cache=False)
        assert res.residuals.max() < 1e-6 and res.orthogonality_error < 1e-8
        F.append(res.freqs_hz)
        dofs.append(res.n_dofs)
    F = np.array(F)
    h = 0.04 / 2.0 ** np.arange(3)
    p = observed_order(F, h)
    ref = richardson(F, h, p)
    err = np.abs(F[-1] - ref) / ref
    print(f"\nP{degree} DOF {dofs}\n  f (finest) {np.round(F[-1], 1)}\n  observed order {np.round(p, 2)}"
          f"\n  Richardson error of finest level {np.round(100 * err, 3)} %")
    return F, p, err


def _check(F, p, lo, hi):
    assert np.all(np.diff(F, axis=0) < 0), "frequencies must decrease on nested refinement"
    assert np.all(np.isfinite(p)) and np.all(p > 0.2)
    assert lo <= np.median(p) <= hi


def test_p1_nested_housing_converges_from_above(tmp_path, monkeypatch):
    F, p, err = _levels(1, tmp_path, monkeypatch)
    _check(F, p, 0.6, 2.5)       # P1 theory: 2 asymptotically (4/3 with re-entrant edges)


@pytest.mark.slow
def test_p2_nested_housing_converges_from_above(tmp_path, monkeypatch):
    F, p, err = _levels(2, tmp_path, monkeypatch)
    _check(F, p, 1.2, 4.5)       # P2 theory: 4 smooth; edge singularities -> about 4/3..2
    assert np.all(err < 0.01)
