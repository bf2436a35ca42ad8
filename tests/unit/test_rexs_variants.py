"""``vibrogear import`` of REXS files as the exporters write them: the FVA two-stage gearbox
(REXS 1.4 and 1.6, Bearinx) and its variants in tests/data/rexs/ (``make_variants.py``: REXS
1.0 units, gear positions at the face start, unequal face widths, no load spectrum, exporter
placeholders).  Each variant imports with no hand edit and checks; the known outcomes are the
published model's own numbers and hand computations from the variant's changes."""
import math
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from vibrogear.cli import main
from vibrogear.config import ConfigError, load_scene
from vibrogear.config.rexs import import_rexs
from vibrogear.config.rexs.mapping import MappingStopped
from vibrogear.config.rexs.reader import unit_factor

DATA = Path(__file__).resolve().parents[1] / "data" / "rexs"
XML = DATA / "FVA-Industriegetriebe_2stufig_1-4.rexs"
V16 = DATA / "FVA-Industriegetriebe_2_stufig_1-6.rexs"
VARIANTS = sorted(DATA.glob("FVA_variant_*.rexs"))
LOCATING = ("33", "34", "35", "37", "38")       # axial_force_absorption != no_direction


def _variant(name):
    return DATA / f"FVA_variant_{name}.rexs"


def _by_name(items):
    return {x["name"]: x for x in items}


# ------------------------------------------------------------------ the unit table

@pytest.mark.parametrize("unit, quantity, factor", [
    ("°", "angle", 1.0), ("deg", "angle", 1.0), ("rad", "angle", 180.0 / math.pi),
    ("mm", "length", 1e-3), ("m", "length", 1.0), ("µm", "length", 1e-6),
    ("\u03bcm", "length", 1e-6), ("um", "length", 1e-6), ("mum", "length", 1e-6),
    ("1 / min", "speed", 1.0), ("1/min", "speed", 1.0), ("rpm", "speed", 1.0),
    ("rad / s", "speed", 60.0 / (2 * math.pi)),
    ("N m", "torque", 1.0), ("Nm", "torque", 1.0), ("N*m", "torque", 1.0),
    ("N\u00b7m", "torque", 1.0), ("N mm", "torque", 1e-3),
    ("kW", "power", 1e3), ("W", "power", 1.0),
    ("kg / dm^3", "density", 1e3), ("kg/m^3", "density", 1.0), ("g / cm^3", "density", 1e3),
    ("N / mm^2", "stress", 1e6), ("N/mm\u00b2", "stress", 1e6), ("MPa", "stress", 1e6),
    ("N/mm", "stiffness", 1e3), ("N / m", "stiffness", 1.0), ("N / µm", "stiffness", 1e6),
    ("N / mum", "stiffness", 1e6), ("kN/mm", "stiffness", 1e6),
    ("N mm / rad", "rotational stiffness", 1e-3), ("kg m^2", "inertia", 1.0),
])
def test_unit_spellings(unit, quantity, factor):
    """Every spelling of REXS 1.0-2.0 (their schemas' unit lists) and of other exporters, to
    SI by the unit's definition (1 N/mm = 1000 N/m, 1 kg/dm^3 = 1000 kg/m^3, 1 rad = 180/pi
    deg, 1 rad/s = 60/(2 pi) rpm)."""
    assert unit_factor(unit, quantity) == pytest.approx(factor, rel=1e-15)


def test_unit_of_the_wrong_quantity_is_named(tmp_path, capsys):
    root = ET.parse(XML).getroot()
    g = next(c for c in root.iter("component") if c.get("id") == "15")
    next(a for a in g if a.get("id") == "face_width").set("unit", "deg")
    bad = tmp_path / "bad.rexs"
    bad.write_bytes(ET.tostring(root))
    assert main(["import", str(bad), "-o", str(tmp_path / "s.toml")]) == 2
    err = capsys.readouterr().err
    assert "component 15" in err and "'face_width'" in err and "unit of length" in err


# ------------------------------------------------------------------ variants

