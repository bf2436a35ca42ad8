"""vibrogear from Python (vibrogear/api.py, docs/python.md): load, replace, run in memory.

The references are independent of the code under test: the scene file's own numbers (the
speed grid, the backlash), the files ``vibrogear run`` writes for the same scene (a run in
memory must give exactly the arrays and the verdict the command line writes), and the
message ``vibrogear check --set`` prints for the same bad value.
"""
from __future__ import annotations

import json
import pydoc
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import vibrogear as vg
from vibrogear import cli

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "configs" / "gear_pair.toml"
#: a short sweep: 5 speeds up and down (the gear pair's contact loss lies above 5100 rpm)
SHORT = {"sweep.n_points": 5, "sweep.transient_periods": 100,
         "sweep.extra_transient_periods": 100, "sweep.record_periods": 16}


def test_import_vibrogear_stays_cheap():
    code = ("import sys, vibrogear as vg; assert callable(vg.load); "
            "print(sorted(m for m in ('numba', 'dolfinx', 'matplotlib', 'gmsh', 'scipy') "
            "if m in sys.modules))")
    fresh = subprocess.run([sys.executable, "-c", "import sys, vibrogear; print(sorted(m for m "
                            "in ('numba', 'dolfinx', 'matplotlib', 'gmsh', 'scipy') if m in "
                            "sys.modules))"], capture_output=True, text=True, check=True)
    assert fresh.stdout.strip() == "[]"
    touched = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             check=True)
    assert touched.stdout.strip() == "[]"          # the API module itself loads no solver
    assert vg.__version__ == __import__("vibrogear.version").version.__version__


def test_load_takes_overrides_as_a_dict_or_as_set_strings():
    a = vg.load(SCENE, {"sweep.n_points": 7, "gearbox.meshes[0].backlash": 5e-5})
    b = vg.load(SCENE, ["sweep.n_points=7", "gearbox.meshes[0].backlash=5e-5"])
    assert a == b
    assert (a.sweep.n_points, a.gearbox.meshes[0].backlash) == (7, 5e-5)


def test_replace_returns_a_new_checked_scene_and_leaves_the_old_one():
    scene = vg.load(SCENE)
    new = scene.replace({"gearbox.meshes[0].backlash": 5e-5, "sweep.n_points": np.int64(6)})
    assert new.gearbox.meshes[0].backlash == 5e-5 and new.sweep.n_points == 6
    assert scene.gearbox.meshes[0].backlash == 1e-4 and scene.sweep.n_points == 151
    assert new.replace({}) == new


def test_a_bad_value_is_refused_naming_the_field_as_check_does(capsys):
    scene = vg.load(SCENE)
    with pytest.raises(vg.ConfigError) as err:
        scene.replace({"gearbox.meshes[0].backlash": -1e-5})
    assert err.value.path == "gearbox.meshes[0].backlash"
    assert "out of range: must be >= 0" in str(err.value)
    code = cli.main(["check", str(SCENE), "--set", "gearbox.meshes[0].backlash=-1e-5"])
    assert code == cli.EXIT_INPUT
    assert str(err.value) in capsys.readouterr().err       # the same message
    with pytest.raises(vg.ConfigError, match=r"sweep\.n_pointz: unknown key.*'n_points'"):
        scene.replace({"sweep.n_pointz": 6})
    with pytest.raises(vg.ConfigError, match=r"gearbox\.meshes\[2\]: no such list entry"):
        scene.replace({"gearbox.meshes[2].backlash": 5e-5})
    with pytest.raises(vg.ConfigError, match=r"sweep\.n_points: expected an integer"):
        vg.load(SCENE, {"sweep.n_points": "six"})
    with pytest.raises(vg.ConfigError, match="scene.analyses"):
        vg.run(scene, ["campbell"])                   # a rotor's verb, not a gearbox's


