"""Inner walls of the parametric housing (``[housing] inner_walls``): the meshed solid volume
against the closed form, a bore surface on every wall of every shaft axis, the bores'
numbering (per shaft, front -> inner walls -> back), the coupling points in the inner wall's
middle plane, the default's keys unchanged, and bad input naming the field."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from vibrogear.config import ConfigError, load_scene
from vibrogear.config.base import as_data, build
from vibrogear.config.model.housing import HousingConfig
from vibrogear.config.model.layout import bore_spans
from vibrogear.geometry.housing import bore_layout, build_housing_mesh, housing_volume, read_msh_arrays
from mesh_measures import tet_volume, tri_area

ROOT = Path(__file__).resolve().parents[2]
SMALL = ROOT / "configs" / "housing_small.toml"


def _cfg(**kw) -> HousingConfig:
    d = as_data(load_scene(SMALL).housing)
    d.update(kw)
    return build(HousingConfig, d, "housing")


@pytest.mark.parametrize("walls", [(0.08,), (0.06, 0.11)])
def test_volume_and_a_bore_on_every_wall(tmp_path, walls):
    cfg = _cfg(inner_walls=list(walls))
    L, H, t = cfg.length, cfg.height, cfg.wall_thickness
    # the closed form by hand: the plain box's volume + per wall a (L - 2t) t (H - 2t) plate
    # less a bore cylinder pi r^2 t per shaft axis
    plate = (L - 2 * t) * t * (H - 2 * t) - sum(math.pi * b.bore_radius ** 2 * t for b in cfg.bores)
    assert housing_volume(cfg) == pytest.approx(housing_volume(_cfg()) + len(walls) * plate, rel=1e-14)
    hm = build_housing_mesh(cfg, tmp_path / "h.msh")
    x, tets, facets, values = read_msh_arrays(hm.path)
    # inscribed (faceted) bores cut a little less than the circles: measured +0.07 % (one wall),
    # +0.11 % (two walls) at size 0.03; the plain box's test allows 0.3 %
    assert tet_volume(x, tets) == pytest.approx(housing_volume(cfg), rel=3e-3)
    layout = bore_layout(cfg)
    n = len(walls)
    sides = ["front"] + [f"inner{k + 1}" for k in range(n)] + ["back"]
    assert [g.name for g in layout] == [f"{b.name}/{s}" for b in cfg.bores for s in sides]
    assert len(hm.bore_tags) == len(layout) == (n + 2) * len(cfg.bores)
    for g, tag in zip(layout, hm.bore_tags):
        tris = facets[values == tag]
        assert len(tris) > 0, f"no surface found for bore {g.name}"
        r = np.hypot(x[tris.ravel(), 0] - g.center[0], x[tris.ravel(), 2] - g.center[2])
        assert np.allclose(r, g.radius, rtol=1e-6), "bore group holds faces off the bore cylinder"
        y = x[tris.ravel(), 1]
        assert y.min() >= g.y_range[0] - 1e-9 and y.max() <= g.y_range[1] + 1e-9
        length = g.y_range[1] - g.y_range[0]
        assert tri_area(x, tris) == pytest.approx(2 * math.pi * g.radius * length, rel=0.02)
    for k, yw in enumerate(walls):               # inner bores: the wall's thickness, points mid-wall
        for i, b in enumerate(cfg.bores):
            g = layout[i * (n + 2) + 1 + k]
            assert g.y_range == pytest.approx((yw - t / 2, yw + t / 2))
            assert np.allclose(g.points()[:, 1], yw)
            assert g.n_points == b.rolling_elements
        assert bore_spans(cfg, cfg.bores[0])[f"inner{k + 1}"] == pytest.approx((yw - t / 2, yw + t / 2))


def test_no_inner_walls_keeps_numbering_and_cache_keys():
    cfg = _cfg()
    assert cfg.inner_walls == ()
    assert "inner_walls" not in cfg.key_data()        # cache keys of existing scenes unchanged
    assert [g.name for g in bore_layout(cfg)] == ["input/front", "input/back", "output/front", "output/back"]
    assert _cfg(inner_walls=[0.08]).key_data()["inner_walls"] == (0.08,)


@pytest.mark.parametrize("kw, field, text", [
    (dict(inner_walls=[0.2]), "housing.inner_walls[0]", "(0, width) = (0, 0.16)"),
    (dict(inner_walls=[-0.05]), "housing.inner_walls[0]", "> 0"),
    (dict(inner_walls=[float("nan")]), "housing.inner_walls[0]", "finite"),
    (dict(inner_walls=[0.02]), "housing.inner_walls[0]", "too close to the front wall"),
    (dict(inner_walls=[0.135]), "housing.inner_walls[0]", "too close to the back wall"),
    (dict(inner_walls=[0.06, 0.07]), "housing.inner_walls[1]", "may not overlap"),
    (dict(inner_walls=[0.11, 0.06]), "housing.inner_walls[1]", "ascending"),
    (dict(inner_walls=[0.08], mesh={"element": "hex"}), "housing.inner_walls", "element = 'tet'"),
])
def test_bad_inner_walls_name_the_field(kw, field, text):
    with pytest.raises(ConfigError) as exc:
        _cfg(**kw)
    assert exc.value.path == field and text in str(exc.value)


def test_coupling_points_per_wall():
    d = as_data(load_scene(SMALL).housing)
    d["inner_walls"] = [0.08]
    d["bores"][1]["wall_rolling_elements"] = [10, 25, 12]
    cfg = build(HousingConfig, d, "housing")
    n = {g.name: g.n_points for g in bore_layout(cfg)}
    assert n == {"input/front": 8, "input/inner1": 8, "input/back": 8,
                 "output/front": 10, "output/inner1": 25, "output/back": 12}
    assert len(bore_layout(cfg)[4].points()) == 25
    assert "wall_rolling_elements" not in cfg.key_data()["bores"][0]
    d["bores"][1]["wall_rolling_elements"] = [10, 25]
    with pytest.raises(ConfigError) as exc:
        build(HousingConfig, d, "housing")
    assert exc.value.path == "housing.bores[1].wall_rolling_elements" and "3 entries" in str(exc.value)
    d["bores"][1]["wall_rolling_elements"] = [10, 2, 12]
    with pytest.raises(ConfigError) as exc:
        build(HousingConfig, d, "housing")
    assert exc.value.path == "housing.bores[1].wall_rolling_elements[1]"


def test_bad_inner_wall_through_the_cli_exits_2(tmp_path):
    import contextlib
    import io

    from vibrogear.cli import main
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = main(["check", str(SMALL), "--set", "housing.inner_walls=[0.3]"])
    assert rc == 2 and "housing.inner_walls[0]" in err.getvalue()


def test_regions_of_an_inner_wall_and_its_bores():
    """Pure geometry of the pictures' regions: a point nearer the inner wall's middle plane
    than any outer wall plane is the inner wall's (region 6 + B), an inner bore's boss point
    is the bore's, and the labels group an inner bore with its inner wall (no opposite)."""
    from types import SimpleNamespace

    from vibrogear.models.housing.surface_mesh import classify_points, mode_labels, region_names

    planes = np.array([0.0, 0.3, 0.0, 0.2, 0.0, 0.2])
    bores = [SimpleNamespace(name=f"a/{s}", center=(0.1, y, 0.1), axis=(0.0, ax, 0.0), radius=0.02,
                             y_range=(y - 0.01, y + 0.01)) for s, y, ax in
             (("front", 0.005, -1.0), ("inner1", 0.08, 1.0), ("back", 0.195, 1.0))]
    pts = np.array([[0.2, 0.075, 0.15],      # on the inner wall, away from its bore
                    [0.1, 0.08, 0.125],      # in the inner bore's ring
                    [0.2, 0.085, 0.2],       # the top wall's outer face beside the inner wall
                    [0.2, 0.03, 0.1]])       # cavity side of the front wall: nearer the front
    assert classify_points(pts, planes, bores).tolist() == [9, 7, 5, 2]
    names = region_names(bores)
    assert names[-1] == "inner wall 1" and len(names) == 10
    normals = np.vstack([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1],
                         [0, -1, 0], [0, 1, 0], [0, 1, 0], [0, 1, 0]]).astype(float)
    verts = np.array([[0.2, 0.075, 0.15], [0.25, 0.075, 0.1], [0.2, 0.075, 0.05]])
    values = np.zeros((3, 3, 2))
    values[:, 1, :] = 1.0                                   # along y: normal to the inner wall
    region = np.array([9, 9, 9])
    energy = np.array([[0.05, 0.05, 0.1, 0.15, 0, 0.1, 0.05, 0.2, 0.05, 0.25],   # wall .25 + bore .2
                       [0.1, 0.1, 0.3, 0.3, 0, 0.05, 0.05, 0.02, 0.05, 0.03]])
    labels, where = mode_labels(energy, names, normals, verts, values, region)
    assert labels[0] == "inner wall 1 with bore 2 bending (45 % of KE)" and where[0] == 9
    # front .3 + bore 1 .05, back .3 + bore 3 .05 (the inner bore 2 goes with the inner wall)
    assert labels[1].startswith("front and back walls") and labels[1].endswith("(70 % of KE)")