@pytest.mark.parametrize("path", VARIANTS + [V16], ids=lambda p: p.stem)
def test_every_variant_imports_and_checks(path, tmp_path, capsys):
    out = tmp_path / "scene.toml"
    assert main(["import", str(path), "-o", str(out)]) == 0
    assert main(["check", str(out)]) == 0
    assert main(["check", str(path)]) == 0


def test_rexs10_units_give_the_same_scene():
    """REXS 1.0 spellings (°, µm, Nm, rpm, kg/m^3 with the value x 1000, MPa): the same
    quantities, so the same scene."""
    a, b = import_rexs(XML).data, import_rexs(_variant("rexs10_units")).data
    for d in (a, b):
        d["scene"].pop("description"), d["scene"].pop("name"), d["gearbox"].pop("name")
    assert a == b


def test_face_start_positions_give_the_original_centres():
    """Each gear's u at the start of its face (u - b/2): read as centres, gears 15, 17 and 18
    leave the shaft section that carries them (e.g. gear 18 at u = 28 mm with b = 74 mm would
    start 9 mm before its shaft), so the file is read as face-start and every centre is the
    original's; each gear is listed under "assumed"."""
    orig = _by_name(import_rexs(XML).data["gearbox"]["gears"])
    imp = import_rexs(_variant("face_start"))
    got = _by_name(imp.data["gearbox"]["gears"])
    assert {k: g["position"] for k, g in got.items()} == \
        {k: g["position"] for k, g in orig.items()}
    for gid in ("15", "16", "17", "18"):
        assert any(a.startswith(f"cylindrical_gear {gid}: u_coordinate_on_shaft") and
                   "start of its face" in a for a in imp.report.assumed), gid


def test_unequal_faces_mesh_on_the_overlap():
    """Stage 19: pinion 15 (b = 50 mm, centre at housing y = 117 mm: face 92..142 mm) and
    wheel 17 now b = 44 mm at u = 77 mm on shaft 13 (y0 = 45 mm: centre 122 mm, face
    100..144 mm): overlap 100..142 mm = 42 mm.  Stage 20: pinion 16 widened to 80 mm about
    its old centre holds the 74 mm wheel 18 whole: 74 mm."""
    imp = import_rexs(_variant("unequal_faces"))
    meshes = _by_name(imp.data["gearbox"]["meshes"])
    assert meshes["stage19"]["face_width"] == pytest.approx(0.042, abs=1e-12)
    assert meshes["stage20"]["face_width"] == pytest.approx(0.074, abs=1e-12)
    gears = _by_name(imp.data["gearbox"]["gears"])
    assert gears["gear17"]["position"] == pytest.approx(0.077, abs=1e-12)   # its own centre
    assert any("overlap over 42 mm" in a and "121 mm" in a for a in imp.report.assumed)
    sc = load_scene(_variant("unequal_faces"))          # the layout check accepts the pair
    assert sc.gearbox.meshes[0].face_width == pytest.approx(0.042, abs=1e-12)


def test_no_load_spectrum_takes_the_components_operating_point():
    """No load spectrum: 456 N m on external_load 40 and 1234 1/min on shaft 12 (load case
    3's values) make the operating point; the output torque 456 x (51/27)(34/23), lossless."""
    sc = load_scene(_variant("no_spectrum"))
    cp = {c.role: c for c in sc.gearbox.couplings}
    assert cp["motor"].torque == 456.0 and sc.time_response.rpm == 1234.0
    assert cp["load"].torque == pytest.approx(456 * 51 / 27 * 34 / 23, rel=1e-9)


def test_power_instead_of_torque(tmp_path):
    """The external load's power P = T omega: 456 N m at 1234 rpm is 58.9 kW."""
    root = ET.parse(_variant("no_spectrum")).getroot()
    load = next(c for c in root.iter("component") if c.get("id") == "40")
    a = next(x for x in load if x.get("id") == "torque_around_u_axis")
    a.set("id", "power")
    a.set("unit", "kW")
    a.text = repr(456 * 1234 * math.pi / 30 / 1e3)
    f = tmp_path / "power.rexs"
    f.write_bytes(ET.tostring(root))
    motor = next(c for c in import_rexs(f).data["gearbox"]["couplings"] if c["role"] == "motor")
    assert motor["torque"] == pytest.approx(456.0, rel=1e-9)


