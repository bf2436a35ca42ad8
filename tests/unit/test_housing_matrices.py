"""The full housing matrices against the housing master modes on the same mesh: scipy eigsh of the
free-DOF (K, M) reproduces the modes' frequencies, and T / T_center reproduce their bore values;
the npz cache (a hit does no FE work); the serial-only guard."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from vibrogear.config import load_scene
from vibrogear.config.base import as_data, build
from vibrogear.config.model.housing import HousingConfig
from vibrogear.models.gearbox.full_linear import mac_matrix

ROOT = Path(__file__).resolve().parents[2]
SMALL = ROOT / "configs" / "housing_small.toml"


def _cfg(**changes) -> HousingConfig:
    d = as_data(load_scene(SMALL).housing)
    for k, v in changes.items():
        node, *path = k.split(".")
        if path:
            d[node] = {**d[node], path[0]: v}
        else:
            d[k] = v
    return build(HousingConfig, d, "housing")


def _check(cfg, n_modes: int):
    """Full matrices vs master modes of ``cfg``: frequencies, bore values, bore-centre values."""
    from vibrogear.models.housing.run import housing_matrices, housing_modes
    modes, mats = housing_modes(cfg), housing_matrices(cfg)
    N = mats.n_dofs
    B, P = modes.bore_values.shape[:2]
    assert mats.K.shape == mats.M.shape == (N, N) and mats.T.shape == (B * P * 3, N)
    assert mats.T_center.shape == (B * 3, N) and mats.free_dofs.shape == (N,)
    assert mats.n_dofs_total == modes.n_dofs and abs(mats.K - mats.K.T).max() <= 1e-12 * abs(mats.K).max()
    assert abs(mats.M - mats.M.T).max() <= 1e-12 * abs(mats.M).max()
    assert np.array_equal(mats.bore_points, modes.bore_points, equal_nan=True)
    lam, X = spla.eigsh(mats.K, k=n_modes, M=mats.M, sigma=0.0, which="LM")
    order = np.argsort(lam)
    lam, X = lam[order], X[:, order]
    X /= np.sqrt(np.einsum("ij,ij->j", X, mats.M @ X))
    f = np.sqrt(lam) / (2 * np.pi)
    assert np.allclose(f, modes.freqs_hz[:n_modes], rtol=1e-6, atol=0)
    ref = np.nan_to_num(modes.bore_values[..., :n_modes]).reshape(B * P * 3, n_modes)
    TX = mats.T @ X
    mac = np.diag(mac_matrix(TX, ref))
    assert np.all(mac > 1 - 1e-6), mac
    sign = np.sign(np.einsum("ij,ij->j", TX, ref))
    amp = np.abs(TX * sign - ref).max(axis=0) / np.abs(ref).max(axis=0)
    assert np.all(amp < 1e-6), amp
    cref = modes.bore_center_values[..., :n_modes].reshape(B * 3, n_modes)
    assert np.abs((mats.T_center @ X) * sign - cref).max() < 1e-6 * np.abs(cref).max()
    # padding rows are empty; T is a partition of unity (rigid translation -> 1 at every point)
    pad = np.zeros((B, P, 3), dtype=bool)
    for i, n in enumerate(modes.bore_n_points):
        pad[i, n:] = True
    assert mats.T[np.flatnonzero(pad.ravel())].nnz == 0
    ones = np.zeros(N)
    ones[mats.free_dofs % 3 == 1] = 1.0                    # y translation
    ty = (mats.T @ ones).reshape(B, P, 3)
    assert np.allclose(ty[~pad[..., 0], 1], 1.0, atol=1e-12) and np.allclose(ty[..., [0, 2]], 0.0)
    return modes, mats


def test_full_matrices_reproduce_master_modes_and_bore_values(empty_vibrogear_cache):
    _, mats = _check(_cfg(), 10)
    assert not mats.cached and mats.n_dofs < mats.n_dofs_total            # base plate clamped
    assert mats.mass_kg > 0 and mats.beta == _cfg().material.beta


_LOAD = r"""
import json, sys, time
from vibrogear.config import load_scene
from vibrogear.models.housing.run import housing_matrices
t = time.perf_counter()
m = housing_matrices(load_scene(sys.argv[1]).housing)
print(json.dumps({"cached": m.cached, "dolfinx": "dolfinx" in sys.modules, "gmsh": "gmsh" in sys.modules,
                  "key": m.cache_key, "sum": float(abs(m.K).sum() + abs(m.T).sum())}))
"""


def test_second_call_is_a_cache_load_without_fe_work(empty_vibrogear_cache):
    from vibrogear.models.housing.run import housing_cache_keys, housing_matrices
    first = housing_matrices(_cfg())                        # computed by the test above or now
    again = housing_matrices(_cfg())
    assert again.cached and "cache_load" in again.timings
    for k in ("K", "M", "T", "T_center"):
        assert abs(getattr(again, k) - getattr(first, k)).max() == 0.0
    assert np.array_equal(again.free_dofs, first.free_dofs)
    assert again.cache_key.split("-")[-1] == housing_cache_keys(_cfg())[1].split("-")[-1]
    assert again.cache_key.startswith("housing-matrices-")
    env = {**os.environ, "VIBROGEAR_CACHE_DIR": str(empty_vibrogear_cache)}
    out = subprocess.run([sys.executable, "-c", _LOAD, str(SMALL)], capture_output=True, text=True,
                         env=env, cwd=ROOT, timeout=120)
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["cached"] and not r["dolfinx"] and not r["gmsh"] and r["key"] == again.cache_key
    assert r["sum"] == pytest.approx(float(abs(first.K).sum() + abs(first.T).sum()), rel=1e-15)


def test_refuses_under_mpi(monkeypatch):
    from vibrogear.models.housing.run import housing_matrices
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "2")
    with pytest.raises(RuntimeError, match="serial"):
        housing_matrices(_cfg())


@pytest.mark.slow
def test_elastic_foundation_and_finer_mesh(empty_vibrogear_cache):
    """No clamped DOF on an elastic foundation (K SPD through the springs, rigid-like modes low),
    and a finer mesh with more modes."""
    _, soft = _check(_cfg(support="elastic", foundation_stiffness=2e8, **{"modes.count": 12}), 12)
    assert soft.n_dofs == soft.n_dofs_total
    _check(_cfg(**{"mesh.size": 0.02, "modes.count": 30}), 30)