@pytest.fixture(scope="module")
def in_memory(tmp_path_factory):
    """load -> replace -> run(["sweep"]) from an empty working folder with an empty cache."""
    import os
    cwd, cache = tmp_path_factory.mktemp("cwd"), tmp_path_factory.mktemp("cache")
    old, old_cache = os.getcwd(), os.environ.get("VIBROGEAR_CACHE_DIR")
    os.chdir(cwd)
    os.environ["VIBROGEAR_CACHE_DIR"] = str(cache)
    try:
        scene = vg.load(SCENE).replace({**SHORT, "gearbox.meshes[0].backlash": 5e-5})
        run = vg.run(scene, ["sweep"])
        fig = run.results["sweep"].plot()
    finally:
        os.chdir(old)
        if old_cache is None:
            os.environ.pop("VIBROGEAR_CACHE_DIR")
        else:
            os.environ["VIBROGEAR_CACHE_DIR"] = old_cache
    return scene, run, fig, cwd, cache


def test_a_run_in_memory_writes_nothing_and_returns_arrays_and_a_figure(in_memory):
    from matplotlib.figure import Figure

    scene, run, fig, cwd, cache = in_memory
    assert list(cwd.iterdir()) == [] and list(cache.iterdir()) == []
    assert run.out is None and run.status == "ok" and list(run.results) == ["sweep"]
    a = run.results["sweep"].arrays()
    grid = np.linspace(4500.0, 7000.0, 5)                    # the scene file's [sweep] range
    assert np.allclose(a["param"], np.concatenate([grid, grid[::-1]]))
    assert list(a["direction"]) == ["up"] * 5 + ["down"] * 5
    assert a["poincare"].shape == (10, 16)
    assert np.all(a["qmin"] <= a["qmax"])
    assert run.results["sweep"].study.monitor.lines == (-50.0,)   # -backlash in um
    assert isinstance(fig, Figure) and len(fig.axes) >= 2
    assert isinstance(run.findings["verdict"], str) and run.findings["verdict"]
    assert run.summary["results"]["sweep"]["points"] == 10
    assert "files" not in run.summary["results"]["sweep"]


def test_a_run_into_a_folder_writes_what_the_command_line_writes(in_memory, tmp_path):
    scene, run, _, _, _ = in_memory
    out = tmp_path / "out"
    on_disk = vg.run(scene, ["sweep"], out=out)
    assert on_disk.out == out
    assert {"sweep.npz", "sweep.csv", "bifurcation.png", "summary.json",
            "report.html"} <= {p.name for p in out.iterdir()}
    assert not list(out.glob("*.partial.jsonl"))
    with np.load(out / "sweep.npz", allow_pickle=False) as z:
        written = {k: z[k] for k in z.files}
    mem = run.results["sweep"].arrays()
    assert sorted(mem) == sorted(written)                       # the npz's names
    for k in ("param", "qmin", "qmax", "poincare", "period_n", "motion_class"):
        np.testing.assert_array_equal(mem[k], written[k])      # deterministic: the same run
    summary = json.loads((out / "summary.json").read_text())
    assert run.findings["verdict"] == summary["findings"]["verdict"]
    assert [b["from"] for b in run.findings["bands"]] == \
        [b["from"] for b in summary["findings"]["bands"]]


def test_modes_in_memory_equal_the_modes_csv(tmp_path):
    from matplotlib.figure import Figure

    scene = vg.load(SCENE)
    res = vg.run(scene, "modes").results["modes"]
    assert isinstance(res.plot(), Figure)
    vg.run(scene, ["modes"], out=tmp_path)
    import csv
    rows = list(csv.DictReader((tmp_path / "modes.csv").open()))
    a = res.arrays()
    assert np.array_equal(a["frequency_hz"], [float(r["frequency_hz"]) for r in rows])
    assert list(a["dominant"]) == [r["dominant"] for r in rows]
    assert np.allclose(a["mesh_energy_G1"], [float(r["mesh_energy_G1"]) for r in rows],
                       rtol=1e-3, atol=1e-4)                    # the csv keeps 4 digits


