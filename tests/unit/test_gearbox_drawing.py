"""The gearbox drawing (report/plots/gearbox_drawing.py) against the scene files it draws.

The expected sizes are read from the TOML files with tomllib, not from the config objects
the drawing reads, and checked twice: in the layout's numbers and in the patches of the
rendered figure (data coordinates, millimetres)."""
from __future__ import annotations

import math
import tomllib
from pathlib import Path

import pytest

from vibrogear.config.scene import load_scene
from vibrogear.report.plots.gearbox_drawing import draw_gearbox, figure_of, gearbox_layout

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
SCENES = ("two_stage", "gear_pair", "single_stage")


def _raw(name):
    with open(CONFIGS / f"{name}.toml", "rb") as fh:
        return tomllib.load(fh)


def _axis(raw, shaft):
    bores = {b["name"]: b for b in raw.get("housing", {}).get("bores", [])}
    b = bores.get(shaft.get("bore", ""))
    return (b["x"], b["z"]) if b else (shaft["x"], shaft["z"])


@pytest.mark.parametrize("name", SCENES)
def test_drawing_renders_a_png(name, tmp_path):
    path = draw_gearbox(load_scene(CONFIGS / f"{name}.toml"), tmp_path / "gearbox")
    data = path.read_bytes()
    assert path.suffix == ".png" and data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    assert width > 1000 and height > 400


@pytest.mark.parametrize("name", SCENES)
def test_gears_drawn_at_their_pitch_radius_and_face_width(name):
    raw, scene = _raw(name), load_scene(CONFIGS / f"{name}.toml")
    shafts = {s["name"]: s for s in raw["gearbox"]["shafts"]}
    lay = gearbox_layout(scene)
    fig = figure_of(scene)
    patches = {p.get_gid(): p for ax in fig.axes for p in ax.patches}
    for g in raw["gearbox"]["gears"]:
        assert g.get("helix_angle", 0.0) == 0.0          # spur: pitch radius = z m / 2
        r_mm = g["teeth"] * g["module"] / 2 * 1e3
        x, z = (1e3 * c for c in _axis(raw, shafts[g["shaft"]]))
        (circle,) = [s for s in lay.of("gear", "end") if s.name == g["name"]]
        assert circle.radius == pytest.approx(r_mm, rel=1e-12)
        assert circle.centre == pytest.approx((x, z), rel=1e-12)
        drawn = patches[f"gear:{g['name']}:end"]
        assert drawn.get_radius() == pytest.approx(r_mm, rel=1e-12)
        assert tuple(drawn.center) == pytest.approx((x, z), rel=1e-12)
        (rect,) = [s for s in lay.of("gear", "side") if s.name == g["name"]]
        y_mm = 1e3 * (shafts[g["shaft"]].get("y0", 0.0) + g["position"])
        assert rect.x1 - rect.x0 == pytest.approx(1e3 * g["width"], rel=1e-12)
        assert 0.5 * (rect.x0 + rect.x1) == pytest.approx(y_mm, rel=1e-12)
        assert rect.y1 - rect.y0 == pytest.approx(2 * r_mm, rel=1e-12)
        side = patches[f"gear:{g['name']}:side"]
        assert side.get_width() == pytest.approx(1e3 * g["width"], rel=1e-12)
        assert side.get_height() == pytest.approx(2 * r_mm, rel=1e-12)


@pytest.mark.parametrize("name", SCENES)
def test_meshing_pitch_circles_touch(name):
    """The drawn axes are the bores': the pitch circles of every mesh touch (centre distance
    = m (z_a + z_b) / 2, which the scene's check enforces)."""
    raw, lay = _raw(name), gearbox_layout(load_scene(CONFIGS / f"{name}.toml"))
    circles = {s.name: s for s in lay.of("gear", "end")}
    gears = {g["name"]: g for g in raw["gearbox"]["gears"]}
    for m in raw["gearbox"]["meshes"]:
        a, b = circles[m["gear_a"]], circles[m["gear_b"]]
        dist = math.dist(a.centre, b.centre)
        ga, gb = gears[m["gear_a"]], gears[m["gear_b"]]
        assert dist == pytest.approx(1e3 * ga["module"] * (ga["teeth"] + gb["teeth"]) / 2,
                                     rel=1e-9)
        assert dist == pytest.approx(a.radius + b.radius, rel=1e-9)