def test_placeholders_are_not_given():
    """axial_stiffness = 0 N/m on the five locating bearings, radial_stiffness 1e23 N/m and
    an empty one: each takes the documented default (axial 1e8 N/m, concept radial 1e9 N/m)
    and is listed under "assumed" with the file's value."""
    imp = import_rexs(_variant("placeholders"))
    b = _by_name(imp.data["gearbox"]["bearings"])
    for cid in LOCATING:
        assert b[f"bearing{cid}"]["axial_stiffness"] == 1e8
        kind = "concept_bearing" if cid in ("37", "38") else \
            "rolling_bearing_with_catalog_geometry"
        assert any(a.startswith(f"{kind} {cid}: axial stiffness 1e+08 N/m (the file's 0 N/m")
                   for a in imp.report.assumed), cid
    for cid, why in (("36", "1e+23 N/m"), ("37", "empty"), ("38", "1e+23 N/m")):
        assert b[f"bearing{cid}"]["stiffness"] == 1e9
        assert any(a.startswith(f"concept_bearing {cid}: radial stiffness 1e+09 N/m") and why in a
                   for a in imp.report.assumed), cid


def test_all_shapes_at_once():
    """Every shape in one file (as one exporter's file combines them): the gear centres,
    the overlap face widths and the operating point of the single-shape variants."""
    imp = import_rexs(_variant("all"))
    ref = import_rexs(_variant("unequal_faces")).data["gearbox"]
    gb = imp.data["gearbox"]
    assert [(g["name"], g["position"], g["width"]) for g in gb["gears"]] == \
        [(g["name"], g["position"], g["width"]) for g in ref["gears"]]
    assert [m["face_width"] for m in gb["meshes"]] == [m["face_width"] for m in ref["meshes"]]
    assert all(b.get("axial_stiffness", 1e8) == 1e8 for b in gb["bearings"])
    assert imp.data["time_response"]["rpm"] == 1234.0


# ------------------------------------------------------------------ load cases

@pytest.mark.parametrize("path", [XML, V16], ids=["rexs1.4", "rexs1.6"])
def test_the_longest_load_case_is_taken(path):
    """Shares 20, 30, 35, 15 % (1.4: load_duration_fraction; 1.6: operating_time_fraction):
    load case 3, 1234 rpm and 456 N m, is the operating point; the map spans all four."""
    imp = import_rexs(path)
    motor = next(c for c in imp.data["gearbox"]["couplings"] if c["role"] == "motor")
    assert (imp.data["time_response"]["rpm"], motor["torque"]) == (1234.0, 456.0)
    assert (imp.data["map"]["rpm_min"], imp.data["map"]["rpm_max"]) == (543.0, 3456.0)
    assert (imp.data["map"]["torque_min"], imp.data["map"]["torque_max"]) == (345.0, 789.0)
    assert any("load case 3 of 4 (the largest duration share, 35 %)" in m
               for m in imp.report.mapped)


def test_load_case_named(tmp_path, capsys):
    out = tmp_path / "lc2.toml"
    assert main(["import", str(XML), "--load-case", "2", "-o", str(out)]) == 0
    sc = load_scene(out)
    motor = next(c for c in sc.gearbox.couplings if c.role == "motor")
    assert (sc.time_response.rpm, motor.torque) == (3456.0, 345.0)
    assert main(["import", str(XML), "--load-case", "5", "-o", str(out)]) == 2
    assert "--load-case" in capsys.readouterr().err


# ------------------------------------------------------------------ the draft

