"""``vibrogear import`` of the FVA two-stage industrial gearbox (REXS 1.4, Bearinx export;
tests/data/rexs/, Apache-2.0) and of broken copies of it: every bad file exits 2 naming the
component, and writes nothing."""
import json
import math
import re
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from vibrogear.cli import main
from vibrogear.config import load_scene
from vibrogear.config.rexs import import_rexs
from vibrogear.config.rexs.scene_toml import scene_toml

DATA = Path(__file__).resolve().parents[1] / "data" / "rexs"
XML = DATA / "FVA-Industriegetriebe_2stufig_1-4.rexs"
JSN = DATA / "FVA-Industriegetriebe_2stufig_1-4.rexsj"


def test_xml_and_json_give_the_same_scene():
    a, b = import_rexs(XML).data, import_rexs(JSN).data
    assert a["scene"].pop("description").endswith(".rexs (REXS 1.4)")
    assert b["scene"].pop("description").endswith(".rexsj (REXS 1.4)")
    assert a == b


def test_fva_model_as_published():
    """The model's own numbers: stage 1 z = 27/51 at m_n = 4.5 mm, beta = 21 deg; stage 2
    23/34 at 6.5 mm, 10 deg; both centre distances 190 mm; input and output shafts coaxial,
    the input running in the output (concept bearing 36); bearings 6210-2Z, 33014, 33012."""
    sc = load_scene(XML)
    gb = sc.gearbox
    assert [s.name for s in gb.shafts] == ["shaft12", "shaft13", "shaft14"]
    teeth = {g.name: (g.teeth, g.module, g.helix_angle) for g in gb.gears}
    assert teeth["gear15"] == (27, 0.0045, 21.0) and teeth["gear17"] == (51, 0.0045, 21.0)
    assert teeth["gear16"] == (23, 0.0065, 10.0) and teeth["gear18"] == (34, 0.0065, 10.0)
    x = {s.name: (s.x, s.z) for s in gb.shafts}
    assert x["shaft12"] == x["shaft14"]
    assert abs(x["shaft13"][0] - x["shaft12"][0]) == pytest.approx(0.19, abs=1e-12)
    b = {b.name: b for b in gb.bearings}
    assert b["bearing36"].outer_shaft == "shaft14" and b["bearing36"].shaft == "shaft12"
    assert {b["bearing33"].designation, b["bearing34"].designation,
            b["bearing35"].designation} == {"6210-2Z", "33014", "33012"}
    # the load: load case 3 (35 % of the time) 456 N m at 1234 rpm on the input
    motor = next(c for c in gb.couplings if c.role == "motor")
    assert motor.torque == 456.0 and sc.time_response.rpm == 1234.0
    # the output torque: input x (51/27)(34/23), lossless
    load = next(c for c in gb.couplings if c.role == "load")
    assert load.torque == pytest.approx(456 * 51 / 27 * 34 / 23, rel=1e-6)
    # every gear, bearing and coupling sits on a node (loading would have raised), and no
    # element is longer than 20 mm
    for s in gb.shafts:
        assert max(sec.length / sec.elements for sec in s.sections) <= 0.02 + 1e-12


def test_toml_reads_back_and_names_components(tmp_path):
    imp = import_rexs(XML)
    text = scene_toml(imp)
    assert tomllib.loads(text) == imp.data
    assert "# REXS concept_bearing 36" in text and "# REXS cylindrical_stage 19" in text
    for part in ("mapped (", "assumed (", "ignored ("):
        assert f"#   {part}" in text
    # every component of the file appears in the report (nothing silently dropped)
    report = "\n".join(imp.report.lines())
    for c in imp.model.components.values():
        if c.type not in ("shaft_section", "material", "cylindrical_gear_flank"):
            assert re.search(rf"\b{c.type} {c.id}\b", report), c.label()