@pytest.mark.parametrize("name", SCENES)
def test_shafts_sections_and_housing_to_scale(name):
    raw, lay = _raw(name), gearbox_layout(load_scene(CONFIGS / f"{name}.toml"))
    for sh in raw["gearbox"]["shafts"]:
        rects = sorted((s for s in lay.of("shaft", "side") if s.name.startswith(sh["name"] + "[")),
                       key=lambda s: s.x0)
        assert len(rects) == len(sh["sections"])
        y = 1e3 * sh.get("y0", 0.0)
        for r, sec in zip(rects, sh["sections"]):
            assert r.x0 == pytest.approx(y, abs=1e-9)
            assert r.x1 - r.x0 == pytest.approx(1e3 * sec["length"], rel=1e-12)
            assert r.y1 - r.y0 == pytest.approx(1e3 * sec["outer_diameter"], rel=1e-12)
            y = r.x1
    h = raw.get("housing")
    if h is None:
        assert not lay.of("housing")
        return
    (outer,) = lay.of("housing", "end")
    assert (outer.x1 - outer.x0, outer.y1 - outer.y0) == pytest.approx(
        (1e3 * h["length"], 1e3 * h["height"]), rel=1e-12)
    (cavity,) = lay.of("cavity", "end")
    assert cavity.x0 - outer.x0 == pytest.approx(1e3 * h["wall_thickness"], rel=1e-12)
    (side,) = lay.of("housing", "side")
    assert side.x1 - side.x0 == pytest.approx(1e3 * h["width"], rel=1e-12)
    for b in h["bores"]:
        (bore,) = [s for s in lay.of("bore", "end") if s.name == b["name"]]
        assert bore.radius == pytest.approx(1e3 * b["bore_radius"], rel=1e-12)
    # a bearing spans from the shaft's surface to its bore
    bores = {b["name"]: b for b in h["bores"]}
    shafts = {s["name"]: s for s in raw["gearbox"]["shafts"]}
    for b in raw["gearbox"]["bearings"]:
        upper = max((s for s in lay.of("bearing", "side") if s.name == b["name"]),
                    key=lambda s: s.y1)
        sh = shafts[b["shaft"]]
        c = 1e3 * _axis(raw, sh)[0 if lay.across == "x" else 1]
        assert upper.y1 - c == pytest.approx(1e3 * bores[sh["bore"]]["bore_radius"], rel=1e-12)


def test_a_scene_without_gearbox_is_refused():
    scene = load_scene(CONFIGS / "impact_pair.toml")
    with pytest.raises(ValueError, match="no \\[gearbox\\]"):
        gearbox_layout(scene)


def test_power_flow_line_per_mesh_between_its_gears():
    """With a load path the side view carries one line per mesh from gear_a's centre to
    gear_b's (their pitch circles touch: its length is the centre distance), solid for a
    loaded mesh and dashed for an idle one, labelled with the load path's tooth force."""
    scene = load_scene("configs/two_stage.toml")
    lp = {"meshes": [{"name": "G1", "role": "loaded", "normal_force_N": 2420.0,
                      "power_kW": 55.3},
                     {"name": "G2", "role": "idle", "normal_force_N": 16.4, "power_kW": 0.0}]}
    fig = figure_of(scene, lp)
    side = fig.axes[0]
    lines = {ln.get_gid(): ln for ln in side.get_lines() if (ln.get_gid() or "").startswith("power:")}
    assert set(lines) == {"power:G1", "power:G2"}
    gears = {g.name: g for g in scene.gearbox.gears}
    for m in scene.gearbox.meshes:
        x, y = lines[f"power:{m.name}"].get_data()
        a, b = gears[m.gear_a], gears[m.gear_b]
        centre_distance_mm = 0.5 * (a.teeth * a.module + b.teeth * b.module) * 1e3
        assert math.hypot(x[1] - x[0], y[1] - y[0]) == pytest.approx(centre_distance_mm,
                                                                    rel=1e-6)
    assert lines["power:G1"].get_linestyle() == "-" and lines["power:G2"].get_linestyle() == "--"
    texts = [t.get_text() for t in side.texts]
    assert "G1: F_n 2.42 kN, 55.3 kW" in texts and "G2: idle" in texts
