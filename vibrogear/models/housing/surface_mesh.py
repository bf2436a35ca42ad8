"""The housing's whole boundary surface for pictures: triangles, the master modes' displacement
at its vertices and which wall or bore each mode moves.

Two halves.  :func:`boundary_surface` (dolfinx, called from :func:`.fe.solve_mesh_modes`) takes
every exterior facet of the solid mesh, triangle facets of tetrahedra as they are and quad
facets of hexahedra split into two triangles (0, 1, 3) and (0, 3, 2) in dolfinx's
tensor-product vertex order, orients each so that (b - a) x (c - a) points out of the solid,
evaluates each mode's displacement vector at the vertices and each cell's share
rho |phi_i|^2 of the modal kinetic energy (for mass-normalised modes the shares of a mode sum
to 1).  The other half is numpy only: :func:`wall_planes` finds the outer wall planes of the
surface, :func:`classify_points` assigns points to walls and bores, :func:`mode_labels` names
each mode's dominant motion.  Fields carried by :class:`~.result.HousingModes`:

- ``shape_vertices``    (nv, 3)     vertex coordinates, m
- ``shape_triangles``   (nt, 3)     vertex indices, outward orientation
- ``shape_facet_tag``   (nt,)       0: free surface, 1: supported (fixed) base, 2 + b: bore b
- ``shape_values``      (nv, 3, m)  mass-normalised displacement (float32), 1/sqrt(kg)
- ``shape_vertex_region`` (nv,)     region of each vertex (index into ``region_names``)
- ``region_normals``    (R, 3)      outward normal of each region (wall plane / bore axis)
- ``region_energy``     (m, R)      integral of rho |phi_i|^2 over each region (sums to 1 over
                                    the regions for mass-normalised modes)
- meta: ``region_names`` (R,): the six walls, then "bore b (name)", then "inner wall k" for
  each inner wall of a parametric housing (known from its bores ``<name>/inner<k>``)

:func:`mode_labels` names each mode from these ("front wall bending (71 % of KE)") and gives
the region its picture should face.
"""
from __future__ import annotations

import re

import numpy as np

__all__ = ["boundary_surface", "triangulate_facets", "wall_planes", "classify_points", "outer_skin",
           "mode_labels", "SHAPE_FIELDS", "empty_shape_fields", "WALL_NAMES", "BOSS_RADIUS_FACTOR"]

SHAPE_FIELDS = ("shape_vertices", "shape_triangles", "shape_facet_tag", "shape_values",
                "shape_vertex_region", "region_normals", "region_energy")
#: the six outer wall planes, in the order of :data:`_DIRECTIONS` (names of the parametric
#: box: front wall at y = 0, back wall at y = width, x from the left end to the right end)
WALL_NAMES = ("left end wall", "right end wall", "front wall", "back wall", "base", "top wall")
_PAIRS = ("both end walls", "front and back walls", "base and top wall")
_DIRECTIONS = np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]], float)
#: points within this many bore radii of a bore's axis (and within its axial extent) belong to
#: the bore's region (the parametric bosses are 1.5-1.7 bore radii)
BOSS_RADIUS_FACTOR = 1.7
#: a mode is named after one region when that region holds at least this share of its energy
DOMINANT_SHARE = 0.4
#: ... or a pair of opposite walls (with their bores) together at least this share
PAIR_SHARE = 0.3


def empty_shape_fields(m: int = 0) -> dict:
    return {"shape_vertices": np.zeros((0, 3)), "shape_triangles": np.zeros((0, 3), np.int32),
            "shape_facet_tag": np.zeros(0, np.int16), "shape_values": np.zeros((0, 3, m), np.float32),
            "shape_vertex_region": np.zeros(0, np.int16),
            "region_normals": np.zeros((0, 3)), "region_energy": np.zeros((m, 0))}