def test_import_cli_writes_a_scene_that_checks(tmp_path, capsys):
    out = tmp_path / "fva.toml"
    assert main(["import", str(JSN), "-o", str(out)]) == 0
    assert main(["check", str(out)]) == 0
    text = capsys.readouterr().out
    assert "twist 0.02 rad" in text and "contact constant" in text
    assert main(["check", str(XML)]) == 0


def _xml_root():
    return ET.parse(XML).getroot()


def _write_xml(root, path):
    path.write_bytes(ET.tostring(root))
    return path


def _component(root, cid):
    return next(c for c in root.iter("component") if c.get("id") == cid)


def _broken_missing_attribute(root):
    g = _component(root, "15")
    g.remove(next(a for a in g if a.get("id") == "number_of_teeth"))


def _broken_missing_reference(root):
    rel = next(r for r in root.iter("relation") if r.get("id") == "5")
    next(iter(rel)).set("id", "999")


def _broken_stage_on_one_shaft(root):
    rel = next(r for r in root.iter("relation") if r.get("id") == "7")   # shaft 13 <- gear 17
    next(x for x in rel if x.get("role") == "assembly").set("id", "12")


def _broken_planetary(root):
    comps = root.find("components")
    ET.SubElement(comps, "component", id="900", type="planetary_stage", name="PS")


def _broken_unit(root):
    s = _component(root, "21")
    next(a for a in s if a.get("id") == "length").set("unit", "furlong")


