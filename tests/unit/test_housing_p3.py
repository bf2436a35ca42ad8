"""P3 (cubic Lagrange) housing tetrahedra (issue 23, p-refinement).

* A slender solid cantilever (1 x 0.1 x 0.05 m steel) meshed at 2 x and 1 x its thickness (one or
  two elements through it, like the housing walls): its first two bending frequencies against the
  Timoshenko clamped-free frequency equation (solved here, independently of the FE code; the
  converged 3D solid sits ~0.45 % above beam theory), and the convergence order: P3 must converge
  faster than P2 on the same meshes (errors against a fine P3 solution).
* On one mesh the P2 space lies inside the P3 space, so every P3 frequency is <= the P2 one
  (min-max): checked on ``configs/housing_small.toml`` through the whole pipeline (meshing, bore
  coupling points, skin, XDMF mode shapes interpolated to P1), and the P3 bore values agree with P2's.
* ``mesh.degree = 3`` validates (4 does not) and keys its own modes entry, but shares the mesh entry.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from reference.timoshenko_beam import timoshenko_cantilever_f1
from vibrogear.config import ConfigError
from vibrogear.config.model.housing import MaterialConfig

ROOT = Path(__file__).resolve().parents[2]
SMALL = ROOT / "configs" / "housing_small.toml"
L, B, H = 1.0, 0.1, 0.05
E, NU, RHO = 210e9, 0.3, 7850.0




@pytest.fixture(scope="module")
def beam(tmp_path_factory):
    """{(size, degree): first two frequencies} on the same gmsh meshes."""
    from vibrogear.geometry.housing import build_beam_mesh
    from vibrogear.models.housing.fe import solve_mesh_modes

    d = tmp_path_factory.mktemp("beam")
    mat = MaterialConfig(E=E, nu=NU, rho=RHO)
    out = {}
    for size, degrees in ((2 * H, (2, 3)), (H, (2, 3)), (H / 2, (3,))):
        mesh = build_beam_mesh(L, B, H, d / f"beam{size:g}.msh", size=size)
        for deg in degrees:
            res = solve_mesh_modes(mesh, material=mat, degree=deg, count=4)
            assert res.degree == deg and res.residuals.max() < 1e-6 and res.orthogonality_error < 1e-8
            assert res.mass_kg == pytest.approx(RHO * L * B * H, rel=1e-10)
            out[size, deg] = (res.freqs_hz[:2], res.n_dofs)
    return out


def test_p3_bending_matches_timoshenko_with_one_element_through_the_thickness(beam):
    f_ref = np.array([timoshenko_cantilever_f1(E=E, nu=NU, rho=RHO, L=L, b=B, h=H),
                      timoshenko_cantilever_f1(E=E, nu=NU, rho=RHO, L=L, b=H, h=B)])
    p2, p3 = beam[2 * H, 2][0], beam[2 * H, 3][0]
    rel2, rel3 = (p2 - f_ref) / f_ref, (p3 - f_ref) / f_ref
    print(f"size 2H: P2 {rel2}, P3 {rel3} vs Timoshenko {f_ref}")
    # the 3D solid is above beam theory (~0.45 % here); P3 on the coarse mesh stays within 0.7 %
    assert np.all(rel3 > 0.0) and np.all(rel3 < 0.007)
    assert np.all(p3 < p2)                       # nested spaces on one mesh: P3 below P2


def test_p3_converges_faster_than_p2(beam):
    ref = beam[H / 2, 3][0]                      # fine P3 (~35k DOF)
    e = {k: (v[0] - ref) / ref for k, v in beam.items() if k[0] > H / 2}
    for size in (2 * H, H):
        assert np.all(e[size, 3] > 0.0)
        assert np.all(e[size, 3] < e[size, 2] / 2.5), (size, e[size, 2], e[size, 3])
    order = {d: np.log(e[2 * H, d] / e[H, d]) / np.log(2.0) for d in (2, 3)}
    print(f"errors vs fine P3: {e}; observed orders {order}")
    assert np.all(order[3] > order[2])
    # P3 on the coarse mesh (~3.8k DOF) beats P2 on the mesh of half the size (~2.8k DOF)
    assert np.all(e[2 * H, 3] < e[H, 2])


@pytest.fixture(scope="module")
def small_p2_p3():
    from vibrogear.analyses.housing.convergence import with_mesh
    from vibrogear.config import load_scene
    from vibrogear.models.housing.run import housing_modes

    cfg = load_scene(SMALL).housing
    out = {}
    for deg in (2, 3):
        c = with_mesh(cfg, degree=deg, count=8)
        c = dataclasses.replace(c, modes=dataclasses.replace(c.modes, shapes=2))
        out[deg] = housing_modes(c, cache=False)
    return out


def test_p3_housing_pipeline_below_p2_on_the_same_mesh(small_p2_p3):
    p2, p3 = small_p2_p3[2], small_p2_p3[3]
    assert p3.degree == 3 and p3.n_dofs > 2.5 * p2.n_dofs
    assert np.all(p3.freqs_hz <= p2.freqs_hz * (1 + 1e-9))
    assert np.all(p3.freqs_hz > 0.9 * p2.freqs_hz)
    assert p3.residuals.max() < 1e-6 and p3.orthogonality_error < 1e-8
    assert p3.mass_kg == pytest.approx(p2.mass_kg, rel=1e-10)
    # coupling points: finite, and mode 1 at the bores the same shape as P2's (up to sign)
    a, b = p2.bore_values[..., 0], p3.bore_values[..., 0]
    ok = np.isfinite(a) & np.isfinite(b)
    assert ok.sum() > 0 and np.isfinite(b[np.isfinite(a)]).all()
    mac = np.dot(a[ok], b[ok]) ** 2 / (np.dot(a[ok], a[ok]) * np.dot(b[ok], b[ok]))
    assert mac > 0.99
    # XDMF mode shapes (P1 interpolation of the P3 field) written
    assert p3.shapes_path is not None and Path(p3.shapes_path).is_file()
    # outer-skin normal displacements (edge midpoints, evaluated from the P3 field): finite
    assert p3.surface_values.shape[-1] == p3.freqs_hz.size and np.isfinite(p3.surface_values).all()
    assert len(p3.surface_centers) == len(p2.surface_centers)         # same mesh, same skin


def test_degree_3_validates_and_keys_its_own_modes_entry():
    from vibrogear.analyses.housing.convergence import with_mesh
    from vibrogear.config import load_scene
    from vibrogear.models.housing.run import housing_cache_key

    cfg = load_scene(SMALL).housing
    c2, c3 = with_mesh(cfg, degree=2), with_mesh(cfg, degree=3)
    assert c3.mesh.degree == 3
    assert housing_cache_key(c2, "mesh") == housing_cache_key(c3, "mesh")
    for stage in ("modes", "matrices"):
        assert housing_cache_key(c2, stage) != housing_cache_key(c3, stage)
    with pytest.raises(ConfigError) as exc:
        with_mesh(cfg, degree=4)
    assert "housing.mesh.degree" in str(exc.value)


@pytest.mark.slow
def test_p3_full_matrices_reproduce_the_modes_and_bore_values(small_p2_p3):
    """Serial full matrices of the P3 housing (the reduction checks' path): eigsh of (K, M) gives
    the P3 master frequencies, and T (one probe per P3 node) the bore values; T is a partition of
    unity (a rigid y translation is 1 at every coupling point).  ~14 s (T is built node by node)."""
    import scipy.sparse.linalg as spla

    from vibrogear.analyses.housing.convergence import with_mesh
    from vibrogear.config import load_scene
    from vibrogear.models.housing.run import housing_matrices

    modes = small_p2_p3[3]
    mats = housing_matrices(with_mesh(load_scene(SMALL).housing, degree=3, count=8), cache=False)
    assert mats.n_dofs_total == modes.n_dofs
    n = 4
    lam, X = spla.eigsh(mats.K, k=n, M=mats.M, sigma=0.0, which="LM")
    order = np.argsort(lam)
    lam, X = lam[order], X[:, order]
    X /= np.sqrt(np.einsum("ij,ij->j", X, mats.M @ X))
    assert np.allclose(np.sqrt(lam) / (2 * np.pi), modes.freqs_hz[:n], rtol=1e-6, atol=0)
    B, P = modes.bore_values.shape[:2]
    ref = np.nan_to_num(modes.bore_values[..., :n]).reshape(B * P * 3, n)
    TX = mats.T @ X
    sign = np.sign(np.einsum("ij,ij->j", TX, ref))
    assert np.abs(TX * sign - ref).max() < 1e-6 * np.abs(ref).max()
    pad = np.zeros((B, P, 3), dtype=bool)
    for i, k in enumerate(modes.bore_n_points):
        pad[i, k:] = True
    ones = np.zeros(mats.n_dofs)
    ones[mats.free_dofs % 3 == 1] = 1.0
    ty = (mats.T @ ones).reshape(B, P, 3)
    assert np.allclose(ty[~pad[..., 0], 1], 1.0, atol=1e-12) and np.allclose(ty[..., [0, 2]], 0.0)
