"""Loads in an engineer's terms: a coupling's ``torque`` [N m] or ``power`` [kW] at ``rpm``
replaces its ``twist`` [rad]; the reduced model's static force is the same to 1e-12."""
import math

import numpy as np
import pytest

from vibrogear.config import ConfigError, load_scene, scene_from_dict
from vibrogear.config.base import read_toml_file
from vibrogear.config.scene import Scene
from vibrogear.models.gearbox.model import build_gearbox

SCENE = "configs/gear_pair.toml"


def _with_load(data, i, **load):
    c = data["gearbox"]["couplings"][i]
    c.pop("twist", None)
    c.update(load)
    return data


@pytest.fixture(scope="module")
def twist_model():
    return build_gearbox(load_scene(SCENE)).reduced.forcing.F0


def test_torque_and_power_equal_the_twist(twist_model):
    """gear_pair: motor 2.5e3 N m/rad x 0.025 rad = 62.5 N m; load 1e4 x 0.025 = 250 N m.
    The same loads as torque, and as power at 3000 rpm (P = T 2 pi n / 60), give the
    static force of the twist scene to 1e-12 (relative, max norm)."""
    base = read_toml_file(SCENE, Scene)
    by_torque = _with_load(_with_load(base, 0, torque=62.5), 1, torque=250.0)
    omega = 3000.0 * 2 * math.pi / 60
    by_power = _with_load(_with_load(read_toml_file(SCENE, Scene), 0, power=62.5 * omega / 1e3,
                                     rpm=3000.0), 1, torque=250.0)
    ref = twist_model
    for data in (by_torque, by_power):
        sc = scene_from_dict(data)
        assert sc.gearbox.couplings[0].static_twist == pytest.approx(0.025, rel=1e-14)
        f0 = build_gearbox(sc).reduced.forcing.F0
        assert np.max(np.abs(f0 - ref)) <= 1e-12 * np.max(np.abs(ref))


@pytest.mark.parametrize("load, key", [({"torque": 1.0, "twist": 0.01}, "torque"),
                                        ({"power": 1.0}, "rpm"),
                                        ({"torque": 1e5}, "torque"),
                                        ({}, "twist")])
def test_bad_loads_name_the_field(load, key):
    """Exactly one of twist / torque / power (with rpm); a twist >= 1 rad is refused with
    the implied value."""
    data = read_toml_file(SCENE, Scene)
    c = data["gearbox"]["couplings"][0]
    c.pop("twist")
    c.update(load)
    with pytest.raises(ConfigError) as exc:
        scene_from_dict(data)
    assert exc.value.path == f"gearbox.couplings[0].{key}"