@pytest.mark.parametrize("cls, entries", [
    ("vibrogear.analyses.time_response:TimeResponseResult",
     ["delta", "(nc, n) [m]", "t_s", "[s]", "force", "[N]", "period"]),
    ("vibrogear.analyses.sweep.sweep:SweepStudyResult",
     ["qmin", "[m", "poincare", "(N, R)", "impacts", "[1/period]", "arrays", "plot"]),
    ("vibrogear.solvers.sequential.sweep:SweepResult",
     ["param", "(N,)", "qmax", "[model length, m]", "lyapunov", "[1/model time]", "wall_time"]),
    ("vibrogear.analyses.continuation:ContinuationStudyResult",
     ["branch.npz", "qmin", "(M,) [m", "floquet", "label"]),
    ("vibrogear.solvers.periodic.branch:ContinuationResult",
     ["param", "(M,)", "period", "[model time units]", "u0", "(M, n)", "residual"]),
    ("vibrogear.analyses.gearbox_modes:GearboxModesResult",
     ["f_hz", "(K,) [Hz]", "zeta", "(K,) [1]", "mesh", "(M, K) [1]", "rpm_lo", "[rpm]"]),
    ("vibrogear.analyses.states.states:StatesResult",
     ["params", "(P,) [rpm or Omega]", "attractors", "fraction", "basin_fraction", "[m"]),
])
def test_help_lists_the_fields_with_units_and_shapes(cls, entries):
    import importlib
    module, name = cls.split(":")
    text = pydoc.render_doc(getattr(importlib.import_module(module), name),
                            renderer=pydoc.plaintext)
    missing = [e for e in entries if e not in text]
    assert not missing, f"help({name}) lacks {missing}"


def test_the_example_notebook_runs_and_writes_nothing():
    """docs/examples/gear_pair.ipynb, executed as a user would (a Jupyter kernel in its
    folder): no cell fails, the folder stays as it was, the sweep prints the scene's grid."""
    nbclient = pytest.importorskip("nbclient")
    nbformat = pytest.importorskip("nbformat")
    pytest.importorskip("ipykernel")
    folder = ROOT / "docs" / "examples"
    before = sorted(p.name for p in folder.iterdir())
    nb = nbformat.read(folder / "gear_pair.ipynb", as_version=4)
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(folder)}}).execute()
    assert sorted(p.name for p in folder.iterdir()) == before
    text = "\n".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                     for o in c.outputs)
    assert "refused: gearbox.meshes[0].backlash: value -1e-05 out of range" in text
    assert "  4500 rpm up" in text and "  7000 rpm down" in text
    assert "backlash 0.05 mm:" in text and "backlash 0.2 mm: " in text
    figures = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs
               if "image/png" in o.get("data", {})]
    assert figures                                    # the Figure shows as the cell's value


def test_import_rexs_gives_the_scene_vibrogear_import_maps():
    """The FVA two-stage gearbox (REXS 1.4): the gear data the file states (test_rexs_import)."""
    path = ROOT / "tests" / "data" / "rexs" / "FVA-Industriegetriebe_2stufig_1-4.rexs"
    scene = vg.import_rexs(path)
    teeth = {g.name: (g.teeth, g.module, g.helix_angle) for g in scene.gearbox.gears}
    assert teeth["gear15"] == (27, 0.0045, 21.0) and teeth["gear17"] == (51, 0.0045, 21.0)
    assert teeth["gear16"] == (23, 0.0065, 10.0) and teeth["gear18"] == (34, 0.0065, 10.0)
    assert vg.load(path) == scene                      # load imports a REXS file the same way
    with pytest.raises(vg.ConfigError, match="housing"):
        vg.import_rexs(path, housing="casing.step")
    with pytest.raises(vg.ConfigError, match=r"\*\.rexs"):
        vg.import_rexs(SCENE)


def test_replace_refills_what_the_scene_derives_as_a_set_does():
    """single_stage with the housing's box sizes and bore positions left to the gearbox
    (config/model/housing_sizing.py): a thicker wall through ``replace`` gives the scene the file
    with that wall gives, the box grown by twice the 5 mm (margin = tip + wall + 5 mm)."""
    import copy

    from vibrogear.config.scene import read_toml, scene_from_dict
    data = read_toml(ROOT / "configs" / "single_stage.toml")
    for k in ("length", "width", "height"):
        data["housing"].pop(k)
    for b in data["housing"]["bores"]:
        b.pop("x"), b.pop("z")
    scene = scene_from_dict(copy.deepcopy(data))
    thick = scene.replace({"housing.wall_thickness": 0.02})
    edited = copy.deepcopy(data)
    edited["housing"]["wall_thickness"] = 0.02
    assert thick == scene_from_dict(edited)
    assert thick.housing.length == pytest.approx(scene.housing.length + 2 * 0.005, abs=1e-9)


