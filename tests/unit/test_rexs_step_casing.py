"""``vibrogear import MODEL.rexs --housing CASING.step --fixed-region ...``: the casing from CAD.

The reference casing is the ``--housing box`` scene's own parametric housing written as a
millimetre STEP file (``geometry.housing.write_housing_step``), clamped on its base plate's
underside as the box is: the STEP scene must have the box scene's frame (shaft axes, bearing
planes), bores where the box has them, pass ``check``, and give the box's housing modes up to
the difference of two tetrahedral meshes of one solid (slow test).
"""
import csv
import tomllib
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main

XML = Path(__file__).resolve().parents[1] / "data" / "rexs" / "FVA-Industriegetriebe_2stufig_1-4.rexs"


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    """(box scene path, its STEP casing in mm, the base plate underside's region as flag text)."""
    from vibrogear.config import load_scene
    from vibrogear.geometry.housing import write_housing_step
    d = tmp_path_factory.mktemp("casing")
    scene = d / "box.toml"
    assert main(["import", str(XML), "--housing", "box", "-o", str(scene)]) == 0
    h = load_scene(scene).housing
    step = write_housing_step(h, d / "casing_mm.step")
    o, tb = h.base_overhang + 0.01, h.base_thickness
    region = f"{-o},{-o},{-tb - 1e-4},{h.length + o},{h.width + o},{-tb + 1e-4}"
    return scene, step, region


def _import(box, tmp_path, *extra, region=None):
    out = tmp_path / "step.toml"
    rc = main(["import", str(XML), "--housing", str(box[1]),
               f"--fixed-region={box[2] if region is None else region}", "-o", str(out), *extra])
    return rc, out


def test_step_casing_takes_the_box_frame_and_a_bore_per_bearing(box, tmp_path, capsys):
    rc, out = _import(box, tmp_path)
    assert rc == 0
    err = capsys.readouterr().err
    s, b = tomllib.loads(out.read_text()), tomllib.loads(box[0].read_text())
    assert s["housing"]["source"] == "step"
    assert (out.parent / s["housing"]["file"]).resolve() == box[1].resolve()
    # the same frame: every shaft's y0 as in the box scene, every bore on its box axis
    assert [sh["y0"] for sh in s["gearbox"]["shafts"]] == [sh["y0"] for sh in b["gearbox"]["shafts"]]
    axis = {x["name"]: (x["x"], x["z"]) for x in b["housing"]["bores"]}
    bores = {x["name"]: x for x in s["housing"]["bores"]}
    assert sorted(bores) == ["axis1/back", "axis1/front", "axis1/inner1", "axis2/back", "axis2/front"]
    shafts = {sh["name"]: sh for sh in s["gearbox"]["shafts"]}
    for name, x in bores.items():
        c = x["center"]
        assert (c[0], c[2]) == axis[name.partition("/")[0]] and x["axis"] == [0.0, 1.0, 0.0]
    # each bore at its casing bearing's plane; the box's walls are at y = 0.01, 0.118, 0.245 (m)
    planes = {"33": "axis1/front", "34": "axis1/inner1", "35": "axis1/back",
              "37": "axis2/front", "38": "axis2/back"}
    for bg in s["gearbox"]["bearings"]:
        if bg["name"].removeprefix("bearing") in planes:
            y = shafts[bg["shaft"]]["y0"] + bg["position"]
            assert bores[planes[bg["name"].removeprefix("bearing")]]["center"][1] == pytest.approx(y, abs=1e-9)
    assert bores["axis1/front"]["center"][1] == pytest.approx(0.01)
    assert bores["axis1/inner1"]["center"][1] == pytest.approx(b["housing"]["inner_walls"][0])
    # 6210: D = 90 mm (ISO 15), the box's bore on that axis too; 33014 (D = 110) and 33012
    # (D = 95) sit in the box's 45 mm bores: the casing's seat is taken and reported
    assert [bores[k]["bore_radius"] for k in ("axis1/front", "axis1/inner1", "axis1/back")] == [0.045] * 3
    assert "bearing's radius 55 mm there; its coaxial cylinder nearest to it, radius 45 mm" in err
    assert "bearing's radius 47.5 mm there" in err and "'axis1/front': the STEP" not in err
    assert [bores[k]["rolling_elements"] for k in ("axis1/front", "axis1/inner1", "axis1/back")] \
        == b["housing"]["bores"][0]["wall_rolling_elements"]
    assert bores["axis2/front"]["bore_radius"] == b["housing"]["bores"][1]["bore_radius"]
    # the assumptions are in the TOML header too, and the scene checks
    assert "# Mapping report" in out.read_text() and "housing frame of `--housing box`" in out.read_text()
    assert main(["check", str(out)]) == 0


