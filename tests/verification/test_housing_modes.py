"""Housing master modes: mass normalisation, residuals, mass against the closed-form volume,
rigid-body content of the bore coupling values, and the cache (a hit does no FE work)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from vibrogear.config import load_scene
from vibrogear.config.base import build
from vibrogear.config.base import as_data
from vibrogear.config.model.housing import HousingConfig
from vibrogear.geometry.housing import housing_volume

ROOT = Path(__file__).resolve().parents[2]
SMALL = ROOT / "configs" / "housing_small.toml"


def _cfg(**changes):
    d = as_data(load_scene(SMALL).housing)
    for k, v in changes.items():
        node, *path = k.split(".")
        if path:
            d[node] = {**d[node], path[0]: v}
        else:
            d[k] = v
    return build(HousingConfig, d, "housing")


@pytest.fixture(scope="module")
def fixed(empty_vibrogear_cache):
    from vibrogear.models.housing.run import housing_modes
    return housing_modes(_cfg())


def test_fixed_base_modes_are_mass_normalised_and_converged(fixed):
    cfg = _cfg()
    assert fixed.n_modes == cfg.modes.count and not fixed.cached
    assert np.all(np.diff(fixed.freqs_hz) >= 0) and fixed.freqs_hz[0] > 0
    assert fixed.orthogonality_error < 1e-8            # max |V^T M V - I|
    assert fixed.residuals.max() < 1e-6                # ||K x - lam M x|| / ||K x||
    assert fixed.converged_reason == "CONVERGED_TOL"
    # integral of rho over the mesh against the closed-form solid volume (faceted bores: 0.1 %)
    assert fixed.mass_kg == pytest.approx(housing_volume(cfg) * cfg.material.rho, rel=1e-3)
    B, P = len(fixed.bore_names), max(b.rolling_elements for b in cfg.bores)
    assert fixed.bore_values.shape == (B, P, 3, fixed.n_modes)
    assert fixed.bore_center_values.shape == (B, 3, fixed.n_modes)
    for i, n in enumerate(fixed.bore_n_points):
        assert np.all(np.isfinite(fixed.bore(i))) and np.all(np.isnan(fixed.bore_values[i, n:]))
    assert np.allclose(fixed.damping_ratios, 0.5 * cfg.material.beta * 2 * np.pi * fixed.freqs_hz)


def test_soft_foundation_rigid_modes_reproduce_the_housing_mass(empty_vibrogear_cache):
    """On a very soft elastic foundation the 6 lowest modes are rigid-body motions.  Their values
    at the bore coupling points must fit u = a + theta x X exactly, and for mass-normalised modes
    sum_i psi_i psi_i^T = M_rb^-1, whose translational block inverts to m I with m = rho V
    (closed-form volume), and whose coupling block gives the centre of mass (y = width/2)."""
    from vibrogear.models.housing.run import housing_modes
    cfg = _cfg(support="elastic", foundation_stiffness=2e6, **{"modes.count": 7})
    res = housing_modes(cfg)
    assert res.freqs_hz[5] < 0.05 * res.freqs_hz[6]   # 6 rigid modes well below the first elastic
    X = np.vstack([res.bore_points[i, :n] for i, n in enumerate(res.bore_n_points)])
    psi = []
    for k in range(6):
        U = np.vstack([res.bore(i)[:, :, k] for i in range(len(res.bore_names))])
        # u = a + theta x X  ->  linear least squares in (a, theta)
        A = np.zeros((3 * len(X), 6))
        for j, x in enumerate(X):
            A[3 * j:3 * j + 3, :3] = np.eye(3)
            A[3 * j:3 * j + 3, 3:] = -np.array([[0, -x[2], x[1]], [x[2], 0, -x[0]], [-x[1], x[0], 0]])
        sol, *_ = np.linalg.lstsq(A, U.ravel(), rcond=None)
        assert np.linalg.norm(A @ sol - U.ravel()) < 1e-3 * np.linalg.norm(U)
        psi.append(sol)
    Mrb = np.linalg.inv(np.array(psi).T @ np.array(psi))
    m = housing_volume(cfg) * cfg.material.rho
    assert np.allclose(Mrb[:3, :3], m * np.eye(3), rtol=0, atol=2e-3 * m)
    # M_rb[:3, 3:] = -m [c x]: recover the centre of mass
    c = -np.array([Mrb[2, 4], Mrb[0, 5], Mrb[1, 3]]) / m
    assert c[1] == pytest.approx(cfg.width / 2, abs=1e-3 * cfg.width)
    assert 0 < c[0] < cfg.length and -cfg.base_thickness < c[2] < cfg.height


_LOAD = r"""
import json, sys
from vibrogear.config import load_scene
from vibrogear.models.housing.run import housing_modes
res = housing_modes(load_scene(sys.argv[1]).housing)
print(json.dumps({"cached": res.cached, "dolfinx": "dolfinx" in sys.modules, "gmsh": "gmsh" in sys.modules,
                  "f": res.freqs_hz.tolist()}))
"""


def test_cache_hit_does_no_fe_work_and_changes_invalidate(fixed, empty_vibrogear_cache):
    from vibrogear.models.housing.run import housing_modes
    env = {**os.environ, "VIBROGEAR_CACHE_DIR": str(empty_vibrogear_cache)}
    out = subprocess.run([sys.executable, "-c", _LOAD, str(SMALL)], capture_output=True, text=True,
                         env=env, cwd=ROOT, timeout=120)
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["cached"] and not r["dolfinx"] and not r["gmsh"]
    assert np.array_equal(r["f"], fixed.freqs_hz)
    # a material change re-solves on the cached mesh; f scales as sqrt(E)
    stiff = housing_modes(_cfg(**{"material.E": 4 * 2.1e11}))
    assert not stiff.cached and stiff.timings["meshing"] == 0.0
    assert np.allclose(stiff.freqs_hz, 2 * fixed.freqs_hz, rtol=1e-6)
    # a geometry change re-meshes
    thick = housing_modes(_cfg(wall_thickness=0.016))
    assert not thick.cached and thick.timings["meshing"] > 0.0


def test_block_lanczos_agrees_with_slepc_krylov_schur_and_cutoff(fixed, empty_vibrogear_cache):
    """The default block Lanczos against SLEPc Krylov-Schur on the same mesh; cutoff_hz mode."""
    from vibrogear.models.housing.run import housing_modes
    ks = housing_modes(_cfg(**{"modes": {**as_data(_cfg().modes), "solver": "krylovschur"}}))
    assert np.allclose(ks.freqs_hz, fixed.freqs_hz, rtol=1e-8)
    assert ks.residuals.max() < 1e-6 and ks.orthogonality_error < 1e-8
    cut = 0.5 * (fixed.freqs_hz[4] + fixed.freqs_hz[5])
    below = housing_modes(_cfg(**{"modes": {**as_data(_cfg().modes), "cutoff_hz": cut}}))
    assert below.n_modes == 5 and below.status == "ok"
    assert np.allclose(below.freqs_hz, fixed.freqs_hz[:5], rtol=1e-8)
    assert below.residuals.max() < 1e-6 and below.orthogonality_error < 1e-8
