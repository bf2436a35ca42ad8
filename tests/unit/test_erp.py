"""Equivalent radiated power and the housing's outer surface against closed forms.

* a synthetic flat surface: the quadrature of phi_n^2 and the ERP of one mode driven at one
  frequency equal the analytic integrals;
* housing_small (real FE modes, fresh cache): the outer surface's area equals the box's
  analytic outer area (less base and bores) within the faceting of the circles; the ERP of
  each housing mode driven alone at one frequency equals 1/2 rho c (omega a)^2 sum phi_n^2 dA;
  the surface-velocity XDMF reads back with meshio with the right counts and values;
* a cache entry of the older layout (no surface data) is not read as one without it.
"""
from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

from vibrogear.analyses.nvh.housing_surface import (SurfaceMap, erp_db, erp_spectrum, erp_watts,
    rms_velocity_field)
from vibrogear.config import load_scene

ROOT = Path(__file__).resolve().parents[2]
SMALL = ROOT / "configs" / "housing_small.toml"
RHO, C = 1.2, 343.0


def _harmonic_rates(m: int, mode: int, a: float, omega: float, periods: int = 3, S: int = 32):
    """Modal velocities (m, n): mode ``mode`` moves as a sin(omega t), sampled over whole
    periods."""
    t = np.arange(periods * S) * (2 * np.pi / omega / S)
    rates = np.zeros((m, t.size))
    rates[mode] = a * omega * np.cos(omega * t)
    return rates


def _unit_square(values) -> SurfaceMap:
    """The unit square z = 0 as two triangles; ``values(x, y)`` -> (m,) phi_n at a point."""
    verts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    tris = np.array([[0, 1, 2], [0, 2, 3]])
    mids = 0.5 * (verts[tris] + verts[tris][:, [1, 2, 0]])          # (2, 3, 3)
    vals = np.array([[values(*p[:2]) for p in f] for f in mids])     # (2, 3, m)
    return SurfaceMap(columns=np.arange(vals.shape[-1]), values=vals,
                      weights=np.full((2, 3), 0.5 / 3), vertices=verts, triangles=tris,
                      areas=np.array([0.5, 0.5]))


def test_synthetic_surface_closed_forms():
    # mode 0: phi_n = 1; mode 1: phi_n = x (integral of x^2 over the square = 1/3)
    smap = _unit_square(lambda x, y: np.array([1.0, x]))
    assert np.allclose(smap.gram, [[1.0, 0.5], [0.5, 1.0 / 3.0]], rtol=1e-14)
    a, w = 2e-6, 2 * np.pi * 800.0
    for mode, integral in ((0, 1.0), (1, 1.0 / 3.0)):
        erp = erp_watts(smap.gram, _harmonic_rates(2, mode, a, w), RHO, C)
        assert erp == pytest.approx(0.5 * RHO * C * (w * a) ** 2 * integral, rel=1e-12)
    # RMS velocity of mode 0: (omega a) / sqrt(2) on every facet
    v = rms_velocity_field(smap, _harmonic_rates(2, 0, a, w))
    assert np.allclose(v, w * a / math.sqrt(2), rtol=1e-12)
    assert erp_db(1e-12) == pytest.approx(0.0) and erp_db(1.0) == pytest.approx(120.0)


