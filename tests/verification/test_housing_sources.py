"""Imported housings against independent references.

* STEP: the parametric housing written by gmsh as a millimetre STEP file and imported back has
  the closed-form solid volume (so the unit conversion is right) and the parametric run's first
  20 frequencies within 0.5 %; a millimetre STEP cantilever reproduces the parametric cantilever
  on the same mesh, lies above the Timoshenko closed form of test_housing_cantilever by the
  3D-vs-beam margin, and converges monotonically from above on nested meshes.
* Meshes: one tetrahedral mesh written by meshio as Abaqus, Nastran, Gmsh, VTU and XDMF (and
  as 10-node tetrahedra) gives the spectrum of the original mesh to 1e-10.
* Modes: a modal housing made from a parametric housing's own exported modes gives the same
  reduced gearbox model bit for bit and the same coupled frequencies.
* Bad files: no tetrahedra, a fixed region selecting nothing, a bore cutting no face, an open
  shell: exit 2 naming the field and the file.
"""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.config import ConfigError, load_scene
from vibrogear.config.base import as_data, build
from vibrogear.config.model.housing import HousingConfig, MaterialConfig
from vibrogear.geometry.housing import build_beam_mesh, housing_volume, read_msh_arrays, write_housing_step
from vibrogear.models.housing.fe import solve_mesh_modes
from vibrogear.models.housing.run import housing_modes

from test_housing_cantilever import B, E, H, L, NU, RHO, timoshenko_cantilever_f1  # noqa: I001

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture()
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VIBROGEAR_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache"


def _small(size=0.02, count=20) -> HousingConfig:
    d = as_data(load_scene(ROOT / "configs" / "housing_small.toml").housing)
    d["mesh"]["size"] = size
    d["modes"].update(count=count, shapes=0)
    return build(HousingConfig, d, "housing")


def _bore_lines(cfg: HousingConfig) -> list[dict]:
    return [{"name": b.name, "center": [b.x, 0.5 * cfg.width, b.z], "axis": [0, 1, 0],
             "bore_radius": b.bore_radius, "rolling_elements": b.rolling_elements} for b in cfg.bores]


def _write_box_step(path: Path, lx_mm: float, ly_mm: float, lz_mm: float) -> Path:
    import gmsh

    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setString("Geometry.OCCTargetUnit", "MM")   # OCC's unit is process-wide
        gmsh.model.add("box")
        gmsh.model.occ.addBox(0, 0, 0, lx_mm, ly_mm, lz_mm)
        gmsh.model.occ.synchronize()
        gmsh.write(str(path))            # gmsh labels STEP coordinates as millimetres
    finally:
        gmsh.finalize()
    return path


def test_step_of_the_parametric_housing_gives_its_modes(tmp_path):
    par = _small()
    ref = housing_modes(par, cache=False)
    step = write_housing_step(par, tmp_path / "housing_mm.step")
    assert re.search(r"SI_UNIT\(\.MILLI\.,\.METRE\.\)", step.read_text())
    imp = build(HousingConfig, {
        "source": "step", "file": str(step), "bores": _bore_lines(par),
        "fixed_region": {"min": [-1, -1, -par.base_thickness], "max": [1, 1, -par.base_thickness]},
        "material": as_data(par.material), "mesh": {"size": par.mesh_size, "bore_size": par.bore_mesh_size},
        "modes": {"count": 20, "shapes": 0}}, "housing")
    res = housing_modes(imp, cache=False)
    info = res.source_info
    # OCC's volume of the millimetre file in m^3 is the closed-form volume: units honoured
    assert info["volume_m3"] == pytest.approx(housing_volume(par), rel=1e-9)
    assert info["solids"] == 1 and info["fixed_faces"] == 1 and info["bore_faces"] == [1, 1, 1, 1]
    # the same bores, coupling points and outward axes as the parametric layout
    assert res.bore_names == ref.bore_names
    assert np.allclose(res.bore_points, ref.bore_points, atol=1e-12, equal_nan=True)
    assert np.allclose(res.bore_axes, ref.bore_axes, atol=1e-15)
    rel = res.freqs_hz / ref.freqs_hz - 1
    print(f"STEP vs parametric, first 20 modes: max |rel| = {np.abs(rel).max():.2e} "
          f"({res.n_dofs} vs {ref.n_dofs} DOF)")
    assert np.abs(rel).max() < 5e-3
    assert res.residuals.max() < 1e-6 and res.orthogonality_error < 1e-8