def test_fixed_region_in_mm_is_the_same(box, tmp_path):
    mm = ",".join(repr(1000 * float(v)) for v in box[2].split(","))
    rc, out = _import(box, tmp_path, "--length-unit", "mm", region=mm)
    assert rc == 0
    region = tomllib.loads(out.read_text())["housing"]["fixed_region"]
    want = [float(v) for v in box[2].split(",")]
    assert region["min"] + region["max"] == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("args, words", [
    (["--housing", "{d}/nowhere.step", "--fixed-region=0,0,0,1,1,1"], ["--housing", "nowhere.step", "no such file"]),
    (["--housing", "{d}/text.step", "--fixed-region=0,0,0,1,1,1"], ["--housing", "text.step", "not a readable STEP"]),
    (["--housing", "{step}"], ["--fixed-region", "missing", "clamped"]),
    (["--housing", "{step}", "--fixed-region=1,2,3"], ["--fixed-region", "six comma-separated", "'1,2,3'"]),
    (["--housing", "{step}", "--fixed-region=0,0,0,1,a,1"], ["--fixed-region", "six comma-separated"]),
    (["--housing", "{step}", "--fixed-region=0,2,0,1,1,1"], ["--fixed-region", "YMIN = 2 exceeds YMAX = 1"]),
    (["--housing", "{step}", "--fixed-region=5,5,5,6,6,6"], ["--fixed-region", "selects no boundary face"]),
    (["--housing", "box", "--fixed-region=0,0,0,1,1,1"], ["--fixed-region", "only with --housing CASING.step"]),
    (["--housing", "casing.iges"], ["--housing", "expected 'box' or a STEP file"]),
])
def test_bad_casing_input_exits_2_and_writes_nothing(box, tmp_path, capsys, args, words):
    (tmp_path / "text.step").write_text("this is not ISO 10303-21\n")
    args = [a.format(d=tmp_path, step=box[1]) for a in args]
    out = tmp_path / "scene.toml"
    assert main(["import", str(XML), *args, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert not out.exists()
    for w in words:
        assert w in err, (w, err)


def test_casing_in_another_frame_exits_2_naming_the_bore(box, tmp_path, capsys):
    """A casing exported in its CAD frame (here: a plain 300 x 200 x 100 mm block, no bores
    about the FVA shafts' axes) has no seat about the first bearing's axis."""
    import gmsh
    step = tmp_path / "block_mm.step"
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setString("Geometry.OCCTargetUnit", "MM")
        gmsh.model.occ.addBox(0, 0, 0, 300, 200, 100)
        gmsh.model.occ.synchronize()
        gmsh.write(str(step))
    finally:
        gmsh.finalize()
    out = tmp_path / "scene.toml"
    assert main(["import", str(XML), "--housing", str(step), "--fixed-region=0,0,0,0.3,0.2,0",
                 "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert not out.exists()
    assert "--housing" in err and "bore 'axis1/front'" in err and "housing frame" in err


def _edit_after(path, anchor: str, old: str, new: str) -> None:
    """Replace the first ``old`` after ``anchor`` in the scene file (a hand edit)."""
    text = path.read_text()
    j = text.index(old, text.index(anchor))
    path.write_text(text[:j] + new + text[j + len(old):])


def test_run_names_a_bore_without_faces(box, tmp_path, capsys):
    """A bore edited off its seat in the written scene: the run exits 2 naming the bore entry
    before any output is written."""
    rc, out = _import(box, tmp_path)
    assert rc == 0
    _edit_after(out, 'name = "axis1/inner1"', "bore_radius = 0.045", "bore_radius = 0.05")
    capsys.readouterr()
    res = tmp_path / "res"
    assert main(["modes", str(out), "--out", str(res), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "housing.bores[1]" in err and "no face lies on the cylinder of radius 0.05 m" in err
    assert not res.exists()


def _housing_freqs(scene, size, count=10):
    from vibrogear.config import load_scene
    from vibrogear.models.housing.run import housing_modes
    sc = load_scene(scene, (f"housing.mesh.size={size}", f"housing.modes.count={count}"))
    return housing_modes(sc.housing, cache=False).freqs_hz[:count]


@pytest.mark.slow
def test_step_casing_gives_the_box_housing_modes(box, tmp_path):
    """The box scene and its STEP import are one solid meshed twice (the parametric mesher with
    its junction grading, the STEP mesher with its bore grading), both clamped on the base
    plate's underside.  Their first ten housing frequencies must agree to within the meshes'
    own discretisation error, and closer on finer meshes.  Measured under load (P2 tetrahedra,
    ~100 s in all): size 0.026 m, 109k / 96k DOF: gaps 0.07 .. 0.38 %; size 0.018 m, 240k /
    199k DOF: gaps 0.03 .. 0.18 %; the box's own frequencies move by 0.3 .. 1.1 % between
    the two sizes, more than the gap on the finer mesh in every mode."""
    rc, out = _import(box, tmp_path)
    assert rc == 0
    coarse = [_housing_freqs(s, 0.026) for s in (box[0], out)]
    fine = [_housing_freqs(s, 0.018) for s in (box[0], out)]
    gap_coarse = np.abs(coarse[1] - coarse[0]) / coarse[0]
    gap_fine = np.abs(fine[1] - fine[0]) / fine[0]
    assert gap_coarse.max() < 5e-3
    assert gap_fine.max() < 0.6 * gap_coarse.max() and gap_fine.max() < 2.5e-3
    assert np.sqrt(np.mean(gap_fine ** 2)) < 0.75 * np.sqrt(np.mean(gap_coarse ** 2))
    assert np.all(np.abs(fine[1] - fine[0]) < np.abs(coarse[0] - fine[0]))


def test_several_seats_in_a_window_take_the_one_at_the_bearing(box):
    """A window along the whole second axis holds its front, inner-wall and back seats (all of
    radius 81 mm in the box): the front bore shrinks its window to the seat at its plane,
    the front wall and boss, y = -0.02 .. 0.02 m about the plane y = 0.01 m."""
    from vibrogear.cli_import import _seat_radii_from_step
    from vibrogear.config.rexs.mapping import MappingReport

    class Imp:
        report = MappingReport()
        data = {"housing": {"bores": [{"name": "axis2/front", "center": [0.157413888, 0.01, 0.157413888],
                                       "axis": [0.0, 1.0, 0.0], "length": 0.6, "bore_radius": 0.09}],
                            "mesh": {"size": 0.045}}}
    _seat_radii_from_step(Imp, str(box[1]))
    b = Imp.data["housing"]["bores"][0]
    assert b["bore_radius"] == 0.081          # the casing's seat, not the 90 mm asked for
    assert b["length"] == pytest.approx(2 * 0.03 + 1e-4, abs=1e-6)
    text = "\n".join(Imp.report.assumed)
    assert "3 separate seats of radius 81 mm" in text and "radius 90 mm there" in text
    assert Imp.data["housing"]["mesh"]["size"] == pytest.approx(0.5 * 0.081)   # follows the seat
    assert text.count("tetrahedral P2 mesh, size 0.0405 m") == 1


@pytest.mark.slow
def test_gearbox_modes_with_the_step_casing_are_the_box_ones(box, tmp_path):
    """``vibrogear modes`` of the whole gearbox on the STEP casing, no hand edit: the shafts find
    their per-bearing bores (``axis<k>/<wall>``), and the coupled modes are the box scene's up
    to the two housing meshes' difference (STEP: size 0.0225 m by the import's rule; box:
    0.026 m).  Measured under load (~40 s for both): the first 20 within 0.31 %, the same
    dominant subsystem in each."""
    rc, out = _import(box, tmp_path)
    assert rc == 0
    res = {}
    for name, scene in (("box", box[0]), ("step", out)):
        assert main(["modes", str(scene), "--out", str(tmp_path / name), "--quiet"]) == 0
        res[name] = list(csv.DictReader(open(tmp_path / name / "modes.csv")))
    assert len(res["step"]) == len(res["box"])
    fb = np.array([float(r["frequency_hz"]) for r in res["box"][:20]])
    fs = np.array([float(r["frequency_hz"]) for r in res["step"][:20]])
    assert np.max(np.abs(fs - fb) / fb) < 5e-3
    assert [r["dominant"] for r in res["step"][:20]] == [r["dominant"] for r in res["box"][:20]]


def test_bores_of_one_axis_off_its_line_are_named(box, tmp_path, capsys):
    """The bores ``axis1/<wall>`` all carry the axis ``axis1``: one moved off the line is an
    input error at ``check`` naming it."""
    rc, out = _import(box, tmp_path)
    assert rc == 0
    _edit_after(out, 'name = "axis1/back"', "center = [0.347413888", "center = [0.35")
    capsys.readouterr()
    assert main(["check", str(out)]) == 2
    err = capsys.readouterr().err
    assert "housing.bores[2].center" in err and "'axis1/back'" in err and "one line" in err