def test_erp_per_bin_two_harmonics():
    """Mode 0 (phi_n = 1) at omega and mode 1 (phi_n = x) at 3 omega over R = 4 periods: the
    ERP of bin 4 is 1/2 rho c (omega a)^2 * 1, of bin 12 1/2 rho c (3 omega b)^2 / 3, nothing
    elsewhere, and the bins sum to the time average."""
    smap = _unit_square(lambda x, y: np.array([1.0, x]))
    a, b, w, R, S = 3e-6, 1e-6, 2 * np.pi * 450.0, 4, 16
    t = np.arange(R * S) * (2 * np.pi / w / S)
    rates = np.array([a * w * np.cos(w * t), 3 * w * b * np.sin(3 * w * t + 0.3)])
    p = erp_spectrum(smap.gram, rates, RHO, C)
    expect = np.zeros(R * S // 2 + 1)
    expect[R] = 0.5 * RHO * C * (w * a) ** 2
    expect[3 * R] = 0.5 * RHO * C * (3 * w * b) ** 2 / 3.0
    assert np.allclose(p, expect, rtol=1e-12, atol=1e-12 * expect.max())
    assert p.sum() == pytest.approx(erp_watts(smap.gram, rates, RHO, C), rel=1e-12)


def _analytic_outer_area(c) -> float:
    """Outer area of the housing_small solid less its base face and bore surfaces: box top
    and sides, base plate sides and top rim, bosses (wall disc pi R^2 replaced by the boss's
    side 2 pi R l and end ring pi (R^2 - r^2))."""
    L, W, H, o, tb = c.length, c.width, c.height, c.base_overhang, c.base_thickness
    area = L * W + 2 * (L + W) * H                         # box top and four walls
    area += 2 * (L + 2 * o + W + 2 * o) * tb               # plate sides
    area += (L + 2 * o) * (W + 2 * o) - L * W              # plate rim around the box
    for b in c.bores:                                      # one boss each side
        area += 2 * (2 * math.pi * b.boss_radius * b.boss_length - math.pi * b.bore_radius ** 2)
    return area


@pytest.fixture(scope="module")
def small_modes(tmp_path_factory):
    d = tmp_path_factory.mktemp("vgcache")
    old = os.environ.get("VIBROGEAR_CACHE_DIR")
    os.environ["VIBROGEAR_CACHE_DIR"] = str(d)
    try:
        from vibrogear.models.housing.run import housing_modes
        scene = load_scene(SMALL)
        yield scene.housing, housing_modes(scene.housing)
    finally:
        if old is None:
            os.environ.pop("VIBROGEAR_CACHE_DIR")
        else:
            os.environ["VIBROGEAR_CACHE_DIR"] = old


def _map(hm) -> SurfaceMap:
    return SurfaceMap(columns=np.arange(hm.n_modes), values=hm.surface_values,
                      weights=hm.surface_weights, vertices=hm.surface_vertices,
                      triangles=hm.surface_triangles, areas=hm.surface_areas)


def test_outer_surface_area_is_the_box_area(small_modes):
    cfg, hm = small_modes
    assert hm.has_surface and hm.surface_values.shape == (hm.surface_areas.size, 3, hm.n_modes)
    exact = _analytic_outer_area(cfg)
    assert hm.surface_areas.sum() == pytest.approx(exact, rel=1e-2)      # faceted circles
    assert np.allclose(hm.surface_weights.sum(axis=1), hm.surface_areas, rtol=1e-14)
    # no inner cavity wall (x = t or L - t, ...) and nothing on the base face z = -tb
    c, t = hm.surface_centers, cfg.wall_thickness
    inner = ((np.abs(c[:, 0] - t) < 1e-9) | (np.abs(c[:, 0] - (cfg.length - t)) < 1e-9)
             | (np.abs(c[:, 2] - (cfg.height - t)) < 1e-9))
    assert not np.any(inner)
    assert not np.any(np.abs(c[:, 2] + cfg.base_thickness) < 1e-9)
    # the triangles are oriented outward: +z on the top face, -x on the wall x = 0
    tri = hm.surface_vertices[hm.surface_triangles]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    top, wall = np.abs(c[:, 2] - cfg.height) < 1e-9, np.abs(c[:, 0]) < 1e-9
    assert top.sum() > 4 and wall.sum() > 4
    assert np.all(n[top, 2] > 0) and np.all(n[wall, 0] < 0)


def test_single_mode_erp_closed_form(small_modes):
    _, hm = small_modes
    smap = _map(hm)
    for i in (0, 3, hm.n_modes - 1):
        w = hm.omegas[i] * 0.7
        a = 1e-3 / math.sqrt(hm.mass_kg)                  # modal amplitude (mass-normalised)
        phi2 = float(np.sum(hm.surface_weights * hm.surface_values[..., i] ** 2))
        closed = 0.5 * RHO * C * (w * a) ** 2 * phi2
        erp = erp_watts(smap.gram, _harmonic_rates(hm.n_modes, i, a, w), RHO, C)
        assert erp == pytest.approx(closed, rel=1e-10)
        assert closed > 0


def test_surface_velocity_xdmf_reads_back(small_modes, tmp_path):
    import meshio
    from vibrogear.report.writers.nvh import write_surface_velocity

    _, hm = small_modes
    rates = _harmonic_rates(hm.n_modes, 1, 1e-4, 2 * np.pi * 500.0)
    v = rms_velocity_field(_map(hm), rates)
    path = write_surface_velocity(tmp_path / "surface_velocity_2400.xdmf", hm.surface_vertices,
                                  hm.surface_triangles, v)
    assert path.with_suffix(".h5").exists()
    m = meshio.read(path)
    assert m.points.shape == hm.surface_vertices.shape
    assert m.cells[0].type == "triangle" and m.cells[0].data.shape == hm.surface_triangles.shape
    assert np.allclose(m.cell_data["v_rms"][0], v, rtol=1e-14)
    assert np.array_equal(m.cells[0].data, hm.surface_triangles)


def test_old_cache_layout_is_not_misread(small_modes, tmp_path):
    """An entry of the older layout (modes.npz without the surface arrays) fails to load, so
    the cache discards and rebuilds it (and its key differs from the new layout's anyway)."""
    from vibrogear.cache import cache_key
    from vibrogear.models.housing.result import load_modes, save_modes
    from vibrogear.models.housing.run import housing_cache_key

    cfg, hm = small_modes
    assert housing_cache_key(cfg, "modes") != cache_key("housing-modes", cfg.key_data())
    save_modes(hm, tmp_path / "entry")
    with np.load(tmp_path / "entry" / "modes.npz") as z:
        old = {k: z[k] for k in z.files if not k.startswith("surface_")}
    np.savez(tmp_path / "entry" / "modes.npz", **old)
    with pytest.raises(KeyError):
        load_modes(tmp_path / "entry")


def test_surface_map_takes_the_housing_coordinates(small_modes):
    """The reduced model's housing coordinates (after the shafts', in subsystem order) and
    its time unit 1/omega_ref: a housing modal rate of 1 model unit is omega_ref 1/s."""
    from types import SimpleNamespace

    from vibrogear.analyses.nvh.housing_surface import surface_map
    from vibrogear.models.gearbox.synthesis import Subsystem

    _, hm = small_modes
    shaft = Subsystem(name="s", kind="shaft", n_dofs=12, freqs_hz=np.arange(1.0, 6.0),
                      vectors=np.zeros((12, 5)), damping_ratio=np.zeros(5))
    m_h = 4                                               # the scene keeps 4 housing modes
    house = Subsystem(name="housing", kind="housing", n_dofs=hm.n_dofs,
                      freqs_hz=hm.freqs_hz[:m_h], vectors=np.zeros((3, m_h)),
                      damping_ratio=np.zeros(m_h))
    gm = SimpleNamespace(housing=hm, subsystems=(shaft, house), omega_ref=1234.0)
    smap, note = surface_map(gm)
    assert note == "" and np.array_equal(smap.columns, 5 + np.arange(m_h))
    n = 5 + m_h
    states = np.zeros((2, 2 * n))
    states[:, n + 5 + 2] = 1.0                            # housing mode 2's rate
    rates = smap.modal_rates(states, n)
    assert rates.shape == (m_h, 2) and np.allclose(rates[2], 1234.0)
    assert np.allclose(np.delete(rates, 2, axis=0), 0.0)
    assert surface_map(SimpleNamespace(housing=None))[0] is None


def test_surface_values_match_the_boundary_dof_values(small_modes):
    """A second path to phi_n: the edge midpoints of the P2 surface facets are P2 nodes, so
    the mode's nodal displacement there (the boundary-DOF preview, read straight from the
    eigenvectors) dotted with the facet's outward unit normal is phi_n."""
    from scipy.spatial import cKDTree

    _, hm = small_modes
    tri = hm.surface_vertices[hm.surface_triangles]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    mids = 0.5 * (tri + tri[:, [1, 2, 0]])                              # (nf, 3, 3)
    dist, idx = cKDTree(hm.preview_points).query(mids.reshape(-1, 3))
    hit = dist < 1e-9
    assert hit.mean() > 0.5                                             # most are in the preview
    k = hm.preview_values.shape[-1]
    dofs = hm.preview_values[idx[hit]]                                  # (h, 3, k)
    normals = np.repeat(n, 3, axis=0)[hit]
    ref = np.einsum("hck,hc->hk", dofs, normals)
    got = hm.surface_values.reshape(-1, hm.n_modes)[hit, :k]
    assert np.max(np.abs(got - ref)) < 1e-8 * np.max(np.abs(ref))