@pytest.fixture(scope="module")
def beam_step(tmp_path_factory):
    return _write_box_step(tmp_path_factory.mktemp("step") / "beam_mm.step", 1000 * L, 1000 * B, 1000 * H)


def _beam_cfg(step, size, refine=0, count=2):
    return build(HousingConfig, {
        "source": "step", "file": str(step), "fixed_region": {"min": [0, 0, 0], "max": [0, B, H]},
        "material": {"E": E, "nu": NU, "rho": RHO}, "mesh": {"size": size, "refine": refine},
        "modes": {"count": count, "shapes": 0}}, "housing")


def test_step_cantilever_is_the_parametric_cantilever(beam_step, tmp_path):
    """Same box, same element size (the STEP rules allow smaller elements near edges, so the
    meshes differ by a few nodes): the frequencies agree far inside this mesh's 0.5 % discretisation
    error, and lie within [0, 1.5 %] above Timoshenko like the parametric cantilever's."""
    res = housing_modes(_beam_cfg(beam_step, 0.025, count=4), cache=False)
    mesh = build_beam_mesh(L, B, H, tmp_path / "beam.msh", size=0.025)
    ref = solve_mesh_modes(mesh, material=MaterialConfig(E=E, nu=NU, rho=RHO), degree=2, count=4)
    assert abs(res.n_dofs / ref.n_dofs - 1) < 0.02
    assert np.abs(res.freqs_hz / ref.freqs_hz - 1).max() < 1e-4
    f_thin = timoshenko_cantilever_f1(E=E, nu=NU, rho=RHO, L=L, b=B, h=H)
    assert 0.0 < res.freqs_hz[0] / f_thin - 1 < 0.015
    assert res.mass_kg == pytest.approx(RHO * L * B * H, rel=1e-10)


def test_step_cantilever_converges_on_nested_meshes(beam_step):
    """Uniform splits (h, h/2, h/4): monotone convergence from above; the observed order p of
    f1 lies between the clamp's edge-singularity bound (~1.4) and P2's smooth-solution h^4,
    and the Richardson limit sits 0-0.6 % above Timoshenko's beam value (the 3D solid is
    slightly stiffer than beam theory, test_housing_cantilever: ~0.4 %)."""
    f = np.array([housing_modes(_beam_cfg(beam_step, 0.1, refine=k), cache=False).freqs_hz[0] for k in range(3)])
    assert f[0] > f[1] > f[2]
    p = math.log2((f[0] - f[1]) / (f[1] - f[2]))
    f_inf = f[2] - (f[1] - f[2]) / (2 ** p - 1)
    f_beam = timoshenko_cantilever_f1(E=E, nu=NU, rho=RHO, L=L, b=B, h=H)
    print(f"STEP cantilever f1 on h, h/2, h/4: {f}; order {p:.2f}; limit {f_inf:.4f} Hz, "
          f"{f_inf / f_beam - 1:+.3%} vs Timoshenko")
    assert 1.2 < p < 4.5
    assert 0.0 < f_inf / f_beam - 1 < 0.006


# ----------------------------------------------------------------------------- FE mesh files

@pytest.fixture(scope="module")
def beam_mesh(tmp_path_factory):
    d = tmp_path_factory.mktemp("beam")
    mesh = build_beam_mesh(L, B, H, d / "beam.msh", size=0.05)
    ref = solve_mesh_modes(mesh, material=MaterialConfig(E=E, nu=NU, rho=RHO), degree=2, count=6)
    x, tets, _, _ = read_msh_arrays(mesh.path)
    return d, x, tets, ref


def _tetra10(x, tets):
    """10-node tetrahedra (meshio/VTK order: vertices, then edges 01 12 02 03 13 23) with
    straight-edge midpoints."""
    edges = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]
    mid, pts, cells = {}, list(x), []
    for t in tets:
        row = list(t)
        for a, b in edges:
            key = tuple(sorted((t[a], t[b])))
            if key not in mid:
                mid[key] = len(pts)
                pts.append(0.5 * (x[t[a]] + x[t[b]]))
            row.append(mid[key])
        cells.append(row)
    return np.array(pts), np.array(cells)


