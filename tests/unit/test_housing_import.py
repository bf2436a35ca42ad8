"""Imported housings, fast parts: the ``[housing] source`` schema, bad inputs through the CLI
(exit 2, the field and the file named, no output file), bore grouping and ring frames, and the
modal readers' checks on hand-made data (frequencies, normalisation, layouts)."""
from __future__ import annotations

import os
import shutil
import stat
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.config import ConfigError, load_scene
from vibrogear.config.base import build
from vibrogear.config.model.housing import HousingConfig
from vibrogear.geometry.housing import BoreGeometry, ring_frame
from vibrogear.geometry.housing_import import bore_segments

ROOT = Path(__file__).resolve().parents[2]

BORE = {"name": "input", "center": [0.1, 0.08, 0.09], "axis": [0, 1, 0], "bore_radius": 0.02,
        "rolling_elements": 8}


def _touch(tmp_path, name, text="x"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _cfg(**kw):
    return build(HousingConfig, kw, "housing")


def test_parametric_default_and_cache_key_data_unchanged():
    """The parametric housing keeps its schema and its pre-import cache-key data."""
    h = load_scene(ROOT / "configs" / "housing_small.toml").housing
    assert h.source == "parametric" and h.file is None and h.fixed_region is None
    d = h.key_data()
    assert not {"source", "file", "fixed_region", "length_unit"} & set(d)
    assert not {"center", "axis", "length"} & set(d["bores"][0])


def test_bore_line_along_y_gives_x_and_z(tmp_path):
    f = _touch(tmp_path, "h.step")
    h = _cfg(source="step", file=str(f), fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]},
             mesh={"size": 0.02}, bores=[BORE])
    b = h.bores[0]
    assert (b.x, b.z) == (0.1, 0.09) and b.unit_axis == (0.0, 1.0, 0.0)
    tilted = _cfg(source="step", file=str(f), fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]},
                  mesh={"size": 0.02}, bores=[{**BORE, "axis": [1, 1, 0]}])
    assert tilted.bores[0].x is None
    assert np.allclose(tilted.bores[0].unit_axis, [2 ** -0.5, 2 ** -0.5, 0])


def test_file_key_digest_follows_content(tmp_path):
    f = _touch(tmp_path, "m.inp", "one")
    h = _cfg(source="mesh", file=str(f), fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]})
    k1 = h.key_data()["file"]["sha256"]
    f.write_text("two")
    assert h.key_data()["file"]["sha256"] != k1


