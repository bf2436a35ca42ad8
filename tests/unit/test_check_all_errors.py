"""``vibrogear check`` reports every problem it finds in one run, each with its fix in scene
terms and numbers as written; shafts get nodes where their parts are."""
import re

import pytest

from vibrogear.cli import main
from vibrogear.config import ConfigError, load_scene
from vibrogear.config.base import read_toml_file
from vibrogear.config.model.rotor import node_positions
from vibrogear.config.scene import Scene, scene_from_dict
from vibrogear.config.model.shaft_mesh import MAX_ELEMENT_LENGTH

SCENE = "configs/single_stage.toml"
EDIT = ["gearbox.gears[0].teeth=32", "gearbox.gears[1].teeth=96",
        "gearbox.shafts[0].sections[1].length=0.2", "gearbox.shafts[1].sections[1].length=0.2"]


def _check(capsys, sets):
    argv = ["check", SCENE]
    for s in sets:
        argv += ["--set", s]
    code = main(argv)
    cap = capsys.readouterr()
    return code, cap.out + cap.err


def test_teeth_32_96_and_longer_sections_in_one_round(capsys):
    """single_stage with teeth 40/80 -> 32/96 and the 0.16 m sections -> 0.20 m: one check
    lists the centre distance (m_n (32 + 96) / 2 = 0.096 m: bore 'output' to x = 0.073 +
    0.096 = 0.169 m), the housing length for the moved bore (0.169 + 0.0735 + 0.015 =
    0.2575 m) and the height (2 (0.0735 + 0.015) = 0.177 m); the bearings at 0.2 m get their
    nodes.  Applying the printed fixes passes."""
    code, text = _check(capsys, EDIT)
    assert code == 2
    assert "(3 problems found)" in text
    assert "move bore 'output' to x = 0.169 m" in text
    assert "housing.length >= 0.2575 m" in text and "housing.height >= 0.177 m" in text
    assert "not a node" not in text
    fixes = ["housing.bores[1].x=0.169", "housing.length=0.2575", "housing.height=0.177",
             "housing.bores[0].z=0.0885", "housing.bores[1].z=0.0885"]
    code, text = _check(capsys, EDIT + fixes)
    assert code == 0, text


def test_field_errors_are_collected_and_numbers_shown_as_written():
    data = read_toml_file(SCENE, Scene)
    data["gearbox"]["meshes"][0]["backlash"] = 0.05
    data["gearbox"]["gears"][0]["teeth"] = 3
    data["gearbox"]["shafts"][0]["master_count"] = 0
    with pytest.raises(ConfigError) as exc:
        scene_from_dict(data)
    paths = [e.path for e in exc.value.errors]
    assert set(paths) == {"gearbox.meshes[0].backlash", "gearbox.gears[0].teeth",
                          "gearbox.shafts[0].master_count"}
    text = str(exc.value)
    assert "value 0.05 out of range" in text and "value 3 out of range" in text


def test_at_most_20_errors_shown():
    data = read_toml_file(SCENE, Scene)
    for k in range(25):
        data["gearbox"][f"typo{k:02d}"] = 1
    with pytest.raises(ConfigError) as exc:
        scene_from_dict(data)
    assert len(exc.value.errors) == 25
    assert str(exc.value).count("unknown key") == 20 and "and 5 more" in str(exc.value)


def test_shafts_meshed_for_you():
    """Sections without element counts: a node at every gear, bearing and coupling and at
    every section change, no element longer than 20 mm."""
    data = read_toml_file(SCENE, Scene)
    for sh in data["gearbox"]["shafts"]:
        for sec in sh["sections"]:
            sec.pop("elements")
    data["gearbox"]["gears"][0]["position"] = 0.123      # off the old grid
    sc = scene_from_dict(data)
    gb = sc.gearbox
    for sh in gb.shafts:
        nodes = node_positions(sh.sections)
        feats = [x.position for grp in (gb.gears, gb.bearings, gb.couplings) for x in grp
                 if x.shaft == sh.name]
        for x in feats + [0.04, 0.20, 0.24]:
            assert min(abs(n - x) for n in nodes) < 1e-12
        assert max(b - a for a, b in zip(nodes, nodes[1:])) <= MAX_ELEMENT_LENGTH + 1e-12


def test_explicit_elements_unchanged_when_parts_on_nodes():
    """A scene whose parts already sit on nodes keeps its mesh exactly."""
    data = read_toml_file(SCENE, Scene)
    sc = scene_from_dict(data)
    for sh, raw in zip(sc.gearbox.shafts, data["gearbox"]["shafts"]):
        assert [(s.length, s.elements) for s in sh.sections] == \
            [(r["length"], r["elements"]) for r in raw["sections"]]