def test_time_response_and_branches_in_memory():
    """The time response's clock from the scene alone: 40 mesh periods of the 40-tooth
    pinion at 5800 rpm last 40 x 60 / (5800 x 40) s, sampled 32 times a period; the branch
    figure and arrays of a short continuation."""
    from matplotlib.figure import Figure

    scene = vg.load(SCENE, {"time_response.periods": 40, "continuation.max_points": 12})
    run = vg.run(scene, ["time_response", "continuation"])
    tr = run.results["time_response"].arrays()
    assert tr["t_s"][-1] == pytest.approx(40 * 60.0 / (5800.0 * 40), rel=1e-12)
    assert tr["t_s"].shape == (40 * 32 + 1,)
    assert tr["delta"].shape == tr["force"].shape == (len(tr["names"]), tr["t_s"].size)
    assert tr["names"][0] == "G1"
    assert isinstance(run.results["time_response"].plot(), Figure)
    br = run.results["continuation"]
    a = br.arrays()
    assert {"param", "qmin", "qmax", "stable", "label", "floquet", "branch"} <= set(a)
    assert np.all((a["param"] >= 4500.0 - 1e-9) & (a["param"] <= 7000.0 + 1e-9))
    assert isinstance(br.plot("qmin"), Figure)
    assert isinstance(run.results["continuation"].plot(sweep=None), Figure)
    with pytest.raises(ValueError, match="qmax"):
        br.plot("q")


@pytest.mark.slow                     # ~19 s on two cores: two runs of each, one writing figures
def test_map_and_runup_in_memory_judge_as_their_files_do(tmp_path):
    """The findings of a run in memory come from the results' arrays; a run into a folder
    derives them from the files it wrote (map.npz, runup.npz): the same bands and verdict."""
    scene = vg.load(SCENE, {"map.n_speeds": 3, "map.n_loads": 2, "map.curves": False,
                            "map.transient_periods": 60, "map.extra_transient_periods": 60,
                            "map.record_periods": 16, "runup.rpm_end": 5000.0,
                            "runup.rate": 800.0})
    for verb in ("map", "runup"):
        mem = vg.run(scene, [verb])
        disk = vg.run(scene, [verb], out=tmp_path / verb)
        summary = json.loads((tmp_path / verb / "summary.json").read_text())
        assert mem.findings["bands"] == summary["findings"]["bands"]
        assert mem.findings["verdict"] == summary["findings"]["verdict"] == \
            disk.findings["verdict"]
        with np.load(tmp_path / verb / f"{verb}.npz", allow_pickle=False) as z:
            a = mem.results[verb].arrays()
            assert sorted(a) == sorted(z.files)
            for k in z.files:
                if k != "wall_time":                  # the one entry that is a clock
                    np.testing.assert_array_equal(a[k], z[k], err_msg=k)


def test_compare_of_a_run_with_itself_and_with_a_band_taken_away(in_memory):
    """vg.compare on the same run twice: nothing added, removed or moved, every band kept;
    on a copy of its findings without its first band (through a run folder written here):
    exactly that band is reported removed."""
    import copy
    import json
    import tempfile
    _scene, run, _fig, _cwd, _cache = in_memory
    bands = [b for b in run.findings["bands"] if b["severity"] != "fine"]
    assert bands, "the short gear_pair sweep has bands to compare"
    same = vg.compare(run, run)
    assert not same["bands"]["added"] and not same["bands"]["removed"]
    assert not same["bands"]["moved"] and len(same["bands"]["kept"]) == len(bands)
    fewer = copy.deepcopy(run.summary)
    gone = bands[0]
    fewer["findings"]["bands"] = [b for b in fewer["findings"]["bands"] if b is not None
                                  and b != gone]
    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "summary.json").write_text(json.dumps(fewer, default=str))
        diff = vg.compare(run, d)
    assert diff["bands"]["removed"] == [gone] and not diff["bands"]["added"]