@pytest.mark.parametrize("kw, field, words", [
    (dict(source="step", file="nowhere.step", fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]},
          mesh={"size": 0.02}), "housing.file", "no such file"),
    (dict(source="step", file="{tmp}/h.iges", mesh={"size": 0.02},
          fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]}), "housing.file", "unsupported file type"),
    (dict(source="mesh", file="{tmp}/h.step", fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]}),
     "housing.file", ".inp"),
    (dict(source="step", fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]}, mesh={"size": 0.02}),
     "housing.file", "missing required key"),
    (dict(source="step", file="{tmp}/h.step", mesh={"size": 0.02}), "housing.fixed_region", "missing"),
    (dict(source="step", file="{tmp}/h.step", fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]}),
     "housing.mesh.size", "element size"),
    (dict(source="step", file="{tmp}/h.step", mesh={"size": 0.02},
          fixed_region={"min": [0, 0, 0], "max": [1, -1, 0]}), "housing.fixed_region.max[1]", ">= min[1]"),
    (dict(source="step", file="{tmp}/h.step", mesh={"size": 0.02}, length=0.3,
          fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]}), "housing.length", "only for source"),
    (dict(source="step", file="{tmp}/h.step", mesh={"size": 0.02},
          fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]}, bores=[{**BORE, "axis": [0, 0, 0]}]),
     "housing.bores[0].axis", "non-zero"),
    (dict(source="step", file="{tmp}/h.step", mesh={"size": 0.02},
          fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]}, bores=[{k: v for k, v in BORE.items() if k != "center"}]),
     "housing.bores[0].center", "missing required key"),
    (dict(source="step", file="{tmp}/h.step", mesh={"size": 0.02},
          fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]}, bores=[{**BORE, "boss_radius": 0.03}]),
     "housing.bores[0].boss_radius", "only for the parametric"),
    (dict(source="modal", file="{tmp}/m.npz", fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]}),
     "housing.fixed_region", "not for source = 'modal'"),
    (dict(length=0.3, width=0.2, height=0.2, wall_thickness=0.01, file="{tmp}/h.step",
          bores=[dict(x=0.1, z=0.1, bore_radius=0.02, boss_radius=0.035, rolling_elements=9)]),
     "housing.file", "only for an imported"),
    (dict(length=0.3, width=0.2, height=0.2, wall_thickness=0.01), "housing.bores", "at least 1"),
    (dict(width=0.2, height=0.2, wall_thickness=0.01,
          bores=[dict(x=0.1, z=0.1, bore_radius=0.02, boss_radius=0.035, rolling_elements=9)]),
     "housing.length", "missing required key"),
])
def test_schema_errors_name_the_field(tmp_path, kw, field, words):
    for name in ("h.step", "h.iges", "m.npz"):
        _touch(tmp_path, name)
    kw = {k: (v.format(tmp=tmp_path) if isinstance(v, str) else v) for k, v in kw.items()}
    with pytest.raises(ConfigError) as exc:
        _cfg(**kw)
    assert exc.value.path == field and words in str(exc.value)


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads files without read permission")
def test_unreadable_file(tmp_path):
    f = _touch(tmp_path, "h.step")
    f.chmod(0)
    try:
        with pytest.raises(ConfigError, match="not readable"):
            _cfg(source="step", file=str(f), mesh={"size": 0.02},
                 fixed_region={"min": [0, 0, 0], "max": [1, 1, 0]})
    finally:
        f.chmod(stat.S_IRUSR | stat.S_IWUSR)


_SCENE = """[scene]
name = "imp"
analyses = ["modes"]
[housing]
source = "{source}"
file = "{file}"
{extra}
[[housing.bores]]
name = "input"
center = [0.075, 0.08, 0.09]
axis = {axis}
bore_radius = 0.02
rolling_elements = 8
"""


def _scene(tmp_path, *, source="step", file="data/h.step", axis="[0, 1, 0]",
           extra='fixed_region = { min = [-1, -1, -0.016], max = [1, 1, -0.014] }\nmesh = { size = 0.03 }'):
    p = tmp_path / "scene.toml"
    p.write_text(_SCENE.format(source=source, file=file, axis=axis, extra=extra))
    return p


def test_file_is_relative_to_the_scene_and_check_passes(tmp_path, capsys):
    (tmp_path / "data").mkdir()
    shutil.copy(ROOT / "configs" / "data" / "housing_feet_ribs_mm.step", tmp_path / "data" / "h.step")
    scene = _scene(tmp_path)
    s = load_scene(scene)
    assert Path(s.housing.file) == tmp_path / "data" / "h.step"
    assert main(["check", str(scene)]) == 0


@pytest.mark.parametrize("change, field, words", [
    ("bore_radius = 0.02", "housing.bores[0]", "cuts no boundary face"),
    ("max = [1, 1, -0.014]", "housing.fixed_region", "selects no boundary face"),
    ("__empty__", "housing.file", "not a readable STEP file"),
])
def test_check_opens_the_step_file(tmp_path, capsys, change, field, words):
    """``check`` selects a STEP housing's bores and clamped faces as the mesher will: a bore
    off its seat (radius 21 mm on the 20 mm seat), a clamping box below the feet, or a file
    that is no STEP exit 2 naming the field (the shipped housing_step.toml's solid)."""
    (tmp_path / "data").mkdir()
    src = ROOT / "configs" / "data" / "housing_feet_ribs_mm.step"
    if change == "__empty__":
        _touch(tmp_path / "data", "h.step")
    else:
        shutil.copy(src, tmp_path / "data" / "h.step")
    scene = _scene(tmp_path)
    text = scene.read_text()
    if change == "bore_radius = 0.02":
        text = text.replace(change, "bore_radius = 0.021")
    elif change.startswith("max"):
        text = text.replace("min = [-1, -1, -0.016], max = [1, 1, -0.014]",
                            "min = [-1, -1, -0.06], max = [1, 1, -0.05]")
    scene.write_text(text)
    assert main(["check", str(scene)]) == 2
    err = capsys.readouterr().err
    assert field in err and words in err