@pytest.mark.parametrize("breaker, words", [
    (_broken_missing_attribute, ["component 15", "'number_of_teeth'"]),
    (_broken_missing_reference, ["999"]),
    (_broken_stage_on_one_shaft, ["component 19", "two shafts"]),
    (_broken_planetary, ["component 900", "'planetary_stage'"]),
    (_broken_unit, ["component 21", "'length'", "furlong"]),
])
def test_bad_rexs_exits_2_naming_the_component(tmp_path, capsys, breaker, words):
    root = _xml_root()
    breaker(root)
    bad = _write_xml(root, tmp_path / "bad.rexs")
    out = tmp_path / "scene.toml"
    assert main(["import", str(bad), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    for w in words:
        assert w in err, err
    assert not out.exists()
    assert main(["check", str(bad)]) == 2


@pytest.mark.parametrize("text, words", [
    ("hello, not a model", ["neither XML"]),
    ("<notamodel/>", ["root is <notamodel>"]),
    ("{\"rexs\": 1}", ["\"model\" object"]),
    ("<model version=\"1.4\"><components>", ["not well-formed XML"]),
])
def test_not_rexs_exits_2(tmp_path, capsys, text, words):
    bad = tmp_path / ("bad.rexsj" if text.startswith("{") else "bad.rexs")
    bad.write_text(text)
    out = tmp_path / "scene.toml"
    assert main(["import", str(bad), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert all(w in err for w in words), err
    assert not out.exists()


def test_json_missing_attribute(tmp_path, capsys):
    doc = json.loads(JSN.read_text())
    sec = next(c for c in doc["model"]["components"] if c["id"] == 24)
    sec["attributes"] = [a for a in sec["attributes"] if a["id"] != "outer_diameter_begin"]
    bad = tmp_path / "bad.rexsj"
    bad.write_text(json.dumps(doc))
    assert main(["import", str(bad), "-o", str(tmp_path / "s.toml")]) == 2
    err = capsys.readouterr().err
    assert "component 24" in err and "'outer_diameter_begin'" in err


def test_import_to_stdout(capsys):
    assert main(["import", str(XML)]) == 0
    cap = capsys.readouterr()
    assert tomllib.loads(cap.out)["scene"]["name"] == "FVA-Industriegetriebe_2stufig_1-4"
    assert "mapped (" in cap.err


def test_unsupported_version_named(tmp_path, capsys):
    root = _xml_root()
    root.set("version", "0.9")
    bad = _write_xml(root, tmp_path / "old.rexs")
    assert main(["import", str(bad), "-o", str(tmp_path / "s.toml")]) == 2
    assert "REXS version '0.9'" in capsys.readouterr().err


def test_unknown_designation_falls_back_to_boundary_dimensions(tmp_path):
    """A designation outside the ISO table with inner_diameter / outer_diameter / width in
    the file: the boundary dimensions are used (and the fallback reported)."""
    root = _xml_root()
    b = _component(root, "33")
    next(a for a in b if a.get("id") == "catalogue_designation").text = "XYZ-123"
    for aid, val in (("inner_diameter", "50"), ("outer_diameter", "90"), ("width", "20")):
        ET.SubElement(b, "attribute", id=aid, unit="mm").text = val
    imp = import_rexs(_write_xml(root, tmp_path / "dims.rexs"))
    bearing = next(x for x in imp.data["gearbox"]["bearings"] if x["name"] == "bearing33")
    assert (bearing["bore_diameter"], bearing["outer_diameter"], bearing["width"]) == \
        (0.05, 0.09, 0.02)
    assert any("'XYZ-123' is not in the ISO table" in a for a in imp.report.assumed)


def test_unknown_designation_without_dimensions_exits_2(tmp_path, capsys):
    root = _xml_root()
    b = _component(root, "34")
    next(a for a in b if a.get("id") == "catalogue_designation").text = "XYZ-123"
    bad = _write_xml(root, tmp_path / "bad.rexs")
    assert main(["import", str(bad), "-o", str(tmp_path / "s.toml")]) == 2
    err = capsys.readouterr().err
    assert "component 34" in err and "'catalogue_designation'" in err


def test_box_housing_puts_an_inner_wall_at_the_middle_bearing(tmp_path, capsys):
    """The FVA output shaft's 33014 (component 34) sits between the front and the back
    bearing planes: the generated box gets an inner wall there.  By hand from the file: the
    front plane is bearing 33's (shaft 12 at u = 65 mm), bearing 34 is at shaft 14's
    u0 + 13 mm = 160 + 13 = 173 mm, bearing 35 (back) at 160 + 140 = 300 mm and bearing 38
    (shaft 13: 45 + 250 = 295 mm) within one 20 mm wall of it.  Housing y = model y - 65 mm
    + half a wall: the inner wall at 173 - 65 + 10 = 118 mm, width 300 - 65 + 20 = 255 mm.
    Every casing bearing is carried by the bore of its own wall."""
    from vibrogear.geometry.housing import bore_layout
    from vibrogear.models.gearbox.supports import _bore_of

    out = tmp_path / "box.toml"
    assert main(["import", str(XML), "--housing", "box", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert re.search(r"inner wall 1 at y = 0\.118 m \(housing\.inner_walls\[0\].*casing "
                     r"bearing 34 between", err)
    data = tomllib.loads(out.read_text())
    h = data["housing"]
    assert h["inner_walls"] == pytest.approx([0.118], abs=1e-12)
    assert h["width"] == pytest.approx(0.255, abs=1e-12)
    # coupling points per wall of the coaxial axis: the 6210's 10 balls (front), the 33014's
    # and 33012's 25 rollers each (the element-set rule, as the derived lines say)
    axis = next(b for b in h["bores"] if b["name"] == data["gearbox"]["shafts"][0]["bore"])
    assert axis["wall_rolling_elements"] == [10, 25, 25]
    assert "inner wall 1 at y = 0.118 m" in out.read_text()          # the TOML header too
    assert main(["check", str(out)]) == 0
    sc = load_scene(out)
    layout = bore_layout(sc.housing)

    class Bores:                        # what the bearing-to-bore assignment reads
        bore_names = [g.name for g in layout]
        bore_centers = __import__("numpy").array([g.center for g in layout])

    shafts = {s.name: s for s in sc.gearbox.shafts}
    got = {b.name: Bores.bore_names[_bore_of(Bores, shafts[b.shaft].bore,
                                             shafts[b.shaft].y0 + b.position)]
           for b in sc.gearbox.bearings if not b.outer_shaft}
    a, i = shafts["shaft12"].bore, shafts["shaft13"].bore
    assert [g.n_points for g in layout if g.name.startswith(a + "/")] == [10, 25, 25]
    assert got == {"bearing33": f"{a}/front", "bearing34": f"{a}/inner1", "bearing35": f"{a}/back",
                   "bearing37": f"{i}/front", "bearing38": f"{i}/back"}


@pytest.mark.parametrize("component, u_mm, words", [
    # bearing 34 onto gear 18's middle (u = 65 mm on shaft 14): its wall would cut the gear
    ("34", "65", ("gear 18",)),
    # bearing 38 at u = 225 mm on shaft 13 (housing y 45 + 225 = 270 mm): 30 mm before the
    # back plane (300 mm), more than one 20 mm wall from it, so it needs an inner wall at
    # 270 mm, whose face would leave 300 - 10 - 280 = 10 mm of cavity to the back wall
    ("38", "225", ("10 mm of cavity to the back wall",)),
], ids=["wall-through-a-gear", "wall-crowding-its-neighbour"])
def test_box_housing_refuses_an_inner_wall_it_cannot_place(tmp_path, capsys, component, u_mm,
                                                           words):
    """A casing bearing moved where its inner wall cannot go: exit 2 naming the bearing
    component and why, nothing written."""
    root = _xml_root()
    b = _component(root, component)
    next(a for a in b if a.get("id") == "u_coordinate_on_shaft_inner_side").text = u_mm
    src = _write_xml(root, tmp_path / "moved.rexs")
    out = tmp_path / "s.toml"
    assert main(["import", str(src), "--housing", "box", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"bearing component(s) {component}" in err and all(w in err for w in words)
    assert not out.exists()


def test_box_housing_encloses_the_shafts(tmp_path, capsys):
    """Without bearing 34 every casing bearing sits in the front or back plane: the box is
    generated, coaxial shafts 12 and 14 share one bore pair, and the layout checks (every gear
    tip inside the cavity, every bearing at a bore: config/model/layout.py).  The scene as a whole
    is then refused by its load path: without bearing 34, shafts 12 and 14 (joined by bearing
    36) tilt about bearings 33 and 35 as a mechanism, so shaft 14 is free radially."""
    root = _xml_root()
    comps, rels = root.find("components"), root.find("relations")
    comps.remove(_component(root, "34"))
    for r in [r for r in rels if any(x.get("id") == "34" for x in r)]:
        rels.remove(r)
    src = _write_xml(root, tmp_path / "no34.rexs")
    out = tmp_path / "box.toml"
    assert main(["import", str(src), "--housing", "box", "-o", str(out)]) == 0
    data = tomllib.loads(out.read_text())
    bores = {s["name"]: s["bore"] for s in data["gearbox"]["shafts"]}
    assert bores["shaft12"] == bores["shaft14"] != bores["shaft13"]
    h = data["housing"]
    assert len(h["bores"]) == 2
    # the two axes 190 mm apart in the box
    (a, b) = h["bores"]
    assert math.hypot(a["x"] - b["x"], a["z"] - b["z"]) == pytest.approx(0.19, abs=1e-9)
    capsys.readouterr()
    assert main(["check", str(out)]) == 2
    err = capsys.readouterr().err
    assert "gearbox.shafts[2]" in err and "'shaft14' is free radially" in err


def test_detailed_geometry_bearing(tmp_path):
    """A rolling_bearing_with_detailed_geometry with a rolling_bearing_row (REXS 1.2+:
    number_of_rolling_elements, reference_diameter, pressure_angle) and its rolling_element
    (diameter_of_rolling_element): the element set is the file's, nothing assumed by the
    rule."""
    root = _xml_root()
    b = _component(root, "33")
    b.set("type", "rolling_bearing_with_detailed_geometry")
    comps, rels = root.find("components"), root.find("relations")
    row = ET.SubElement(comps, "component", id="901", type="rolling_bearing_row", name="row")
    for aid, unit, val in (("number_of_rolling_elements", "", "10"),
                           ("reference_diameter", "mm", "70"), ("pressure_angle", "deg", "0")):
        ET.SubElement(row, "attribute", id=aid, unit=unit).text = val
    el = ET.SubElement(comps, "component", id="902", type="rolling_element", name="ball")
    ET.SubElement(el, "attribute", id="diameter_of_rolling_element", unit="mm").text = "12.7"
    for rid, a, part in (("951", "33", "901"), ("952", "901", "902")):
        r = ET.SubElement(rels, "relation", id=rid, type="assembly")
        ET.SubElement(r, "ref", hint="", id=a, role="assembly")
        ET.SubElement(r, "ref", hint="", id=part, role="part")
    for x in list(rels):
        for ref in x:
            if ref.get("hint") == "rolling_bearing_with_catalog_geometry":
                ref.set("hint", "rolling_bearing_with_detailed_geometry")
    next(a for a in b if a.get("id") == "catalogue_designation").text = "unknown"
    imp = import_rexs(_write_xml(root, tmp_path / "detailed.rexs"))
    bearing = next(x for x in imp.data["gearbox"]["bearings"] if x["name"] == "bearing33")
    assert (bearing["elements"], bearing["pitch_diameter"], bearing["element_diameter"]) == \
        (10, 0.07, 0.0127)
    sc = load_scene(_write_xml(root, tmp_path / "detailed.rexs"))
    es = next(x for x in sc.gearbox.bearings if x.name == "bearing33").element_set("b")
    assert es.count == 10 and "elements" not in es.assumed and "element_diameter" not in es.assumed


def test_coded_arrays_read_as_plain_ones(tmp_path):
    """REXS allows arrays as base64 of little-endian float64 (``<array code="float64">``);
    the FVA model with its shaft vectors coded imports to the same scene."""
    import base64
    import struct
    root = _xml_root()
    for c in root.iter("component"):
        for a in c:
            arr = a.find("array")
            if arr is not None:
                vals = [float(x.text) for x in arr.findall("c")]
                for x in list(arr):
                    arr.remove(x)
                arr.set("code", "float64")
                arr.text = base64.b64encode(struct.pack(f"<{len(vals)}d", *vals)).decode()
    coded = import_rexs(_write_xml(root, tmp_path / "FVA-Industriegetriebe_2stufig_1-4.rexs"))
    assert coded.data == import_rexs(XML).data


def test_additional_mass_becomes_a_disc(tmp_path):
    root = _xml_root()
    comps, rels = root.find("components"), root.find("relations")
    m = ET.SubElement(comps, "component", id="903", type="additional_mass", name="flywheel")
    for aid, unit, val in (("u_coordinate_on_shaft", "mm", "30"), ("mass_of_component", "kg",
                           "12.5"), ("moment_of_inertia_u_axis", "kg m^2", "0.08"),
                           ("moment_of_inertia_v_axis", "kg m^2", "0.05"),
                           ("moment_of_inertia_w_axis", "kg m^2", "0.05")):
        ET.SubElement(m, "attribute", id=aid, unit=unit).text = val
    r = ET.SubElement(rels, "relation", id="953", type="assembly")
    ET.SubElement(r, "ref", hint="shaft", id="12", role="assembly")
    ET.SubElement(r, "ref", hint="additional_mass", id="903", role="part")
    src = _write_xml(root, tmp_path / "mass.rexs")
    imp = import_rexs(src)
    assert tomllib.loads(scene_toml(imp)) == imp.data
    sc = load_scene(src)
    d = sc.gearbox.shafts[0].discs[0]
    assert (d.position, d.mass, d.Ip, d.Id) == (0.03, 12.5, 0.08, 0.05)
