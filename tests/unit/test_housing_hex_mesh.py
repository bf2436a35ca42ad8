"""The structured all-hex housing mesher (geometry/housing_hex.py, hex_grid.py) and the
``[housing.mesh] element`` key: geometry checked against closed forms and topology identities."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from vibrogear.config.base import ConfigError
from vibrogear.config.scene import load_scene
from vibrogear.geometry.hex_grid import (HEX_FACES, axis_lines, boundary_quads, graded_fill, hex_volumes,
                                         merge_hexes, min_corner_jacobian)
from vibrogear.geometry.housing import BASE_TAG, BORE_TAG0, bore_layout, housing_volume
from vibrogear.config.model.housing_mesh import hex_blocks as _blocks
from vibrogear.geometry.housing_hex import hex_housing_arrays
from vibrogear.models.housing.run import housing_cache_keys

ROOT = Path(__file__).resolve().parents[2]
HEX = ('housing.mesh.element="hex"',)


def _cfg(scene="housing.toml", sets=()):
    return load_scene(ROOT / "configs" / scene, HEX + tuple(sets)).housing


@pytest.fixture(scope="module")
def shipped():
    cfg = _cfg()
    return cfg, hex_housing_arrays(cfg)


def test_graded_fill_keeps_ends_grows_by_ratio_and_caps():
    pts = np.concatenate([[0.0], graded_fill(0.0, 1.0, 0.01, 0.01, 0.2, 0.5), [1.0]])
    d = np.diff(pts)
    assert np.all(d > 0) and d.sum() == pytest.approx(1.0)
    # s = h_a + 0.5 x: the first cell solves int_0^d dx / s = 1 -> d = h_a (e^0.5 - 1) / 0.5, and
    # consecutive cells grow by e^0.5 while below the cap (up to the rounding of the cell count)
    first = 0.01 * (math.exp(0.5) - 1) / 0.5
    assert d[0] == pytest.approx(first, rel=0.05) and d[-1] == pytest.approx(first, rel=0.05)
    assert d[1] / d[0] == pytest.approx(math.exp(0.5), rel=0.05)
    assert d.max() <= 0.2 * 1.05 and d.max() >= 0.2 * 0.9
    # an interval of one cell's size is one cell
    assert graded_fill(0.0, 0.012, 0.012, 0.012, 0.07, 0.5).size == 0
    lines = axis_lines({0.0: 0.01, 0.3: 0.01, 0.3 + 1e-12: 0.005}, 0.05, 0.5)
    assert lines[0] == 0.0 and lines[-1] == pytest.approx(0.3) and np.all(np.diff(lines) > 1e-6)


def test_unit_cube_grid_volume_and_boundary():
    xs = np.linspace(0, 1, 3)
    corners = np.array([[(xs[i + di], xs[j + dj], xs[k + dk]) for dk in (0, 1) for dj in (0, 1) for di in (0, 1)]
                        for i in range(2) for j in range(2) for k in range(2)])
    x, cells = merge_hexes(corners)
    assert len(x) == 27 and cells.shape == (8, 8)
    assert hex_volumes(x, cells).sum() == pytest.approx(1.0)
    assert len(boundary_quads(cells)) == 6 * 4
    # a mirrored cell is re-ordered to a positive Jacobian
    bad = corners[:1][:, [1, 0, 3, 2, 5, 4, 7, 6]]
    xb, cb = merge_hexes(bad)
    assert min_corner_jacobian(xb, cb) > 0


def test_shipped_housing_volume_matches_the_closed_form(shipped):
    cfg, (x, cells, facets, values) = shipped
    vol = hex_volumes(x, cells)
    assert vol.min() > 0 and min_corner_jacobian(x, cells) > 0
    # bore and boss circles are polygons of ~30 sides: the solid volume differs from the exact one by
    # (inscribed polygon - circle) areas, < 0.1 % of the housing here
    assert vol.sum() == pytest.approx(housing_volume(cfg), rel=1e-3)


def test_shipped_housing_is_conforming_and_has_the_expected_topology(shipped):
    cfg, (x, cells, facets, values) = shipped
    bq = boundary_quads(cells)
    edges = np.sort(np.concatenate([bq[:, [0, 1]], bq[:, [1, 3]], bq[:, [3, 2]], bq[:, [2, 0]]]), axis=1)
    uniq, count = np.unique(edges, axis=0, return_counts=True)
    # a hanging node would leave a boundary edge used by one face: every edge is shared by two
    assert np.all(count == 2)
    # Euler characteristic of the closed boundary surface: the cavity joined to the outside by
    # 2 x (number of shafts) bores is one surface of genus 2 n - 1: chi = 2 - 2 (2 n - 1)
    n = len(cfg.bores)
    chi = len(np.unique(bq)) - len(uniq) + len(bq)
    assert chi == 2 - 2 * (2 * n - 1)
    # no two cells share all their vertices
    assert len(np.unique(np.sort(cells, axis=1), axis=0)) == len(cells)


def test_one_element_through_each_wall(shipped):
    cfg, (x, cells, facets, values) = shipped
    t, L, W, H = cfg.wall_thickness, cfg.length, cfg.width, cfg.height
    inside = (x[:, 0] > 1e-9) & (x[:, 0] < L - 1e-9) & (x[:, 1] > 1e-9) & (x[:, 1] < W - 1e-9) & \
        (x[:, 2] > 1e-9) & (x[:, 2] < H - 1e-9)
    for k, a in ((0, L), (1, W), (2, H)):
        between = inside & (((x[:, k] > 1e-9) & (x[:, k] < t - 1e-9)) | ((x[:, k] > a - t + 1e-9) & (x[:, k] < a - 1e-9)))
        assert not between.any(), f"a node inside a wall along axis {k}"


def test_facet_groups_base_and_bores(shipped):
    cfg, (x, cells, facets, values) = shipped
    fx = x[facets]
    base = fx[values == BASE_TAG]
    zb = -cfg.base_thickness
    assert np.allclose(base[..., 2], zb)
    o = cfg.base_overhang
    area = 0.5 * np.linalg.norm(np.cross(base[:, 3] - base[:, 0], base[:, 2] - base[:, 1]), axis=1).sum()
    assert area == pytest.approx((cfg.length + 2 * o) * (cfg.width + 2 * o), rel=1e-12)
    for k, g in enumerate(bore_layout(cfg)):
        q = fx[values == BORE_TAG0 + k]
        rad = np.hypot(q[..., 0] - g.center[0], q[..., 2] - g.center[2])
        assert len(q) and np.allclose(rad, g.radius)
        assert q[..., 1].min() == pytest.approx(g.y_range[0]) and q[..., 1].max() == pytest.approx(g.y_range[1])
        # the bore's lateral area: the polygon's perimeter x its length, within the faceting of the circle
        a = np.linalg.norm(np.cross(q[:, 3] - q[:, 0], q[:, 2] - q[:, 1]), axis=1).sum() / 2
        exact = 2 * math.pi * g.radius * (g.y_range[1] - g.y_range[0])
        assert a == pytest.approx(exact, rel=0.01) and a < exact


@pytest.mark.parametrize("sets", [(), ('housing.base="feet"',), ('housing.base="none"',), ("housing.ribs=false",),
                                  ("housing.bores[1].boss_length=0.0",)])
def test_variants_mesh_with_the_exact_volume(sets):
    cfg = _cfg(sets=sets)
    x, cells, facets, values = hex_housing_arrays(cfg)
    assert min_corner_jacobian(x, cells) > 0
    assert hex_volumes(x, cells).sum() == pytest.approx(housing_volume(cfg), rel=1e-3)
    assert set(np.unique(values)) == {BASE_TAG, *range(BORE_TAG0, BORE_TAG0 + 2 * len(cfg.bores))}


def test_small_housing_blocks_are_apart():
    cfg = _cfg("housing_small.toml")
    b = _blocks(cfg)
    assert len(b) == 2 and b[0].x1 <= b[1].x0 and (b[0].z0, b[0].z1) == (b[1].z0, b[1].z1)
    x, cells, _, _ = hex_housing_arrays(cfg)
    assert hex_volumes(x, cells).sum() == pytest.approx(housing_volume(cfg), rel=2e-3)


def test_close_bosses_abut_half_way():
    cfg = _cfg(sets=("housing.bores[2].x=0.375",))        # output boss 9 mm from the middle boss
    b = _blocks(cfg)
    assert b[1].x1 == pytest.approx(b[2].x0)
    assert b[1].x1 == pytest.approx(0.5 * (0.25 + 0.056 + 0.375 - 0.064))
    x, cells, _, _ = hex_housing_arrays(cfg)
    assert min_corner_jacobian(x, cells) > 0
    assert hex_volumes(x, cells).sum() == pytest.approx(housing_volume(cfg), rel=1e-3)


@pytest.mark.parametrize("sets, field", [
    (("housing.bores[2].x=0.36",), "housing.bores[2]"),                 # bosses touch
    (("housing.bores[0].x=0.055",), "housing.bores[0].x"),  # boss on a junction
])
def test_layouts_a_structured_grid_cannot_take_are_refused(sets, field):
    with pytest.raises(ConfigError) as e:             # at load time, before anything is written
        _cfg(sets=sets)
    assert e.value.path == field and "element = 'tet'" in str(e.value)


@pytest.mark.parametrize("sets, field", [
    (("housing.mesh.degree=1",), "housing.mesh.degree"),
    (("housing.mesh.refine=1",), "housing.mesh.refine"),
    (("housing.mesh.edge_distance=0.02",), "housing.mesh.edge_distance"),
    (("housing.mesh.size=0.5",), "housing.mesh.size"),
    (("housing.mesh.edge_size=0.1",), "housing.mesh.edge_size"),
])
def test_bad_hex_mesh_keys_name_the_field(sets, field):
    with pytest.raises(ConfigError) as e:
        _cfg(sets=sets)
    assert e.value.path == field


def test_hex_only_for_the_parametric_housing():
    with pytest.raises(ConfigError) as e:
        load_scene(ROOT / "configs" / "housing_step.toml", HEX)
    assert e.value.path == "housing.mesh.element"


def test_cache_keys_tet_unchanged_hex_distinct():
    assert load_scene(ROOT / "configs" / "housing_small.toml").housing.mesh.element == "tet"   # the default
    tet = load_scene(ROOT / "configs" / "housing.toml", ('housing.mesh.element="tet"',)).housing
    assert "element" not in tet.key_data()["mesh"] and "mesh_element" not in tet.key_data()
    hexc = _cfg()
    me = hexc.key_data()["mesh_element"]
    assert me["element"] == "hex" and me["size_gradient"] == 0.5
    assert (me["size"], me["edge_size"], me["bore_size"]) == pytest.approx((0.072, 0.012, 0.030))
    kt, kh = housing_cache_keys(tet), housing_cache_keys(hexc)
    assert kt[0] != kh[0] and kt[1] != kh[1]
    # a changed hex size changes both keys
    kh2 = housing_cache_keys(dataclasses.replace(hexc, mesh=dataclasses.replace(hexc.mesh, bore_size=0.02)))
    assert kh2[0] != kh[0] and kh2[1] != kh[1]


def test_refused_layout_through_the_cli_exits_2_and_writes_nothing(tmp_path):
    import subprocess
    import sys

    vg = Path(sys.executable).parent / "vibrogear"
    out = tmp_path / "out"
    r = subprocess.run([str(vg), "modes", str(ROOT / "configs" / "housing.toml"), "--out", str(out),
                        "--set", HEX[0], "--set", "housing.bores[2].x=0.36"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "housing.bores[2]" in r.stderr and "element = 'tet'" in r.stderr
    assert not out.exists()