@pytest.mark.parametrize("case, field, words", [
    ("missing", "housing.file", "no such file"),
    ("suffix", "housing.file", "unsupported file type"),
    ("axis", "housing.bores[0].axis", "non-zero"),
])
def test_cli_check_rejects_bad_input_with_exit_2(tmp_path, capsys, case, field, words):
    (tmp_path / "data").mkdir()
    _touch(tmp_path / "data", "h.step")
    _touch(tmp_path / "data", "h.txt")
    kw = {"missing": dict(file="data/none.step"), "suffix": dict(file="data/h.txt"),
          "axis": dict(axis="[0, 0, 0]")}[case]
    scene = _scene(tmp_path, **kw)
    for verb in ("check", "run"):
        out = tmp_path / f"out_{verb}"
        assert main([verb, str(scene), "--quiet", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert field in err and words in err
        assert not out.exists()


def test_bore_segments_merge_touching_intervals():
    segs = bore_segments([(0.15, 0.17), (-0.01, 0.01), (0.01, 0.015), (0.17, 0.175)], 1e-9)
    assert [(a, b) for a, b, _ in segs] == [(-0.01, 0.015), (0.15, 0.175)]
    assert [sorted(i) for _, _, i in segs] == [[1, 2], [0, 3]]


@pytest.mark.parametrize("axis", [(0, 1, 0), (0, -1, 0), (1, 0, 0), (0, 0, 1), (1, 2, -3)])
def test_ring_frame_is_orthonormal_and_sign_free(axis):
    e1, e2 = ring_frame(axis)
    u = np.asarray(axis, float) / np.linalg.norm(axis)
    G = np.array([e1, e2, u])
    assert np.allclose(np.abs(G @ G.T), np.eye(3), atol=1e-14)
    f1, f2 = ring_frame(-np.asarray(axis, float))
    assert np.array_equal(e1, f1) and np.array_equal(e2, f2)


def test_ring_points_along_y_are_the_parametric_ones():
    """For an axis along y, theta runs from +x towards +z (the parametric housing's rule)."""
    g = BoreGeometry(name="b", center=(0.1, 0.0, 0.2), axis=(0.0, -1.0, 0.0), radius=0.5,
                     y_range=(0, 0), n_points=4)
    assert np.allclose(g.points(), [[0.6, 0, 0.2], [0.1, 0, 0.7], [-0.4, 0, 0.2], [0.1, 0, -0.3]], atol=1e-15)


# ----------------------------------------------------------------------------- modal readers

def _modal_npz(path, freqs=(100.0, 250.0, 400.0), scale=1.0, **extra):
    rng = np.random.default_rng(3)
    m = len(freqs)
    th = 2 * np.pi * np.arange(4) / 4
    ring = lambda y: np.column_stack([0.075 + 0.02 * np.cos(th), np.full(4, y), 0.09 + 0.02 * np.sin(th)])  # noqa: E731
    data = dict(freqs_hz=np.array(freqs), bore_values=scale * rng.uniform(-1, 1, (2, 4, 3, m)),
                bore_points=np.stack([ring(0.0), ring(0.16)]), bore_n_points=np.array([4, 4]),
                bore_names=np.array(["input/front", "input/back"]), **extra)
    np.savez(path, **data)
    return data


def _modal_cfg(path, **kw):
    bore = {**BORE, "rolling_elements": 4, "center": [0.075, 0.08, 0.09]}
    return _cfg(source="modal", file=str(path), bores=[bore], modes={"count": 3}, **kw)


def test_modal_npz_modal_mass_and_units(tmp_path):
    """Modes with modal masses mu_i are divided by sqrt(mu_i); a millimetre file's lengths
    (points and mode values, mass in kg) are multiplied by 1e-3."""
    from vibrogear.models.housing.run import housing_modes

    mu = np.array([4.0, 1.0, 9.0])
    d = _modal_npz(tmp_path / "m.npz", modal_mass=mu)
    r = housing_modes(_modal_cfg(tmp_path / "m.npz"))
    assert np.array_equal(r.freqs_hz, d["freqs_hz"])
    assert np.allclose(r.bore_values, d["bore_values"] / np.sqrt(mu), rtol=1e-15, atol=0)
    assert np.allclose(r.bore_center_values, r.bore_values.mean(axis=1), rtol=1e-14, atol=1e-17)
    assert np.allclose(r.bore_centers, [[0.075, 0.0, 0.09], [0.075, 0.16, 0.09]], atol=1e-15)
    assert np.array_equal(r.bore_axes, [[0, -1, 0], [0, 1, 0]])
    assert r.source_info["mass_normalisation"] == "divided by sqrt(modal mass)"
    _modal_npz(tmp_path / "mm.npz")
    np.savez(tmp_path / "mm.npz", **{**dict(np.load(tmp_path / "mm.npz")),
                                     "bore_points": d["bore_points"] * 1e3})
    mm = housing_modes(_modal_cfg(tmp_path / "mm.npz", length_unit="mm"))
    with np.load(tmp_path / "mm.npz") as z:
        assert np.allclose(mm.bore_values, 1e-3 * z["bore_values"], rtol=1e-15, atol=0)
    assert np.allclose(mm.bore_points, d["bore_points"], rtol=1e-15)


@pytest.mark.parametrize("freqs, kw, words", [
    ((100.0, 90.0, 400.0), {}, "not ascending: mode 2"),
    ((-1.0, 90.0, 400.0), {}, "negative natural frequency"),
    ((100.0, np.nan, 400.0), {}, "finite"),
    ((100.0, 200.0, 400.0), {"modal_mass": np.array([1.0, 0.0, 1.0])}, "positive"),
])
def test_modal_bad_data_exit_2_naming_the_file(tmp_path, capsys, freqs, kw, words):
    _modal_npz(tmp_path / "m.npz", freqs=freqs, **kw)
    scene = tmp_path / "s.toml"
    scene.write_text('[scene]\nname = "m"\nanalyses = ["modes"]\n[housing]\nsource = "modal"\nfile = "m.npz"\n')
    out = tmp_path / "out"
    assert main(["run", str(scene), "--quiet", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "housing.file" in err and "m.npz" in err and words in err
    assert not (out / "summary.json").exists()


def test_modal_unit_maximum_normalisation_is_refused(tmp_path):
    from vibrogear.models.housing.run import housing_modes

    d = _modal_npz(tmp_path / "m.npz")
    v = d["bore_values"] / np.abs(d["bore_values"]).max(axis=(0, 1, 2))
    np.savez(tmp_path / "m.npz", **{**d, "bore_values": v})
    with pytest.raises(ConfigError, match="unit maximum"):
        housing_modes(_modal_cfg(tmp_path / "m.npz"))


def test_modal_csv_layout_and_config_check(tmp_path):
    """The CSV layout round-trips the NPZ data (repr floats: exact); a config bore off the
    file's bore line or with another rolling-element count is named."""
    from vibrogear.models.housing.modal import write_modes_csv
    from vibrogear.models.housing.run import housing_modes

    _modal_npz(tmp_path / "m.npz")
    a = housing_modes(_modal_cfg(tmp_path / "m.npz"))
    write_modes_csv(a, tmp_path / "m.csv")
    b = housing_modes(_modal_cfg(tmp_path / "m.csv"))
    for k in ("freqs_hz", "bore_values", "bore_points", "bore_axes"):
        assert np.array_equal(getattr(a, k), getattr(b, k), equal_nan=True), k
    assert a.bore_names == b.bore_names
    with pytest.raises(ConfigError) as exc:
        housing_modes(_cfg(source="modal", file=str(tmp_path / "m.csv"),
                           bores=[{**BORE, "rolling_elements": 4, "center": [0.08, 0, 0.09]}]))
    assert exc.value.path == "housing.bores[0].center" and "off the line" in str(exc.value)
    with pytest.raises(ConfigError) as exc:
        housing_modes(_cfg(source="modal", file=str(tmp_path / "m.csv"),
                           bores=[{**BORE, "center": [0.075, 0.5, 0.09]}]))
    assert exc.value.path == "housing.bores[0].rolling_elements"


def test_modal_uff_without_modes_names_dataset_58(tmp_path):
    import pyuff

    from vibrogear.models.housing.run import housing_modes

    f = tmp_path / "frf.unv"
    d = pyuff.prepare_58(binary=0, id1="frf", func_type=4, rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1,
                         ord_data_type=5, abscissa_spacing=1, abscissa_spec_data_type=18,
                         ordinate_spec_data_type=12, orddenom_spec_data_type=13, z_axis_spec_data_type=0,
                         data=np.ones(8, complex), x=np.arange(8.0), rsp_ent_name="pt", ref_ent_name="pt")
    pyuff.UFF(str(f)).write_sets(d, mode="overwrite")
    with pytest.raises(ConfigError, match="dataset 58 holds response functions"):
        housing_modes(_cfg(source="modal", file=str(f)))


def test_modal_uff_dataset_55_round_trip(tmp_path):
    """Nodes (dataset 15) and normal modes (dataset 55) written by pyuff: the ring nodes on the
    config bore's cylinder are found, grouped front/back and ordered by angle; values agree to
    the precision of the UFF fields, modal masses 4 and 9 divide the modes by 2 and 3."""
    import pyuff

    from vibrogear.models.housing.run import housing_modes

    d = _modal_npz(tmp_path / "m.npz")
    pts = d["bore_points"].reshape(-1, 3)
    vals = d["bore_values"].reshape(-1, 3, 3)
    order = np.random.default_rng(0).permutation(len(pts))         # node numbers in any order
    extra = np.array([[0.0, 0.0, 0.0], [0.3, 0.16, 0.15]])         # nodes off the bores
    X = np.vstack([pts[order], extra])
    V = np.concatenate([vals[order], np.ones((2, 3, 3))])
    nodes = np.arange(1, len(X) + 1)
    f = tmp_path / "modes.unv"
    uff = pyuff.UFF(str(f))
    uff.write_sets(pyuff.prepare_15(node_nums=nodes, def_cs=[0] * len(X), disp_cs=[0] * len(X),
                                    color=[0] * len(X), x=X[:, 0], y=X[:, 1], z=X[:, 2]), mode="overwrite")
    mu = [1.0, 4.0, 9.0]
    for i, fr in enumerate(d["freqs_hz"]):
        uff.write_sets(pyuff.prepare_55(
            model_type=1, id1="m", id2="m", id3="m", id4="m", id5="m", analysis_type=2, data_ch=2,
            spec_data_type=8, data_type=2, n_data_per_node=3, r1=V[:, 0, i], r2=V[:, 1, i], r3=V[:, 2, i],
            node_nums=nodes, load_case=1, mode_n=i + 1, modal_m=mu[i], freq=fr, modal_damp_vis=0.0,
            modal_damp_his=0.0), mode="add")
    r = housing_modes(_modal_cfg(f))
    assert r.bore_names == ("input/front", "input/back") and r.bore_n_points == (4, 4)
    assert np.allclose(r.freqs_hz, d["freqs_hz"], rtol=1e-5)
    assert np.allclose(r.bore_points, d["bore_points"], atol=1e-6)
    assert np.allclose(r.bore_values, d["bore_values"] / np.sqrt(mu), atol=1e-6)
    assert np.allclose(r.bore_axes, [[0, -1, 0], [0, 1, 0]])
    with pytest.raises(ConfigError) as exc:
        housing_modes(_cfg(source="modal", file=str(f), bores=[{**BORE, "center": [0.075, 0, 0.09]}]))
    assert exc.value.path == "housing.bores[0].rolling_elements"