@pytest.mark.parametrize("suffix, kind", [(".inp", "tetra"), (".bdf", "tetra"), (".msh", "tetra"),
                                          (".vtu", "tetra"), (".xdmf", "tetra"), (".inp", "tetra10"),
                                          (".vtu", "tetra10")])
def test_mesh_file_formats_give_the_same_spectrum(beam_mesh, suffix, kind):
    """meshio writes the mesh (millimetres) in each format; the imported housing's spectrum is
    the original mesh's to 1e-10 (10-node tetrahedra keep their vertices: same geometry)."""
    import meshio

    d, x, tets, ref = beam_mesh
    pts, cells = (x, tets) if kind == "tetra" else _tetra10(x, tets)
    f = d / f"beam_{kind}{suffix}"
    kw = {"file_format": "gmsh22", "binary": False} if suffix == ".msh" else {}
    meshio.write(f, meshio.Mesh(1000.0 * pts, [(kind, cells)]), **kw)
    cfg = build(HousingConfig, {"source": "mesh", "file": str(f), "length_unit": "mm",
                                "fixed_region": {"min": [0, 0, 0], "max": [0, B, H]},
                                "material": {"E": E, "nu": NU, "rho": RHO},
                                "modes": {"count": 6, "shapes": 0}}, "housing")
    res = housing_modes(cfg, cache=False)
    assert res.n_dofs == ref.n_dofs and res.source_info["cells"] == {kind: len(tets)}
    assert np.abs(res.freqs_hz / ref.freqs_hz - 1).max() < 1e-10
    assert res.mass_kg == pytest.approx(RHO * L * B * H, rel=1e-10)


def test_mesh_housing_bores_and_clamp_from_the_parametric_mesh(tmp_path, cache):
    """The parametric housing's own mesh exported to VTU and imported with fixed_region and
    bore lines: the same spectrum and the same coupling values as the parametric run."""
    import meshio

    par = _small(size=0.03, count=8)
    ref = housing_modes(par, cache=True)
    mesh_file = next(Path(cache).glob("housing-mesh-*/mesh.msh"))
    x, tets, _, _ = read_msh_arrays(mesh_file)
    f = tmp_path / "housing.vtu"
    meshio.write(f, meshio.Mesh(x, [("tetra", tets)]))
    imp = build(HousingConfig, {
        "source": "mesh", "file": str(f), "bores": _bore_lines(par),
        "fixed_region": {"min": [-1, -1, -par.base_thickness], "max": [1, 1, -par.base_thickness]},
        "material": as_data(par.material), "modes": {"count": 8, "shapes": 0}}, "housing")
    res = housing_modes(imp, cache=False)
    assert res.n_dofs == ref.n_dofs and res.bore_names == ref.bore_names
    assert np.abs(res.freqs_hz / ref.freqs_hz - 1).max() < 1e-10
    # mode signs are arbitrary: compare |values| at the coupling points, scaled by the largest
    a, b = np.abs(ref.bore_values), np.abs(res.bore_values)
    assert np.nanmax(np.abs(a - b)) < 1e-7 * np.nanmax(a)


