"""The parametric housing sized for you from the gearbox: what [housing] leaves out is
filled, what it gives is kept."""
import copy
import math

import pytest

from vibrogear.config import ConfigError
from vibrogear.config.base import read_toml_file
from vibrogear.config.model.layout import gear_tip_radius
from vibrogear.config.scene import Scene, scene_from_dict
from vibrogear.models.validate import validate_scene

SCENE = "configs/single_stage.toml"


def _data():
    return read_toml_file(SCENE, Scene)


def test_given_housing_unchanged():
    data = _data()
    sc = scene_from_dict(copy.deepcopy(data))
    h = data["housing"]
    assert (sc.housing.length, sc.housing.width, sc.housing.height) == \
        (h["length"], h["width"], h["height"])
    assert [(b.x, b.z) for b in sc.housing.bores] == [(b["x"], b["z"]) for b in h["bores"]]


def test_sizes_and_bores_from_the_gearbox():
    """single_stage with no box sizes and no bore positions: the bores 1.5 mm x (40 + 80) / 2
    = 0.09 m apart at one height, the box around the largest tip (z2: 0.0615 m) with one
    wall (0.015 m) and 5 mm room, the back bearings (housing y 0.16) in the back wall's
    middle: width 0.1675 m.  The scene passes every check."""
    data = _data()
    h = data["housing"]
    for k in ("length", "width", "height"):
        h.pop(k)
    for b in h["bores"]:
        b.pop("x"), b.pop("z")
    sc = scene_from_dict(data)
    validate_scene(sc)
    (a, b) = sc.housing.bores
    assert abs(math.hypot(b.x - a.x, b.z - a.z) - 0.09) < 1e-12 and a.z == b.z
    tip = max(gear_tip_radius(g) for g in sc.gearbox.gears)
    margin = tip + 0.015 + 0.005
    assert a.x == round(margin, 9) and a.z == round(margin, 9)
    assert sc.housing.length == round(b.x + margin, 9)
    assert sc.housing.width == round(0.16 + 0.0075, 9)


def test_bores_created_from_the_shafts():
    data = _data()
    data["housing"] = {"base": "plate", "wall_thickness": 0.015}
    sc = scene_from_dict(data)
    validate_scene(sc)
    assert [b.name for b in sc.housing.bores] == ["input", "output"]
    # ball bearings without a designation: 8 coupling points and 1.8 x the journal radius
    assert sc.housing.bores[0].rolling_elements == 8


def test_wall_counts_filled_with_inner_walls():
    """single_stage with an inner wall at housing y = 0.04 m and a third bearing of 12
    elements on the driving shaft there (position 0.08 m + y0 -0.04 m): the input axis's bore
    gets [8, 12, 8] coupling points (front, inner, back: rolling_elements 8 where no bearing
    says otherwise), the output axis keeps 10 everywhere, and the scene passes every check
    (bearing elements = its wall's coupling points)."""
    data = _data()
    data["housing"]["inner_walls"] = [0.04]
    data["gearbox"]["bearings"].append({"name": "A mid", "shaft": "driving", "position": 0.08,
                                        "stiffness": 6.0e9, "elements": 12})
    sc = scene_from_dict(copy.deepcopy(data))
    validate_scene(sc)
    inp, out = sc.housing.bores
    assert inp.wall_rolling_elements == (8, 12, 8) and out.wall_rolling_elements == ()
    data["housing"]["bores"][0]["wall_rolling_elements"] = [8, 8, 8]      # given: kept
    with pytest.raises(ConfigError) as exc:
        validate_scene(scene_from_dict(data))
    assert "gearbox.bearings[4].elements" in str(exc.value)
    assert "inner1 bore of 'input' has 8" in str(exc.value)