def test_every_problem_at_once_and_the_draft(tmp_path, capsys):
    """Three independent problems: all three listed (component, attribute, fix), exit 2
    within 30 s, nothing written but scene.draft.toml, which check refuses."""
    root = ET.parse(XML).getroot()
    comp = {c.get("id"): c for c in root.iter("component")}
    g15 = comp["15"]
    g15.remove(next(a for a in g15 if a.get("id") == "number_of_teeth"))
    next(a for a in comp["21"] if a.get("id") == "length").set("unit", "furlong")
    next(a for a in comp["20"] if a.get("id") == "center_distance").text = "200"
    bad = tmp_path / "bad.rexs"
    bad.write_bytes(ET.tostring(root))
    out = tmp_path / "scene.toml"
    t0 = time.monotonic()
    assert main(["import", str(bad), "-o", str(out)]) == 2
    assert time.monotonic() - t0 < 30.0
    err = capsys.readouterr().err
    for words in (["component 15", "'number_of_teeth'"], ["component 21", "'length'", "furlong"],
                  ["component 20", "'center_distance'", "fix:"]):
        assert all(w in err for w in words), err
    assert "3 problems" in err
    assert not out.exists()
    draft = tmp_path / "scene.draft.toml"
    assert draft.exists() and draft.read_text().startswith("# vibrogear DRAFT:")
    assert "number_of_teeth" in draft.read_text()
    assert main(["check", str(draft)]) == 2
    assert "draft" in capsys.readouterr().err
    with pytest.raises(MappingStopped) as info:
        import_rexs(bad)
    assert isinstance(info.value, ConfigError) and len(info.value.errors) == 3


def test_placeholders_leave_no_shaft_free(tmp_path):
    """With the file's axial_stiffness = 0 copied, four rigid-body modes appear (each shaft
    free to slide; checked by hand with --set ...axial_stiffness=0 on the five locating
    bearings: n_rigid = 4); with the placeholders taken as not given, none."""
    import json
    out = tmp_path / "modes"
    assert main(["modes", str(_variant("placeholders")), "--out", str(out), "--quiet"]) == 0
    assert json.loads((out / "summary.json").read_text())["results"]["modes"]["n_rigid"] == 0


def test_missing_operating_point_lists_speed_and_torque(tmp_path, capsys):
    """No load spectrum and neither speed nor torque on the components: both named at once,
    each with its component and fix."""
    root = ET.parse(_variant("no_spectrum")).getroot()
    for cid, aid in (("40", "torque_around_u_axis"), ("12", "rotational_speed")):
        c = next(x for x in root.iter("component") if x.get("id") == cid)
        c.remove(next(a for a in c if a.get("id") == aid))
    bad = tmp_path / "bad.rexs"
    bad.write_bytes(ET.tostring(root))
    assert main(["import", str(bad), "-o", str(tmp_path / "s.toml")]) == 2
    err = capsys.readouterr().err
    assert "2 problems" in err
    assert "component 12 (shaft): missing attribute 'rotational_speed'; fix:" in err
    assert "component 40 (external_load): missing attribute 'torque_around_u_axis'" in err
    assert (tmp_path / "s.draft.toml").exists() and not (tmp_path / "s.toml").exists()


def test_scene_check_problem_names_the_rexs_component(tmp_path, capsys):
    """Mapped, but the scene fails its check (bearing 33 moved to u = 500 mm on the 190 mm
    shaft 12): the scene field and the REXS component it came from, and the draft."""
    root = ET.parse(XML).getroot()
    b = next(x for x in root.iter("component") if x.get("id") == "33")
    next(a for a in b if a.get("id") == "u_coordinate_on_shaft_inner_side").text = "500"
    bad = tmp_path / "bad.rexs"
    bad.write_bytes(ET.tostring(root))
    assert main(["import", str(bad), "-o", str(tmp_path / "s.toml")]) == 2
    err = capsys.readouterr().err
    assert "gearbox.bearings[0].position" in err
    assert "rolling_bearing_with_catalog_geometry 33" in err
    assert (tmp_path / "s.draft.toml").read_text().startswith("# vibrogear DRAFT:")
