"""The housing sweep's reuse of the previous variant (models/housing/sweep.py): the moved-node hex
mesh against the generator and the closed-form volume, the Krylov refinement against a closed-form
spectrum, and a reused-start sweep against each variant's own fresh solve."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from vibrogear.config.scene import load_scene
from vibrogear.geometry.hex_grid import CellCounts, TopologyChange, hex_volumes, min_corner_jacobian
from vibrogear.geometry.housing import housing_volume
from vibrogear.geometry.housing_hex import hex_housing_arrays, moved_hex_nodes

ROOT = Path(__file__).resolve().parents[2]


def _cfg(t, scene="housing.toml", sets=()):
    return load_scene(ROOT / "configs" / scene, ('housing.mesh.element="hex"', f"housing.wall_thickness={t!r}",
                                                  *sets)).housing


def test_replayed_counts_reproduce_the_generator():
    cfg = _cfg(0.012)
    counts = CellCounts()
    x, cells, facets, values = hex_housing_arrays(cfg, counts)
    x2, cells2, facets2, values2 = hex_housing_arrays(cfg, CellCounts(counts.values))
    assert np.array_equal(x, x2) and np.array_equal(cells, cells2) and np.array_equal(facets, facets2)
    plain = hex_housing_arrays(cfg)
    assert np.array_equal(plain[0], x) and np.array_equal(plain[1], cells)


def test_moved_nodes_equal_a_fresh_mesh_where_the_topology_is_the_same():
    # housing.toml: the generator lays the same cells at 13 and 14 mm walls (1676 cells both)
    a, b = _cfg(0.013), _cfg(0.014)
    counts = CellCounts()
    _, cells, facets, values = hex_housing_arrays(a, counts)
    xf, cf, _, _ = hex_housing_arrays(b)
    assert cf.shape == cells.shape
    moved = moved_hex_nodes(b, counts, cells, facets, values)
    perm = np.empty(len(xf), np.int64)
    perm[cells.ravel()] = cf.ravel()               # the fresh mesh's numbering of the same nodes
    assert np.array_equal(perm[cells], cf)
    assert np.max(np.abs(moved - xf[perm])) < 1e-15
    # and the walls really moved: every inner wall face at y = 14 mm
    assert np.any(np.abs(moved[:, 1] - 0.014) < 1e-12) and not np.any(np.abs(moved[:, 1] - 0.013) < 1e-12)


def test_moved_mesh_volume_matches_the_closed_form():
    # counts recorded at 10 mm, nodes moved to 16 mm walls (the generator would lay other counts)
    a, b = _cfg(0.010), _cfg(0.016)
    counts = CellCounts()
    _, cells, facets, values = hex_housing_arrays(a, counts)
    assert len(hex_housing_arrays(b)[1]) != len(cells)
    moved = moved_hex_nodes(b, counts, cells, facets, values)
    assert min_corner_jacobian(moved, cells) > 0
    # the bore and boss circles are polygons: < 0.1 % of the housing (as the generator's own mesh)
    assert hex_volumes(moved, cells).sum() == pytest.approx(housing_volume(b), rel=1e-3)
    assert not hex_volumes(moved, cells).sum() == pytest.approx(housing_volume(a), rel=1e-2)


def test_counts_that_do_not_fit_raise_topology_change():
    counts = CellCounts()
    _, cells, facets, values = hex_housing_arrays(_cfg(0.010), counts)
    with pytest.raises(TopologyChange):      # at 17 mm a grid line merges: one interval fewer
        moved_hex_nodes(_cfg(0.017), counts, cells, facets, values)


def test_krylov_refinement_finds_the_closed_form_spectrum():
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from vibrogear.models.housing.krylov_refine import krylov_refine

    # fixed-fixed string, n interior nodes, spacing h: K = tridiag(-1, 2, -1) / h, M = h I (lumped);
    # lambda_k = 4 sin^2(k pi / (2 (n + 1))) / h^2, modes sin(k pi i / (n + 1))
    n, h, nev, p = 600, 1.0 / 601, 10, 14
    K = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1], format="csc") / h
    mdiag = np.full(n, h)
    lu = spla.splu(K)
    k = np.arange(1, p + 1)
    exact = 4 * np.sin(k * math.pi / (2 * (n + 1))) ** 2 / h ** 2
    i = np.arange(1, n + 1)[:, None]
    # the start: the modes of a string 5 % longer (a neighbouring variant), on these nodes
    X0 = np.sin(k[None, :] * math.pi * i / (1.05 * (n + 1)))
    lam, Z, est, blocks, n_rhs, Zp = krylov_refine(X0, solve=lambda B: lu.solve(B), mdiag=mdiag,
                                                   gram=lambda A, B: A.T @ B, nev=nev, tol=1e-2)
    assert np.all(est[:nev] <= 1e-2) and blocks >= 1 and p + nev <= n_rhs <= p + blocks * nev
    # K Z from the Krylov relation, as a product
    assert np.allclose(K @ Z[:, :nev], mdiag[:, None] * Zp, rtol=0, atol=1e-9 * np.abs(K @ Z).max())
    # the criterion bounds each eigenvalue's relative error (here the error is ~5 % of the bound:
    # quadratic in the modes' error, where the criterion is linear)
    err = np.abs(lam[:nev] / exact[:nev] - 1)
    assert np.all(err <= est[:nev]) and err.max() < 1e-3
    assert np.allclose(Z.T @ (mdiag[:, None] * Z), np.eye(p), atol=1e-10)


def test_acceptance_criterion_rejects_perturbed_modes_and_accepts_converged_ones():
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from vibrogear.models.housing.krylov_refine import ritz_criterion
    from vibrogear.models.housing.sweep import DEFAULT_TOL

    # fixed-fixed string (closed form as above): the exact modes, M-normalised
    n, h, nev = 400, 1.0 / 401, 8
    K = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1], format="csc") / h
    mdiag = np.full(n, h)
    lu = spla.splu(K)
    k = np.arange(1, nev + 2)
    exact = 4 * np.sin(k * math.pi / (2 * (n + 1))) ** 2 / h ** 2
    Phi = np.sin(k[None, :] * math.pi * np.arange(1, n + 1)[:, None] / (n + 1))
    Phi /= np.sqrt(np.sum(mdiag[:, None] * Phi ** 2, axis=0))
    spectrum = 4 * np.sin(np.arange(1, n + 1) * math.pi / (2 * (n + 1))) ** 2 / h ** 2

    def judge(Z):
        Z = Z / np.sqrt(np.sum(mdiag[:, None] * Z ** 2, axis=0))
        lam = np.einsum("ij,ij->j", Z, K @ Z)             # Rayleigh quotients
        return lam, ritz_criterion(Z, lu.solve(mdiag[:, None] * Z), lam, mdiag)

    lam, est = judge(Phi[:, :nev])                        # converged: accepted
    assert np.all(est <= 1e-9) and np.allclose(lam, exact[:nev], rtol=1e-12)
    rng = np.random.default_rng(7)
    noisy = Phi[:, :nev].copy()
    noisy[:, 2] += 0.05 * rng.standard_normal(n) * np.sqrt(1.0 / h) / np.sqrt(n)   # 5 % rough noise
    mixed = Phi[:, :nev].copy()
    mixed[:, 5] = math.cos(0.2) * Phi[:, 5] + math.sin(0.2) * Phi[:, 6]           # two modes mixed
    for Z, j in ((noisy, 2), (mixed, 5)):
        lam, est = judge(Z)
        err = np.abs(lam / exact[:nev] - 1)
        # the perturbed pair is rejected (and its eigenvalue is indeed off by more than the
        # tolerance); the others stay accepted; each pair has an eigenvalue of the whole closed-form
        # spectrum within its bound, |lam - lambda_i| <= est lambda_i
        assert est[j] > DEFAULT_TOL and err[j] > DEFAULT_TOL
        assert np.all(np.delete(est, j) <= 1e-9)
        nearest = np.min(np.abs(lam[:, None] / spectrum[None, :] - 1), axis=1)
        assert np.all(nearest <= est * (1 + 1e-9) + 1e-12)


@pytest.fixture(scope="module")
def small_sweep():
    from vibrogear.config.base import build
    from vibrogear.config.sections.housing import HousingSweepConfig
    from vibrogear.models.housing.sweep import sweep_housing_modes

    # the points as the analysis builds them (the 12 mm base's mesh sizes): one grid for all three
    base = _cfg(0.012, "housing_small.toml", ("housing.mesh.degree=2",))
    opts = build(HousingSweepConfig, {"parameter": "housing.wall_thickness", "values": [0.0105, 0.011, 0.012]},
                 "housing_sweep")
    cfgs = opts.housing_points(base)
    reused = sweep_housing_modes(cfgs, count=12, reuse=True)
    fresh = sweep_housing_modes(cfgs, count=12, reuse=False)
    return reused, fresh


def test_reused_start_sweep_matches_each_fresh_solve(small_sweep):
    from vibrogear.models.housing.sweep import DEFAULT_TOL

    reused, fresh = small_sweep
    assert [v.start for v in reused] == ["fresh", "previous", "previous"]
    assert [v.mesh for v in reused] == ["generated", "moved", "moved"]
    assert all(v.start == "fresh" for v in fresh)
    for r, f in zip(reused, fresh):
        # within 1 % of the variant's own fresh solve (the same grid, generated; tol 1e-8); the
        # criterion bounds each eigenvalue's error by DEFAULT_TOL, each frequency's by half that
        assert r.n_dofs == f.n_dofs
        assert np.max(np.abs(r.freqs_hz / f.freqs_hz - 1)) <= 0.5 * DEFAULT_TOL
        assert r.bound <= DEFAULT_TOL and r.residual < 1.0
    # the first variant is the fresh solve itself
    assert np.allclose(reused[0].freqs_hz, fresh[0].freqs_hz, rtol=1e-12)
    # a thicker wall stiffens the housing: the first frequency rises
    assert reused[2].freqs_hz[0] > reused[1].freqs_hz[0] > reused[0].freqs_hz[0]


@pytest.mark.system
def test_housing_sweep_analysis_reuses_in_runs(tmp_path):
    """The ``housing_sweep`` analysis with an all-hex housing: the points in one run of neighbours,
    each but the first from the previous one; every frequency within 1 % of the point's fresh solve."""
    import csv
    import json
    import os
    import subprocess
    import sys

    from vibrogear.config import load_scene
    from vibrogear.models.housing.sweep import sweep_housing_modes

    scene_path = str(ROOT / "configs" / "housing_sweep.toml")
    sets = ['housing.mesh.element="hex"', "housing.mesh.size=0.03", "housing_sweep.values=[0.013, 0.014]",
            "housing_sweep.n_freqs=4", "housing_sweep.processes=1"]
    out = tmp_path / "sweep"
    env = {**os.environ, "VIBROGEAR_CACHE_DIR": str(tmp_path / "cache"), "OPENBLAS_NUM_THREADS": "1"}
    args = [str(Path(sys.executable).parent / "vibrogear"), "run", scene_path, "--out", str(out), "--quiet"]
    for text in sets:
        args += ["--set", text]
    r = subprocess.run(args, env=env, cwd=ROOT, capture_output=True, text=True, timeout=400)
    assert r.returncode == 0, r.stderr[-3000:]
    points = [json.loads(line) for line in (out / "housing_sweep_points.jsonl").read_text().splitlines()[1:]]
    assert [p["start"] for p in points] == ["fresh", "previous"]
    with (out / "housing_sweep.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    got = np.array([[float(row[f"f{k}_hz"]) for k in range(1, 5)] for row in rows])
    scene = load_scene(scene_path, tuple(sets))
    fresh = sweep_housing_modes(scene.housing_sweep.housing_points(scene.housing), count=4, reuse=False)
    assert np.max(np.abs(got / np.array([f.freqs_hz for f in fresh]) - 1)) < 0.01


def test_reusing_sweep_points_share_the_base_mesh_sizes():
    from vibrogear.config.base import build
    from vibrogear.config.sections.housing import HousingSweepConfig

    base = _cfg(0.012)                                   # hex defaults: 6, 1 and 2.5 x the 12 mm wall
    grid = {"parameter": "housing.wall_thickness", "values": [0.010, 0.016]}
    for reuse, want in ((True, [(0.072, 0.012, 0.030)] * 2), (False, [(0.060, 0.010, 0.025), (0.096, 0.016, 0.040)])):
        pts = build(HousingSweepConfig, {**grid, "reuse": reuse}, "housing_sweep").housing_points(base)
        got = [(p.hex_mesh.size, p.hex_mesh.edge, p.hex_mesh.bore) for p in pts]
        assert np.allclose(got, want, rtol=1e-12)
    # a tetrahedral housing keeps its own sizing rule either way
    tet = load_scene(ROOT / "configs" / "housing_sweep.toml").housing
    pts = build(HousingSweepConfig, grid, "housing_sweep").housing_points(tet)
    assert all(p.mesh.size == tet.mesh.size and p.mesh.edge_size is None for p in pts)