@pytest.mark.parametrize("case, field, words", [
    ("tris", "housing.file", "no tetrahedra"),
    ("region", "housing.fixed_region", "selects no boundary face"),
    ("bore", "housing.bores[0]", "cuts no boundary face"),
    ("shell", "housing.file", "holds no solid"),
])
def test_bad_files_exit_2_naming_field_and_file(beam_mesh, tmp_path, capsys, cache, case, field, words):
    import meshio

    d, x, tets, _ = beam_mesh
    region = "{ min = [0, 0, 0], max = [0, 0.1, 0.05] }"
    bores = ""
    if case == "tris":
        f = tmp_path / "tris.vtu"
        meshio.write(f, meshio.Mesh(x, [("triangle", tets[:, :3])]))
    else:
        f = tmp_path / "beam.vtu"
        meshio.write(f, meshio.Mesh(x, [("tetra", tets)]))
    if case == "region":
        region = "{ min = [2, 0, 0], max = [3, 0.1, 0.05] }"
    if case == "bore":
        bores = ('[[housing.bores]]\nname = "b"\ncenter = [0.5, 0.05, 0.025]\naxis = [0, 1, 0]\n'
                 'bore_radius = 0.01\nrolling_elements = 8\n')
    source = "mesh"
    if case == "shell":
        import gmsh
        f, source = tmp_path / "shell.step", "step"
        gmsh.initialize(readConfigFiles=False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.option.setString("Geometry.OCCTargetUnit", "MM")
            gmsh.model.occ.addRectangle(0, 0, 0, 100, 50)
            gmsh.model.occ.synchronize()
            gmsh.write(str(f))
        finally:
            gmsh.finalize()
    scene = tmp_path / "s.toml"
    scene.write_text(f'[scene]\nname = "bad"\nanalyses = ["modes"]\n[housing]\nsource = "{source}"\n'
                     f'file = "{f.name}"\nfixed_region = {region}\nmesh = {{ size = 0.05 }}\n{bores}')
    out = tmp_path / "out"
    assert main(["run", str(scene), "--quiet", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert field in err and words in err and f.name in err
    assert not (out / "summary.json").exists()
    assert not [p for p in Path(cache).glob("*") if p.name.startswith(".housing")]   # no half-built entry


# ----------------------------------------------------------------------------- modes from a file

def _modal_scene_text(text: str, npz: Path, cfg: HousingConfig) -> str:
    """single_stage.toml with its [housing] replaced by a modal housing reading ``npz``."""
    start, end = text.index("[housing]"), text.index("[integration]")
    bores = "".join(f'[[housing.bores]]\nname = "{b["name"]}"\ncenter = {b["center"]}\naxis = [0, 1, 0]\n'
                    f'bore_radius = {b["bore_radius"]}\nrolling_elements = {b["rolling_elements"]}\n\n'
                    for b in _bore_lines(cfg))
    modal = (f'[housing]\nsource = "modal"\nfile = "{npz}"\n\n{bores}'
             f'[housing.material]\nbeta = {cfg.material.beta!r}\n\n[housing.modes]\ncount = {cfg.modes.count}\n\n')
    return text[:start] + modal + text[end:]


def test_modal_housing_from_exported_modes_reproduces_the_gearbox(tmp_path, cache):
    """The modes a parametric housing run exports (housing_modes.npz) read back as a modal
    housing: the same reduced gearbox model bit for bit, hence the same coupled frequencies."""
    from vibrogear.report.writers.housing import write_modes_outputs
    from vibrogear.models.gearbox.model import build_gearbox

    sets = ["gearbox.shafts.0.master_count=8", "gearbox.shafts.1.master_count=8", "housing.modes.count=10"]
    src = ROOT / "configs" / "single_stage.toml"
    par_scene = load_scene(src, tuple(sets))
    write_modes_outputs(housing_modes(par_scene.housing), tmp_path / "exported", plot=False)
    modal_path = tmp_path / "single_stage_modal.toml"
    modal_path.write_text(_modal_scene_text(src.read_text(), tmp_path / "exported" / "housing_modes.npz",
                                            par_scene.housing))
    modal_scene = load_scene(modal_path, tuple(sets[:2]))
    assert modal_scene.housing.source == "modal"
    a, b = build_gearbox(par_scene), build_gearbox(modal_scene)
    ra, rb = a.reduced, b.reduced
    for name in ("omega2", "damping"):
        assert np.array_equal(getattr(ra, name), getattr(rb, name)), name
    assert np.array_equal(ra.coupling.P, rb.coupling.P)
    assert np.array_equal(ra.contacts.directions, rb.contacts.directions)
    assert np.array_equal(ra.forcing.Fc, rb.forcing.Fc) and np.array_equal(ra.forcing.Fs, rb.forcing.Fs)
    outs = []
    for scene, extra in ((src, sets), (modal_path, sets[:2])):
        out = tmp_path / f"out_{scene.stem}"
        assert main(["modes", str(scene), "--quiet", "--out", str(out)] + sum((["--set", s] for s in extra), [])) == 0
        outs.append(json.loads((out / "summary.json").read_text())["results"]["modes"])
    fa, fb = (np.array(o["first_frequencies_hz"]) for o in outs)
    assert fa.size >= 12 and np.array_equal(fa, fb)
