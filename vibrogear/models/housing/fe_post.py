"""Housing FE model, stage 3 of 3: mode values at the bore points, on the outer skin, a
preview cloud and XDMF mode shapes.  dolfinx is imported inside functions (see :mod:`.fe`).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

_PREVIEW_POINTS = 4000
#: modes evaluated together by :func:`_eval_modes`
_EVAL_CHUNK = 50


def locate(dmesh, points, comm):
    """For each point, (local cell or -1, owning rank); fallback to the closest cell."""
    from mpi4py import MPI
    import dolfinx.geometry as geo

    tdim = dmesh.topology.dim
    tree = geo.BoundingBoxTree(dmesh, tdim)
    cand = geo.compute_collisions(tree, points)
    coll = geo.compute_colliding_cells(dmesh, cand, points)
    n_local_cells = dmesh.topology.index_map(tdim).size_local
    cells = np.full(len(points), -1, dtype=np.int32)
    for k in range(len(points)):
        c = [c for c in coll.links(k) if c < n_local_cells]
        if len(c):
            cells[k] = c[0]
    found = np.where(cells >= 0, comm.rank, comm.size).astype(np.int32)
    owner = np.empty_like(found)
    comm.Allreduce(found, owner, op=MPI.MIN)
    missing = np.flatnonzero(owner == comm.size)
    n_fallback = len(missing)
    if n_fallback:
        entities = np.arange(n_local_cells, dtype=np.int32)
        mid = geo.create_midpoint_tree(dmesh, tdim, entities)
        closest = geo.compute_closest_entity(tree, mid, dmesh, points[missing])
        x = dmesh.geometry.x
        dist = np.full(len(missing), np.inf)
        for j, c in enumerate(closest):
            if c >= 0:
                verts = dmesh.geometry.dofmap.links(c)
                dist[j] = np.min(np.linalg.norm(x[verts] - points[missing[j]], axis=1))
        best = np.empty_like(dist)
        comm.Allreduce(dist, best, op=MPI.MIN)
        for j, k in enumerate(missing):
            mine = dist[j] == best[j] and np.isfinite(dist[j])
            cand_rank = comm.rank if mine else comm.size
            owner[k] = comm.allreduce(cand_rank, op=MPI.MIN)
            if owner[k] == comm.rank:
                cells[k] = closest[j]
    return cells, owner, n_fallback


def _eval_modes(uh, Vloc, pts, cells) -> np.ndarray:
    """Every mode's displacement (npts, 3, m) at ``pts`` in the local ``cells``: the modes are
    packed :data:`_EVAL_CHUNK` at a time into one function of 3 x chunk components, so that each
    point is located in its cell (for hexahedra: a Newton pull-back) once per chunk, not per mode."""
    from dolfinx import fem

    m = Vloc.shape[1]
    out = np.zeros((len(pts), 3, m))
    if not len(pts) or not m:
        return out
    V = uh.function_space
    n_own = V.dofmap.index_map.size_local
    for i0 in range(0, m, _EVAL_CHUNK):
        k = min(_EVAL_CHUNK, m - i0)
        W = fem.VectorFunctionSpace(V.mesh, ("Lagrange", V.ufl_element().degree()), dim=3 * k)
        w = fem.Function(W)
        w.x.array[:n_own * 3 * k] = Vloc[:, i0:i0 + k].reshape(n_own, 3, k).transpose(0, 2, 1).ravel()
        w.x.scatter_forward()
        out[:, :, i0:i0 + k] = w.eval(pts, cells).reshape(len(pts), k, 3).transpose(0, 2, 1)
    return out


def bore_coupling_values(dmesh, uh, Vloc, bores, comm):
    from mpi4py import MPI

    nb, m = len(bores), Vloc.shape[1]
    P = max((b.n_points for b in bores), default=0)
    pts = np.full((nb, P, 3), np.nan)
    vals = np.full((nb, P, 3, m), np.nan)
    cvals = np.zeros((nb, 3, m))
    if nb == 0:
        return pts, vals, cvals, 0
    flat = np.vstack([b.points() for b in bores])
    cells, owner, n_fallback = locate(dmesh, flat, comm)
    mine = np.flatnonzero(owner == comm.rank)
    local = np.zeros((len(flat), 3, m))
    if len(mine):
        local[mine] = _eval_modes(uh, Vloc, flat[mine], cells[mine])
    allv = np.zeros_like(local)
    comm.Allreduce(local, allv, op=MPI.SUM)
    k = 0
    for j, b in enumerate(bores):
        n = b.n_points
        pts[j, :n] = flat[k:k + n]
        vals[j, :n] = allv[k:k + n]
        cvals[j] = allv[k:k + n].mean(axis=0)
        k += n
    return pts, vals, cvals, n_fallback


def surface_values(dmesh, ftags, skip_tags, uh, Vloc, comm):
    """Exterior facets not tagged ``skip_tags`` (base, bores), gathered on rank 0: their vertex
    coordinates (nf, 3, 3) (a hexahedral mesh's quads split into two triangles each), ordered so
    that (b - a) x (c - a) points out of the solid, and each
    mode's displacement along that normal at the three edge midpoints (nf, 3, m)."""
    import dolfinx.mesh
    from dolfinx import cpp

    tdim = dmesh.topology.dim
    fdim = tdim - 1
    dmesh.topology.create_connectivity(fdim, tdim)
    f2c = dmesh.topology.connectivity(fdim, tdim)
    facets = dolfinx.mesh.exterior_facet_indices(dmesh.topology)
    facets = facets[facets < dmesh.topology.index_map(fdim).size_local]
    facets = np.setdiff1d(facets, ftags.indices[np.isin(ftags.values, skip_tags)])
    x = dmesh.geometry.x
    cmesh = dmesh._mesh if hasattr(dmesh, "_mesh") else dmesh
    poly = x[cpp.mesh.entities_to_geometry(cmesh, fdim, facets, False)]       # (nf, 3 or 4, 3)
    cells = np.array([f2c.links(f)[0] for f in facets], dtype=np.int32)
    if poly.shape[1] == 4:        # hexahedra: each quad (tensor order, 3 opposite 0) as 2 triangles
        poly = np.concatenate([poly[:, [0, 1, 3]], poly[:, [0, 3, 2]]])
        cells = np.concatenate([cells, cells])
    tri = poly
    centroid = np.array([x[dmesh.geometry.dofmap.links(c)].mean(axis=0) for c in cells])
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    flip = np.einsum("ij,ij->i", normal, tri[:, 0] - centroid.reshape(-1, 3)) < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    normal[flip] *= -1.0
    unit = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    mids = 0.5 * (tri + tri[:, [1, 2, 0]])                                     # edge midpoints
    pts, where = mids.reshape(-1, 3), np.repeat(cells, 3)
    # an edge midpoint is shared by the two facets at that edge: evaluate each point once (the
    # field is continuous, so the cell it is evaluated in does not matter)
    scale = max(float(np.ptp(pts, axis=0).max()), 1e-300) if len(pts) else 1.0
    _, first, back = np.unique(np.round(pts / (1e-9 * scale)).astype(np.int64), axis=0,
                               return_index=True, return_inverse=True)
    u = _eval_modes(uh, Vloc, pts[first], where[first])[back.ravel()].reshape(len(tri), 3, 3, -1)
    vals = np.einsum("fqcm,fc->fqm", u, unit)
    tris, allv = comm.gather(tri, root=0), comm.gather(vals, root=0)
    if comm.rank != 0:
        return np.zeros((0, 3, 3)), np.zeros((0, 3, Vloc.shape[1]))
    return np.concatenate(tris), np.concatenate(allv)


def mode_previews(dmesh, V, uh, Vloc, comm):
    """Boundary dof coordinates and the first modes there, subsampled, for plots."""
    import dolfinx.mesh
    from dolfinx import fem

    fdim = dmesh.topology.dim - 1
    facets = dolfinx.mesh.exterior_facet_indices(dmesh.topology)
    blocks = fem.locate_dofs_topological(V, fdim, facets)
    blocks = blocks[blocks < V.dofmap.index_map.size_local]
    xyz = V.tabulate_dof_coordinates()[blocks]
    vals = np.stack([Vloc[:, i].reshape(-1, 3)[blocks] for i in range(Vloc.shape[1])], axis=-1)
    all_xyz = comm.gather(xyz, root=0)
    all_vals = comm.gather(vals, root=0)
    if comm.rank != 0:
        return np.zeros((0, 3)), np.zeros((0, 3, Vloc.shape[1]))
    xyz, vals = np.vstack(all_xyz), np.concatenate(all_vals, axis=0)
    order = np.lexsort(np.round(xyz, 9).T)
    step = max(1, len(order) // _PREVIEW_POINTS)
    sel = order[::step]
    return xyz[sel], vals[sel]


def write_shapes(dmesh, uh, Vloc, path: Path, comm) -> Path:
    from dolfinx import fem
    from dolfinx.io import XDMFFile

    V1 = fem.VectorFunctionSpace(dmesh, ("Lagrange", 1))
    u1 = fem.Function(V1)
    u1.name = "mode_shape"
    with XDMFFile(comm, str(path), "w") as f:
        f.write_mesh(dmesh)
        for i in range(Vloc.shape[1]):
            uh.vector.array[:] = Vloc[:, i]
            uh.x.scatter_forward()
            u1.interpolate(uh)
            f.write_function(u1, t=float(i + 1))
    return path