def triangulate_facets(nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(triangles (nt, 3) of node indices, source facet of each triangle (nt,)) from facet
    vertex lists (nf, 3) (triangles, kept) or (nf, 4) (quads in dolfinx's tensor-product
    order 0-1 / 2-3, whose cycle is 0-1-3-2: two triangles each)."""
    nodes = np.asarray(nodes)
    nf = len(nodes)
    if nodes.shape[1] == 3:
        return nodes.copy(), np.arange(nf)
    if nodes.shape[1] == 4:
        tri = np.stack([nodes[:, [0, 1, 3]], nodes[:, [0, 3, 2]]], axis=1).reshape(-1, 3)
        return tri, np.repeat(np.arange(nf), 2)
    raise ValueError(f"facets with {nodes.shape[1]} vertices: expected 3 (tetrahedra) or 4 (hexahedra)")


def outer_skin(verts: np.ndarray, tris: np.ndarray, tags: np.ndarray | None = None) -> np.ndarray:
    """Mask of the non-bore triangles (``tags`` < 2) in the connected pieces that reach the
    bounding box: the outer skin (the bores, left out, are what joins it to a closed
    housing's cavity)."""
    if tags is not None:
        out = np.zeros(len(tris), bool)
        sel = np.asarray(tags) < 2
        out[sel] = outer_skin(verts, np.asarray(tris)[sel])
        return out
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    nt = len(tris)
    if nt == 0:
        return np.zeros(0, bool)
    inc = sp.csr_matrix((np.ones(3 * nt), (np.repeat(np.arange(nt), 3), tris.ravel())),
                        shape=(nt, len(verts)))
    _, label = connected_components(inc @ inc.T, directed=False)
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    tol = 1e-6 * float(np.linalg.norm(hi - lo))
    on_box = np.any((np.abs(verts - lo) <= tol) | (np.abs(verts - hi) <= tol), axis=1)
    return np.isin(label, np.unique(label[np.any(on_box[tris], axis=1)]))


def wall_planes(verts: np.ndarray, tris: np.ndarray, tags: np.ndarray) -> np.ndarray:
    """(6,) plane coordinate of each outer wall along :data:`_DIRECTIONS` (NaN: no such wall):
    among the outer skin's non-bore triangles whose normal is within 18 degrees of the
    direction, the plane holding the largest area (a wall's face beats a base plate's
    overhang or a boss's end face)."""
    verts, tris = np.asarray(verts, float), np.asarray(tris)
    out = np.full(6, np.nan)
    if len(tris) == 0:
        return out
    a, b, c = (verts[tris[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    area = 0.5 * np.linalg.norm(n, axis=1)
    unit = n / np.maximum(2 * area, 1e-300)[:, None]
    keep = outer_skin(verts, tris, tags)
    size = float(np.ptp(verts, axis=0).max())
    centre = (a + b + c) / 3.0
    for k, d in enumerate(_DIRECTIONS):
        sel = keep & (unit @ d > 0.95)
        if not np.any(sel):
            continue
        coord = np.round(centre[sel] @ np.abs(d) / (1e-6 * size)).astype(np.int64)
        vals, inv = np.unique(coord, return_inverse=True)
        out[k] = vals[np.argmax(np.bincount(inv, weights=area[sel]))] * 1e-6 * size
    return out


def inner_wall_planes(bores) -> list[float]:
    """Middle plane y of each inner wall (1, 2, ...), from the bores named ``<name>/inner<k>``
    (:mod:`vibrogear.config.model.housing_walls`); [] for a housing without inner walls."""
    planes: dict[int, float] = {}
    for b in bores:
        m = re.search(r"/inner(\d+)$", getattr(b, "name", "") or "")
        if m:
            planes.setdefault(int(m.group(1)), 0.5 * (b.y_range[0] + b.y_range[1]))
    return [planes[k] for k in sorted(planes)]


def classify_points(points: np.ndarray, planes: np.ndarray, bores) -> np.ndarray:
    """Region index of each point: 6 + b inside bore b's boss (within
    :data:`BOSS_RADIUS_FACTOR` bore radii of its axis, within its axial extent), else the
    wall whose plane is nearest: the six outer walls, then the inner walls (6 + B + k)."""
    p = np.asarray(points, float).reshape(-1, 3)
    inner = inner_wall_planes(bores)
    dist = np.full((len(p), 6 + len(inner)), np.inf)
    for k, d in enumerate(_DIRECTIONS):
        if np.isfinite(planes[k]):
            dist[:, k] = np.abs(p @ np.abs(d) - planes[k])
    for k, y in enumerate(inner):
        dist[:, 6 + k] = np.abs(p[:, 1] - y)
    region = np.argmin(dist, axis=1)
    region[region >= 6] += len(bores)
    for j, b in enumerate(bores):
        ax = np.asarray(b.axis, float) / np.linalg.norm(b.axis)
        rel = p - np.asarray(b.center, float)
        s = rel @ ax
        radial = np.linalg.norm(rel - np.outer(s, ax), axis=1)
        half = 0.5 * abs(b.y_range[1] - b.y_range[0]) if abs(ax[1]) > 0.99 else 2 * b.radius
        region[(radial <= BOSS_RADIUS_FACTOR * b.radius) & (np.abs(s) <= half * 1.05)] = 6 + j
    return region


def region_normals(planes: np.ndarray, bores) -> np.ndarray:
    return np.vstack([_DIRECTIONS] + [np.asarray(b.axis, float) / np.linalg.norm(b.axis)
                                      for b in bores]
                     + [np.array([0.0, 1.0, 0.0])] * len(inner_wall_planes(bores))).reshape(-1, 3)


def region_names(bores) -> tuple[str, ...]:
    return WALL_NAMES + tuple(f"bore {j + 1} ({b.name})" for j, b in enumerate(bores)) + tuple(
        f"inner wall {k + 1}" for k in range(len(inner_wall_planes(bores))))


def _wall_motion(u: np.ndarray, normal: np.ndarray) -> str:
    """'bending' when the motion normal to the wall carries most of the vertices' |u|^2, else
    'sway along <axis>' (the in-plane axis with the larger share)."""
    total = float(np.sum(u * u))
    if total > 0 and float(np.sum((u @ normal) ** 2)) > 0.5 * total:
        return "bending"
    share = np.sum(u * u, axis=0) * (np.abs(normal) < 0.5)
    return f"sway along {'xyz'[int(np.argmax(share))]}"


def _bore_motion(x: np.ndarray, u: np.ndarray, axis: np.ndarray) -> str:
    """Least-squares rigid motion u = t + w x (x - c) of the boss's vertices: 'rocking' (w
    across the axis), 'twist' (w along it), or a 'radial' / 'axial' translation, whichever
    moves the vertices most (rms over them)."""
    c = x.mean(axis=0)
    r = x - c
    A = np.zeros((3 * len(x), 6))
    for k in range(3):
        A[k::3, k] = 1.0
    # w x r = [[0, r_z, -r_y], [-r_z, 0, r_x], [r_y, -r_x, 0]] @ w
    A[0::3, 4], A[0::3, 5] = r[:, 2], -r[:, 1]
    A[1::3, 3], A[1::3, 5] = -r[:, 2], r[:, 0]
    A[2::3, 3], A[2::3, 4] = r[:, 1], -r[:, 0]
    sol = np.linalg.lstsq(A, u.reshape(-1), rcond=None)[0]
    t, w = sol[:3], sol[3:]
    w_ax = (w @ axis) * axis
    rms = lambda v: float(np.sqrt(np.mean(np.sum(np.cross(v, r) ** 2, axis=1))))  # noqa: E731
    parts = {"rocking": rms(w - w_ax), "twist": rms(w_ax),
             "axial": abs(float(t @ axis)), "radial": float(np.linalg.norm(t - (t @ axis) * axis))}
    return max(parts, key=parts.get)


def mode_labels(energy: np.ndarray, names, normals, verts, values, vertex_region
                ) -> tuple[tuple[str, ...], np.ndarray]:
    """(a label per mode, the region its picture should face (m,)) from the kinetic-energy
    shares, the first rule that applies (a bore belongs to the wall its axis points through,
    an inner wall's bore ``<name>/inner<k>`` to inner wall k; a wall's "group" is the wall
    with its bores; only the six outer walls have an opposite):

    1. the largest group and the opposite one hold :data:`PAIR_SHARE`, the smaller at least
       half the larger: "front and back walls bending (44 % of KE)";
    2. one region holds :data:`DOMINANT_SHARE`: "front wall bending (71 % of KE)",
       "bore 2 (input/back) rocking (45 % of KE)";
    3. one group holds it: "front wall with bores 1, 3 bending (52 % of KE)";
    4. else "mixed: A 35 %, B 30 %" (the two largest regions).

    A wall's motion is "bending" when the motion normal to it carries most of its vertices'
    |u|^2, else "sway along" the in-plane axis with more; a boss's by a rigid fit."""
    n_wall = 6
    inner0 = n_wall + sum(1 for n in names[n_wall:] if n.startswith("bore "))   # first inner wall
    owner = []
    for r in range(n_wall, inner0):
        m = re.search(r"/inner(\d+)\)$", names[r])
        owner.append(inner0 + int(m.group(1)) - 1 if m else int(np.argmax(normals[:n_wall] @ normals[r])))
    owner = np.array(owner, dtype=int)
    out, where = [], np.zeros(len(energy), dtype=np.int64)
    for i, e in enumerate(np.asarray(energy, float)):
        if not e.size or not np.isfinite(e).all() or e.sum() <= 0:
            out.append("")
            continue
        e = e / e.sum()
        group = e.copy()
        group[n_wall:inner0] = 0.0                               # the walls with their bores
        np.add.at(group, owner, e[n_wall:inner0])
        order = np.argsort(e)[::-1]
        k, w = int(order[0]), int(np.argmax(group))
        o = w ^ 1 if w < n_wall else w                           # the opposite wall
        motion_of = lambda r: _wall_motion(np.asarray(values[vertex_region == r, :, i], float),  # noqa: E731
                                           normals[r])
        if o != w and group[o] >= 0.5 * group[w] and group[w] + group[o] >= PAIR_SHARE:
            motions = {motion_of(r) for r in (w, o)}
            motion = motions.pop() if len(motions) == 1 else "moving"
            out.append(f"{_PAIRS[w // 2]} {motion} ({100 * (group[w] + group[o]):.0f} % of KE)")
            where[i] = w
        elif e[k] >= DOMINANT_SHARE:
            sel = vertex_region == k
            u = np.asarray(values[sel, :, i], float)
            motion = (_wall_motion(u, normals[k]) if not n_wall <= k < inner0 else
                      _bore_motion(verts[sel], u, normals[k]) if sel.sum() >= 3 else "")
            out.append(f"{names[k]} {motion} ({100 * e[k]:.0f} % of KE)".replace("  ", " "))
            where[i] = k
        elif group[w] >= DOMINANT_SHARE:
            bores = ", ".join(str(b + 1) for b in np.flatnonzero(owner == w))
            with_b = f" with bore{'s' if ',' in bores else ''} {bores}" if bores else ""
            out.append(f"{names[w]}{with_b} {motion_of(w)} ({100 * group[w]:.0f} % of KE)")
            where[i] = w
        else:
            out.append("mixed: " + ", ".join(f"{names[r]} {100 * e[r]:.0f} %" for r in order[:2]))
            where[i] = k
    return tuple(out), where


def boundary_surface(dmesh, ftags, base_tag: int, bore_tags, bores, uh, Vloc, rho: float,
                     comm) -> dict:
    """The fields of the module docstring (on rank 0; empty on the others) plus the meta
    ``region_names``: every exterior facet of ``dmesh`` triangulated and
    oriented outwards, the modes ``Vloc`` (local DOF x m) at its vertices, their energy per
    region."""
    import dolfinx.mesh
    import ufl
    from dolfinx import cpp, fem

    tdim = dmesh.topology.dim
    fdim = tdim - 1
    m = Vloc.shape[1]
    dmesh.topology.create_connectivity(fdim, tdim)
    f2c = dmesh.topology.connectivity(fdim, tdim)
    facets = dolfinx.mesh.exterior_facet_indices(dmesh.topology)
    facets = facets[facets < dmesh.topology.index_map(fdim).size_local]
    n_vert = 3 if dmesh.topology.cell_type == dolfinx.mesh.CellType.tetrahedron else 4
    cmesh = dmesh._mesh if hasattr(dmesh, "_mesh") else dmesh
    nodes = cpp.mesh.entities_to_geometry(cmesh, fdim, facets, False)[:, :n_vert]  # vertices first
    x = dmesh.geometry.x
    cells = np.array([f2c.links(f)[0] for f in facets], dtype=np.int32)
    gdofs = dmesh.geometry.dofmap.array.reshape(-1, dmesh.geometry.dofmap.links(0).size) \
        if len(cells) else np.zeros((0, 1), np.int32)
    tri, src = triangulate_facets(nodes)
    ctr = x[gdofs[cells[src]]].mean(axis=1)
    a, b, c = x[tri[:, 0]], x[tri[:, 1]], x[tri[:, 2]]
    flip = np.einsum("ij,ij->i", np.cross(b - a, c - a), a - ctr) < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    tag_of = dict(zip(ftags.indices.tolist(), ftags.values.tolist()))
    code = {base_tag: 1, **{t: 2 + j for j, t in enumerate(bore_tags)}}
    ftag = np.array([code.get(tag_of.get(int(f), -1), 0) for f in facets], dtype=np.int16)[src]
    # displacement at the used vertices, each evaluated in a cell of one of its facets
    used, first = np.unique(tri.ravel(), return_index=True)
    vcell = cells[src[first // 3]]
    vals = np.zeros((len(used), 3, m))
    for i in range(m):
        uh.vector.array[:] = Vloc[:, i]
        uh.x.scatter_forward()
        if len(used):
            vals[:, :, i] = uh.eval(x[used], vcell)
    # kinetic energy per cell: integral of rho |phi|^2 over it (DG0 test function)
    Q = fem.FunctionSpace(dmesh, ("DG", 0))
    w = ufl.TestFunction(Q)
    form = fem.form(fem.Constant(dmesh, float(rho)) * ufl.inner(uh, uh) * w * ufl.dx)
    n_cells = dmesh.topology.index_map(tdim).size_local
    cell_e = np.zeros((n_cells, m))
    for i in range(m):
        uh.vector.array[:] = Vloc[:, i]
        uh.x.scatter_forward()
        cell_e[:, i] = fem.assemble_vector(form).array[:n_cells]
    centroids = x[gdofs[:n_cells]].mean(axis=1)
    pieces = comm.gather((x[used], np.searchsorted(used, tri), ftag, vals, centroids, cell_e), root=0)
    if comm.rank != 0:
        return {**empty_shape_fields(m), "region_names": ()}
    from .surface_data import merge_vertices

    offs = np.cumsum([0] + [len(p[0]) for p in pieces])
    allx = np.vstack([p[0] for p in pieces])
    alltri = np.vstack([p[1] + o for p, o in zip(pieces, offs)])
    verts, merged = merge_vertices(allx[alltri])
    allv = np.concatenate([p[3] for p in pieces])
    values = np.zeros((len(verts), 3, m))
    values[merged.ravel()] = allv[alltri.ravel()]
    tags = np.concatenate([p[2] for p in pieces])
    planes = wall_planes(verts, merged, tags)
    cell_region = classify_points(np.vstack([p[4] for p in pieces]), planes, bores)
    n_reg = 6 + len(bores) + len(inner_wall_planes(bores))
    energy = np.zeros((m, n_reg))
    np.add.at(energy.T, cell_region, np.vstack([p[5] for p in pieces]))
    names, normals = region_names(bores), region_normals(planes, bores)
    return {"shape_vertices": verts, "shape_triangles": merged.astype(np.int32),
            "shape_facet_tag": tags, "shape_values": values.astype(np.float32),
            "shape_vertex_region": classify_points(verts, planes, bores).astype(np.int16),
            "region_normals": normals, "region_energy": energy, "region_names": names}
