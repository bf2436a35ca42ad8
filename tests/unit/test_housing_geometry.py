"""gmsh housing geometry against closed forms: solid volume, bore surface areas, base area,
physical groups, and the bearing coupling points (paper section II.A: one per rolling element,
uniformly spaced on the bore circumference)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from vibrogear.config import load_scene
from vibrogear.config.base import build
from vibrogear.config.housing import HousingConfig
from vibrogear.geometry.housing import (BASE_TAG, bore_layout, build_housing_mesh, housing_volume,
                                        read_msh_arrays)
from pathlib import Path

SMALL = Path(__file__).resolve().parents[2] / "configs" / "housing_small.toml"


def _tet_volume(x, tets):
    a, b, c, d = (x[tets[:, i]] for i in range(4))
    return np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))).sum() / 6.0


def _tri_area(x, tris):
    a, b, c = (x[tris[:, i]] for i in range(3))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()


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
    assert _tet_volume(x, tets) == pytest.approx(housing_volume(cfg), rel=3e-3)
    # base area: plate / feet / box bottom (exact planar faces)
    L, W = cfg.length, cfg.width
    base_area = {"plate": (L + 2 * cfg.base_overhang) * (W + 2 * cfg.base_overhang),
                 "feet": 4 * cfg.foot_size ** 2, "none": L * W}[cfg.base]
    if cfg.base == "none" and cfg.ribs:  # rib feet stand on the ground too
        base_area += sum(2 * cfg.rib_t * b.boss_length for b in cfg.bores)
    assert _tri_area(x, facets[values == BASE_TAG]) == pytest.approx(base_area, rel=1e-9)
    # each bore surface: lateral area 2 pi r l of its cylinder (inscribed facets: within 2 %)
    layout = bore_layout(cfg)
    assert len(hm.bore_tags) == len(layout) == 2 * len(cfg.bores)
    for g, tag in zip(layout, hm.bore_tags):
        tris = facets[values == tag]
        assert len(tris) > 0
        r = np.hypot(x[tris.ravel(), 0] - g.center[0], x[tris.ravel(), 2] - g.center[2])
        assert np.allclose(r, g.radius, rtol=1e-6), "bore group holds faces off the bore cylinder"
        length = g.y_range[1] - g.y_range[0]
        assert _tri_area(x, tris) == pytest.approx(2 * math.pi * g.radius * length, rel=0.02)


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
