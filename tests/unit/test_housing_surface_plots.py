"""Shaded housing surfaces (models/housing/surface_mesh.py, report/plots/housing_surface.py,
report/writers/housing_animation.py) against closed forms:

- the drawn surface is dolfinx's boundary: on an nx x ny x nz box, tetrahedra (6 per hex,
  dolfinx's create_box) and hexahedra alike, 2 (nx ny + ny nz + nz nx) boundary quads ->
  twice that many triangles, (nx+1)(ny+1)(nz+1) - (nx-1)(ny-1)(nz-1) vertices; the triangles
  point outwards (divergence theorem: 1/3 sum A n . x_c = the box volume);
- a linear displacement field is reproduced exactly at the vertices; the kinetic-energy
  integral of a unit translation is rho x volume;
- a rigid-body translation is coloured uniformly; the projected box lies inside the axes
  from every camera the pictures use;
- the harmonic of the operating deflection shape is recovered from its modal rates.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from vibrogear.models.housing.surface_mesh import (classify_points, mode_labels, triangulate_facets,
                                                   wall_planes)

BOX = np.array([0.4, 0.25, 0.15])
N = (4, 3, 2)
RHO = 7850.0


def _boundary(cell: str, degree: int = 2):
    """boundary_surface of a create_box mesh with the base (z = 0) tagged 1 and three fields:
    a unit x translation, u = (0, 0, x), u = (0, y, 0)."""
    from mpi4py import MPI
    import dolfinx.mesh as dm
    from dolfinx import fem

    from vibrogear.models.housing.surface_mesh import boundary_surface

    ct = {"tet": dm.CellType.tetrahedron, "hex": dm.CellType.hexahedron}[cell]
    msh = dm.create_box(MPI.COMM_WORLD, [np.zeros(3), BOX], list(N), ct)
    fdim = 2
    msh.topology.create_connectivity(fdim, 3)
    base = dm.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[2], 0.0))
    ftags = dm.meshtags(msh, fdim, np.sort(base).astype(np.int32), np.ones(len(base), np.int32))
    V = fem.VectorFunctionSpace(msh, ("Lagrange", degree))
    xyz = V.tabulate_dof_coordinates()
    n = xyz.shape[0]
    cols = np.zeros((n, 3, 3))
    cols[:, 0, 0] = 1.0
    cols[:, 2, 1] = xyz[:, 0]
    cols[:, 1, 2] = xyz[:, 1]
    Vloc = cols.reshape(3 * n, 3)
    uh = fem.Function(V)
    return boundary_surface(msh, ftags, 1, (), (), uh, Vloc, RHO, MPI.COMM_WORLD)


@pytest.fixture(scope="module", params=["tet", "hex"])
def surface(request):
    return request.param, _boundary(request.param)


def test_triangulate_facets_splits_quads_along_their_cycle():
    tri, src = triangulate_facets(np.array([[10, 11, 12, 13]]))
    # the quad's cycle is 0-1-3-2: both triangles use the diagonal 0-3 and cover the quad once
    assert tri.tolist() == [[10, 11, 13], [10, 13, 12]] and src.tolist() == [0, 0]
    tri, src = triangulate_facets(np.array([[1, 2, 3], [4, 5, 6]]))
    assert tri.tolist() == [[1, 2, 3], [4, 5, 6]] and src.tolist() == [0, 1]
    with pytest.raises(ValueError, match="5 vertices"):
        triangulate_facets(np.zeros((1, 5), int))


def test_drawn_surface_is_the_boundary_of_dolfinx_mesh(surface):
    cell, s = surface
    nx, ny, nz = N
    quads = 2 * (nx * ny + ny * nz + nz * nx)
    assert len(s["shape_triangles"]) == 2 * quads               # tet facets, or quads split in 2
    assert len(s["shape_vertices"]) == (nx + 1) * (ny + 1) * (nz + 1) - (nx - 1) * (ny - 1) * (nz - 1)
    assert np.count_nonzero(s["shape_facet_tag"] == 1) == 2 * nx * ny      # the base
    p = s["shape_vertices"][s["shape_triangles"]]
    n = 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert np.einsum("ij,ij->", n, p.mean(axis=1)) / 3.0 == pytest.approx(np.prod(BOX), rel=1e-12)
    assert np.abs(n).sum() == pytest.approx(2 * (BOX[0] * BOX[1] + BOX[1] * BOX[2] + BOX[2] * BOX[0]))


def test_vertex_values_and_kinetic_energy(surface):
    _, s = surface
    x, u = s["shape_vertices"], s["shape_values"].astype(float)
    np.testing.assert_allclose(u[:, :, 0], np.tile([1.0, 0, 0], (len(x), 1)), atol=1e-6)
    np.testing.assert_allclose(u[:, 2, 1], x[:, 0], atol=1e-6)
    np.testing.assert_allclose(u[:, 1, 2], x[:, 1], atol=1e-6)
    # integral of rho |u|^2: unit translation rho V; (0, 0, x): rho A_yz L^3 / 3
    e = s["region_energy"].sum(axis=1)
    assert e[0] == pytest.approx(RHO * np.prod(BOX), rel=1e-10)
    assert e[1] == pytest.approx(RHO * BOX[1] * BOX[2] * BOX[0] ** 3 / 3, rel=1e-10)
    assert len(s["shape_vertex_region"]) == len(x)


def test_wall_planes_and_regions_of_the_box(surface):
    _, s = surface
    planes = wall_planes(s["shape_vertices"], s["shape_triangles"], s["shape_facet_tag"])
    np.testing.assert_allclose(planes, [0, BOX[0], 0, BOX[1], 0, BOX[2]], atol=1e-12)
    pts = np.array([[0.01, 0.12, 0.07], [0.2, 0.24, 0.07], [0.2, 0.12, 0.149]])
    assert classify_points(pts, planes, ()).tolist() == [0, 3, 5]
    bore = SimpleNamespace(center=(0.2, 0.01, 0.07), axis=(0.0, -1.0, 0.0), radius=0.02,
                           y_range=(-0.01, 0.03))
    assert classify_points(np.array([[0.21, 0.0, 0.08], [0.3, 0.0, 0.08]]), planes,
                           (bore,)).tolist() == [6, 2]


def test_mode_labels_name_the_wall_and_its_motion():
    names = ("left end wall", "right end wall", "front wall", "back wall", "base", "top wall",
             "bore 1 (in/front)")
    normals = np.vstack([-np.eye(3)[0], np.eye(3)[0], -np.eye(3)[1], np.eye(3)[1],
                         -np.eye(3)[2], np.eye(3)[2], -np.eye(3)[1]])
    verts = np.array([[0.1, 0.0, 0.1], [0.2, 0.0, 0.1], [0.1, 0.0, 0.2],
                      [0.1, 0.3, 0.1], [0.2, 0.3, 0.1], [0.1, 0.3, 0.2]])
    region = np.array([2, 2, 2, 3, 3, 3])                      # front wall, back wall
    values = np.zeros((6, 3, 5))
    values[:, 1, [0, 2, 3]] = 1.0                              # along the front wall's normal
    values[:, 0, 1] = 1.0                                      # in its plane, along x
    energy = np.array([[0, 0, .7, .1, 0, .2, 0],
                       [0, 0, .5, .1, 0, .4, 0],
                       [0, 0, .3, .1, 0, .4 - .1, .3],         # front .3 + its bore .3
                       [0, .3, .2, .25, 0, .1, .15],           # front + bore .35, back .25: pair
                       [.15, .1, .25, .05, 0, .35, .1]])
    labels, where = mode_labels(energy, names, normals, verts, values, region)
    assert labels[0] == "front wall bending (70 % of KE)"
    assert labels[1] == "front wall sway along x (50 % of KE)"
    assert labels[2] == "front wall with bore 1 bending (60 % of KE)"
    assert labels[3] == "front and back walls bending (60 % of KE)"
    assert labels[4] == "mixed: top wall 35 %, front wall 25 %"
    assert where.tolist() == [2, 2, 2, 2, 5]          # the region each picture faces


def _res(s, mode=0):
    """A HousingModes-like view of a boundary_surface dict for the plotting functions."""
    m = s["shape_values"].shape[-1]
    from vibrogear.models.housing.surface_mesh import mode_labels as labels

    motion = labels(s["region_energy"], s["region_names"], s["region_normals"], s["shape_vertices"],
                    s["shape_values"], s["shape_vertex_region"])
    return SimpleNamespace(shape_vertices=s["shape_vertices"], shape_triangles=s["shape_triangles"],
                           shape_values=s["shape_values"], shape_facet_tag=s["shape_facet_tag"],
                           region_energy=s["region_energy"], region_normals=s["region_normals"],
                           mode_motion=lambda: motion, freqs_hz=np.arange(1.0, m + 1) * 100,
                           bore_names=(), degree=2, n_dofs=123)


def test_rigid_translation_is_coloured_uniformly(surface):
    from matplotlib import colors
    from vibrogear.report.plots.housing_surface import (agg_pyplot, draw_surface, face_normals,
        mode_panel_data)

    _, s = surface
    res = _res(s)
    disp, val, view, _ = mode_panel_data(res, 0)
    np.testing.assert_allclose(val, 1.0, rtol=1e-6)            # |u| / max |u| = 1 on every face
    plt = agg_pyplot()
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    flat = draw_surface(ax, res.shape_vertices, res.shape_triangles, val, displacement=disp,
                        norm=colors.Normalize(0, 1), view=view, shade=False, outline=False)
    fc = np.asarray(flat.get_facecolor())
    assert len(fc) and np.ptp(fc, axis=0).max() == 0.0
    # shaded: the colour depends on the face's normal only
    ax2 = fig.add_subplot(projection="3d")
    shaded = draw_surface(ax2, res.shape_vertices, res.shape_triangles, val, displacement=disp,
                          norm=colors.Normalize(0, 1), view=view, outline=False)
    from vibrogear.report.plots.housing_surface import camera_direction

    nrm = face_normals(res.shape_vertices + disp, res.shape_triangles)
    front = nrm @ camera_direction(*view) > 0
    key = np.round(nrm[front], 6)
    fc = np.asarray(shaded.get_facecolor())
    # (the collection keeps its faces depth-sorted: compare the sets) one colour per normal
    assert len(fc) == front.sum()
    assert len(np.unique(np.round(fc, 9), axis=0)) <= len(np.unique(key, axis=0))
    plt.close(fig)


@pytest.mark.parametrize("normal", [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)])
def test_projected_extent_contains_the_box(surface, normal):
    from matplotlib import colors
    from mpl_toolkits.mplot3d import proj3d
    from vibrogear.report.plots.housing_surface import (agg_pyplot, draw_surface, mode_panel_data,
        view_angles)

    _, s = surface
    res = _res(s)
    disp, val, _, _ = mode_panel_data(res, 1)
    plt = agg_pyplot()
    fig = plt.figure(figsize=(4.4, 4.0))
    ax = fig.add_subplot(projection="3d")
    coll = draw_surface(ax, res.shape_vertices, res.shape_triangles, val, displacement=disp,
                        norm=colors.Normalize(0, 1), view=view_angles(normal))
    fig.canvas.draw()
    moved = res.shape_vertices + disp
    lo, hi = np.minimum(res.shape_vertices.min(0), moved.min(0)), np.maximum(BOX, moved.max(0))
    corners = np.array([[a, b, c] for a in (lo[0], hi[0]) for b in (lo[1], hi[1]) for c in (lo[2], hi[2])])
    px, py, _ = proj3d.proj_transform(*corners.T, ax.get_proj())
    disp_xy = ax.transData.transform(np.column_stack([px, py]))
    bb = ax.bbox
    assert np.all((disp_xy[:, 0] >= bb.x0 - 0.5) & (disp_xy[:, 0] <= bb.x1 + 0.5))
    assert np.all((disp_xy[:, 1] >= bb.y0 - 0.5) & (disp_xy[:, 1] <= bb.y1 + 0.5))
    assert 0 < len(coll.get_paths()) < len(res.shape_triangles)   # back faces culled
    plt.close(fig)


def test_culling_keeps_exactly_the_faces_towards_the_camera(surface):
    from vibrogear.report.plots.housing_surface import agg_pyplot, draw_surface

    _, s = surface
    v, t = s["shape_vertices"], s["shape_triangles"]
    plt = agg_pyplot()
    fig = plt.figure()
    counts = []
    for view, cull in (((20.0, -60.0), False), ((20.0, -60.0), True), ((-20.0, 120.0), True)):
        ax = fig.add_subplot(projection="3d")
        coll = draw_surface(ax, v, t, np.zeros(len(t)), view=view, cull=cull, outline=False)
        fig.canvas.draw()
        counts.append(len(coll.get_paths()))
    plt.close(fig)
    assert counts[0] == len(t) and counts[1] + counts[2] == len(t)   # opposite cameras


def test_mode_figure_and_animation_are_written(surface, tmp_path):
    from PIL import Image
    from vibrogear.report.writers.housing_animation import MAX_BYTES, animate_surface
    from vibrogear.report.plots.housing_surface import mode_panel_data, plot_mode_shapes

    _, s = surface
    res = _res(s)
    from matplotlib.figure import Figure

    from vibrogear.report.figure import write_figure

    fig = plot_mode_shapes(res, [0, 1, 2])
    assert isinstance(fig, Figure) and not list(tmp_path.iterdir())
    png = write_figure(fig, tmp_path / "modes.png", dpi=100)
    with Image.open(png) as im:
        assert im.size[0] > 600
    disp, val, view, title = mode_panel_data(res, 1)
    anim = animate_surface(tmp_path / "a.png", res.shape_vertices, res.shape_triangles, val, disp,
                           title=title, view=view, n_frames=6)
    assert anim.stat().st_size <= MAX_BYTES
    with Image.open(anim) as im:
        assert getattr(im, "n_frames", 1) == 6 and im.format == "PNG"


def test_operating_shape_recovers_the_harmonic():
    from vibrogear.analyses.nvh.housing_surface import erp_spectrum
    from vibrogear.analyses.nvh.nvh import operating_shape

    n, k = 64, 5
    t = np.arange(n) / n
    X = np.array([1.0 + 2.0j, -0.5j, 0.3])
    rates = np.real(X[:, None] * np.exp(2j * np.pi * k * t)) + 0.1 * np.cos(2 * np.pi * 2 * t)
    G = np.diag([1.0, 2.0, 0.5])
    per_bin = erp_spectrum(G, rates, 1.2, 343.0)
    ods = operating_shape(1500.0, rates, per_bin)
    assert ods["bin"] == k
    np.testing.assert_allclose(ods["modal_velocity"], X, atol=1e-12)
    # the ERP of that harmonic: 1/2 rho c X^H G X
    assert per_bin[k] == pytest.approx(0.5 * 1.2 * 343.0 * np.real(X.conj() @ G @ X), rel=1e-12)


def test_vertex_normal_field_of_a_flat_plate():
    from vibrogear.report.plots.housing_surface import vertex_normal_field

    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    t = np.array([[0, 1, 2], [0, 2, 3]])
    val, nrm = vertex_normal_field(v, t, np.full((2, 3), 2.5 + 1j))
    np.testing.assert_allclose(val, 2.5 + 1j)
    np.testing.assert_allclose(nrm, np.tile([0, 0, 1.0], (4, 1)))


def test_plot_key_validated_and_outside_the_cache_key():
    from vibrogear.config import load_scene
    from vibrogear.config.base import ConfigError
    from vibrogear.models.housing.run import housing_cache_key
    from pathlib import Path

    small = Path(__file__).resolve().parents[2] / "configs" / "housing_small.toml"
    a = load_scene(small).housing
    b = load_scene(small, ("housing.modes.plot=[2, 9]",)).housing
    assert a.modes.plot == (1, 2, 3, 4, 5, 6) and b.modes.plot == (2, 9)
    assert housing_cache_key(a, "modes") == housing_cache_key(b, "modes")
    with pytest.raises(ConfigError, match="housing.modes.plot"):
        load_scene(small, ("housing.modes.plot=[0]",))


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """configs/housing_small.toml solved in a private cache, and its mesh file."""
    import os
    from pathlib import Path

    from vibrogear.cache import open_entry
    from vibrogear.config import load_scene
    from vibrogear.models.housing.run import housing_cache_key, housing_modes

    d = tmp_path_factory.mktemp("vgcache")
    old = os.environ.get("VIBROGEAR_CACHE_DIR")
    os.environ["VIBROGEAR_CACHE_DIR"] = str(d)
    try:
        cfg = load_scene(Path(__file__).resolve().parents[2] / "configs" / "housing_small.toml").housing
        res = housing_modes(cfg)
        yield res, open_entry(housing_cache_key(cfg, "mesh")) / "mesh.msh"
    finally:
        if old is None:
            os.environ.pop("VIBROGEAR_CACHE_DIR")
        else:
            os.environ["VIBROGEAR_CACHE_DIR"] = old


def test_housing_boundary_is_the_msh_boundary_and_energy_sums_to_one(small):
    """The boundary triangles of the solved housing are the faces of the .msh tetrahedra that
    belong to one tetrahedron only (counted by numpy from the file, not from dolfinx), and the
    base-tagged ones the file's base facets; the region energies of each mass-normalised mode
    sum to 1 (x^T M x = 1)."""
    from vibrogear.geometry.housing import BASE_TAG, read_msh_arrays

    res, msh = small
    x, tets, facets, tags = read_msh_arrays(msh)
    faces = np.sort(np.concatenate([tets[:, [0, 1, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 3]],
                                    tets[:, [1, 2, 3]]]), axis=1)
    uniq, count = np.unique(faces, axis=0, return_counts=True)
    boundary = uniq[count == 1]
    assert res.has_shapes and len(res.shape_triangles) == len(boundary)
    assert len(res.shape_vertices) == np.unique(boundary).size
    assert np.count_nonzero(res.shape_facet_tag == 1) == np.count_nonzero(tags == BASE_TAG)
    np.testing.assert_allclose(res.region_energy.sum(axis=1), 1.0, rtol=1e-8)
    labels, where = res.mode_motion()
    assert len(labels) == res.n_modes and all(labels) and where.max() < len(res.region_names)


def test_modes_writer_draws_the_shaded_shapes(small, tmp_path):
    import csv

    from PIL import Image
    from vibrogear.report.writers.housing import write_modes_outputs

    res, _ = small
    files = write_modes_outputs(res, tmp_path, draw=(1, 2, 3, 4, 5, 6, 7, 99))
    assert files["plot"] == "housing_modes.png" and files["plot_2"] == "housing_modes_2.png"
    assert files["animation"] == "housing_mode_1_anim.png"
    assert (tmp_path / "housing_mode_1_anim.png").stat().st_size <= 1_000_000
    with Image.open(tmp_path / "housing_mode_1_anim.png") as im:
        assert im.n_frames == 16
    with (tmp_path / "modes.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert [r["dominant_motion"] for r in rows] == list(res.mode_motion()[0])


def test_ods_faces_the_moving_side_and_is_written(surface, tmp_path):
    """One 'mode' whose normal displacement is 1 on the x = L face only: the drawing moves
    only that face's vertices (along +x), the camera looks at it, the files are written."""
    from vibrogear.analyses.nvh.housing_surface import SurfaceMap
    from vibrogear.report.plots.housing_surface import face_normals, ods_drawing, view_angles
    from vibrogear.report.writers.nvh import write_ods

    _, s = surface
    v, t = s["shape_vertices"], s["shape_triangles"]
    on_face = np.isclose(v[t][:, :, 0], BOX[0]).all(axis=1)
    mid = np.zeros((len(t), 3, 1))
    mid[on_face] = 1.0
    disp, view = ods_drawing(v, t, mid, np.array([2.0j]), 100.0)
    assert view == view_angles((1, 0, 0))
    moved = np.abs(disp).max(axis=1) > 0
    assert np.all(np.isclose(v[moved, 0], BOX[0]))
    inner = np.isclose(v[:, 0], BOX[0]) & (v[:, 1] > 1e-9) & (v[:, 1] < BOX[1] - 1e-9) \
        & (v[:, 2] > 1e-9) & (v[:, 2] < BOX[2] - 1e-9)
    np.testing.assert_allclose(np.real(disp[inner]) / np.abs(disp[inner]).max(), [[1, 0, 0]] * inner.sum(),
                               atol=1e-12)                      # 2j / (i 100) = 0.02: real, along +x
    area = 0.5 * np.linalg.norm(np.cross(v[t][:, 1] - v[t][:, 0], v[t][:, 2] - v[t][:, 0]), axis=1)
    smap = SurfaceMap(columns=np.arange(1), values=mid, weights=np.repeat(area[:, None] / 3, 3, 1),
                      vertices=v, triangles=t, areas=area)
    r = SimpleNamespace(surface=smap, ods={"rpm": 1500.0, "bin": 3, "erp_share": 0.8,
                                           "modal_velocity": np.array([2.0j])},
                        velocity_fields={1500.0: np.where(on_face, 1e-3, 1e-7)}, rpm=np.array([1500.0]),
                        freq_hz=np.array([[0.0, 10.0, 20.0, 30.0]]), order=np.arange(4) / 2,
                        erp_db=np.array([60.0]), study=None)
    files = write_ods(r, tmp_path)
    assert set(files) == {"ods_png", "ods_animation"}
    assert (tmp_path / "housing_ods_anim.png").stat().st_size <= 1_000_000
    assert face_normals(v, t)[on_face][0] @ [1, 0, 0] == pytest.approx(1.0)
