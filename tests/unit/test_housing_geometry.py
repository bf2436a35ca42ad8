"""gmsh housing geometry against closed forms: solid volume, bore surface areas, base area,
physical groups, and the bearing coupling points (paper section II.A: one per rolling element,
uniformly spaced on the bore circumference)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from vibrogear.config import load_scene
from vibrogear.config.base import build
from vibrogear.config.model.housing import HousingConfig
from vibrogear.geometry.housing import (BASE_TAG, bore_layout, build_housing_mesh, housing_volume,
                                        read_msh_arrays)
from pathlib import Path
from mesh_measures import tet_volume, tri_area

SMALL = Path(__file__).resolve().parents[2] / "configs" / "housing_small.toml"


@pytest.mark.parametrize("variant", [dict(), dict(base="feet", ribs=True), dict(base="none", ribs=True)])
def test_mesh_volume_and_groups_match_closed_form(tmp_path, variant):
    import dataclasses
    d = dataclasses.asdict(load_scene(SMALL).housing)
    d = {k: v for k, v in d.items() if v is not None}
    d["mesh"] = {"size": 0.03, "degree": 2}
    d.update(variant)
    cfg = build(HousingConfig, d, "housing")
    hm = build_housing_mesh(cfg, tmp_path / "h.msh")
    x, tets, facets, values = read_msh_arrays(hm.path)
    # solid volume: faceted cylinders are inscribed polygons, bores cut slightly less -> tolerance 0.3 %
    assert tet_volume(x, tets) == pytest.approx(housing_volume(cfg), rel=3e-3)
    # base area: plate / feet / box bottom (exact planar faces)
    L, W = cfg.length, cfg.width
    base_area = {"plate": (L + 2 * cfg.base_overhang) * (W + 2 * cfg.base_overhang),
                 "feet": 4 * cfg.foot_size ** 2, "none": L * W}[cfg.base]
    if cfg.base == "none" and cfg.ribs:  # rib feet stand on the ground too
        base_area += sum(2 * cfg.rib_t * b.boss_length for b in cfg.bores)
    assert tri_area(x, facets[values == BASE_TAG]) == pytest.approx(base_area, rel=1e-9)
    # each bore surface: lateral area 2 pi r l of its cylinder (inscribed facets: within 2 %)
    layout = bore_layout(cfg)
    assert len(hm.bore_tags) == len(layout) == 2 * len(cfg.bores)
    for g, tag in zip(layout, hm.bore_tags):
        tris = facets[values == tag]
        assert len(tris) > 0
        r = np.hypot(x[tris.ravel(), 0] - g.center[0], x[tris.ravel(), 2] - g.center[2])
        assert np.allclose(r, g.radius, rtol=1e-6), "bore group holds faces off the bore cylinder"
        length = g.y_range[1] - g.y_range[0]
        assert tri_area(x, tris) == pytest.approx(2 * math.pi * g.radius * length, rel=0.02)


def test_coupling_points_uniform_on_bore_circle():
    cfg = load_scene(SMALL).housing
    layout = bore_layout(cfg)
    names = [g.name for g in layout]
    assert names == ["input/front", "input/back", "output/front", "output/back"]
    for g, b in zip(layout, [cfg.bores[0], cfg.bores[0], cfg.bores[1], cfg.bores[1]]):
        p = g.points()
        assert p.shape == (b.rolling_elements, 3)
        rel = p - np.array(g.center)
        assert np.allclose(np.hypot(rel[:, 0], rel[:, 2]), b.bore_radius)
        assert np.allclose(rel[:, 1], 0.0)
        ang = np.unwrap(np.arctan2(rel[:, 2], rel[:, 0]))
        assert np.allclose(np.diff(ang), 2 * math.pi / b.rolling_elements)
        assert ang[0] == pytest.approx(0.0)
    # front bore centre mid-way through wall + boss (y in [-boss_length, t]); back mirrored
    t, W, lb = cfg.wall_thickness, cfg.width, cfg.bores[0].boss_length
    assert layout[0].center[1] == pytest.approx((t - lb) / 2)
    assert layout[1].center[1] == pytest.approx(W - (t - lb) / 2)
    assert layout[0].axis == (0.0, -1.0, 0.0) and layout[1].axis == (0.0, 1.0, 0.0)


def _graded_cfg(**mesh):
    import dataclasses
    d = dataclasses.asdict(load_scene(SMALL).housing)
    d = {k: v for k, v in d.items() if v is not None}
    d["mesh"] = {"size": 0.03, "degree": 2, **mesh}
    return build(HousingConfig, d, "housing")


def _tet_sizes_near_far(path, cfg):
    """Median element size (edge of the regular tet of the same volume) of the tets near the
    x = 0 wall's junctions with the base (outer edge x = 0, z = 0 and inner edge x = t, z = t)
    and of those far from every junction (mid-wall)."""
    x, tets, _, _ = read_msh_arrays(path)
    P = x[tets]
    vol = np.abs(np.einsum("ij,ij->i", P[:, 1] - P[:, 0], np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 0]))) / 6
    size = (6 * math.sqrt(2) * vol) ** (1 / 3)
    c = P.mean(axis=1)
    t, W = cfg.wall_thickness, cfg.width
    mid_y = (c[:, 1] > 0.25 * W) & (c[:, 1] < 0.75 * W)
    d_out = np.hypot(c[:, 0], c[:, 2])
    d_in = np.hypot(c[:, 0] - t, c[:, 2] - t)
    near = mid_y & (np.minimum(d_out, d_in) < 0.006)
    far = (c[:, 0] < t) & (c[:, 1] > 0.3 * W) & (c[:, 1] < 0.7 * W) & (c[:, 2] > 0.06) & (c[:, 2] < 0.10)
    assert near.sum() >= 3 and far.sum() >= 3
    return np.median(size[near]), np.median(size[far])


def test_edge_grading_refines_near_junction_edges(tmp_path):
    plain = _graded_cfg()
    graded = _graded_cfg(edge_size=0.0075, edge_distance=0.03)
    hp = build_housing_mesh(plain, tmp_path / "plain.msh")
    hg = build_housing_mesh(graded, tmp_path / "graded.msh")
    near_p, far_p = _tet_sizes_near_far(hp.path, plain)
    near_g, far_g = _tet_sizes_near_far(hg.path, graded)
    assert near_p > 0.75 * far_p                    # uniform: no grading
    assert near_g < 0.6 * far_g                     # graded: about half the size at the junctions
    assert near_g < 0.6 * near_p                    # ... than the uniform mesh there
    assert far_g == pytest.approx(far_p, rel=0.2)   # and the bulk about unchanged
    assert hg.n_tets > hp.n_tets
    x, tets, _, _ = read_msh_arrays(hg.path)        # still the same solid
    assert tet_volume(x, tets) == pytest.approx(housing_volume(graded), rel=3e-3)


def test_junction_curves_are_the_reentrant_edges():
    from vibrogear.geometry.housing import _housing_solid, gmsh_session, junction_curves
    cfg = _graded_cfg()
    t, L, W, H = cfg.wall_thickness, cfg.length, cfg.width, cfg.height
    with gmsh_session() as gmsh:
        _housing_solid(gmsh, cfg)
        mids = []
        for c in junction_curves(gmsh):
            b = gmsh.model.getBoundingBox(1, c)
            mids.append(tuple(round(0.5 * (b[i] + b[i + 3]), 4) for i in range(3)))
    # the 12 inner box edges (concave seen from the solid) are all there ...
    inner = [m for m in mids if t - 1e-6 <= min(m[0], L - m[0]) and t - 1e-6 <= min(m[1], W - m[1])
             and t - 1e-6 <= m[2] <= H - t + 1e-6]
    assert len(inner) == 12
    # ... the outer wall/plate edges at z = 0, and no convex edge (outer box top, plate rim)
    assert any(abs(m[0]) < 1e-6 and abs(m[2]) < 1e-6 for m in mids)
    assert not any(abs(m[2] - H) < 1e-6 or m[2] < -1e-6 for m in mids)


@pytest.mark.parametrize("mesh, field", [
    (dict(edge_size=0.05), "housing.mesh.edge_size"),        # > size
    (dict(edge_size=1e-5), "housing.mesh.edge_size"),        # < wall / 50
    (dict(edge_size=-0.01), "housing.mesh.edge_size"),       # <= 0
    (dict(edge_distance=0.02), "housing.mesh.edge_distance"),  # without edge_size
    (dict(edge_size=0.01, edge_distance=0.0), "housing.mesh.edge_distance"),
])
def test_edge_grading_keys_validate(mesh, field):
    from vibrogear.config.base import ConfigError
    with pytest.raises(ConfigError) as ei:
        _graded_cfg(**mesh)
    assert ei.value.path == field and field in str(ei.value)


def test_edge_grading_cache_keys():
    from vibrogear.models.housing.run import housing_cache_keys
    plain, graded = _graded_cfg(), _graded_cfg(edge_size=0.0075)
    assert "mesh_grading" not in plain.key_data()
    assert "edge_size" not in plain.key_data()["mesh"]  # ungraded scenes keep their cache keys
    kp, kg = housing_cache_keys(plain), housing_cache_keys(graded)
    assert kp[0] != kg[0] and kp[1] != kg[1]            # the mesh entry too
    assert graded.key_data()["mesh_grading"] == {"edge_size": 0.0075, "edge_distance": 2 * graded.wall_thickness}
