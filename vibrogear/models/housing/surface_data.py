"""The housing's outer (radiating) surface and its master modes' normal displacement there.

No dolfinx here: :func:`.housing._surface_values` hands over the exterior facets of the
solid that are neither the supported base nor a bore (vertex coordinates ordered so that
the normal (b - a) x (c - a) points out of the solid) and each mode's displacement along
that normal at the facets' three edge midpoints.  :func:`outer_surface` keeps the
connected pieces of that surface that reach the bounding box of the solid (the outer
skin; a closed housing's inner cavity walls do not reach it) and stores, per facet:

- ``surface_vertices``   (nv, 3)     vertex coordinates, m (merged over facets)
- ``surface_triangles``  (nf, 3)     vertex indices, outward orientation
- ``surface_centers``    (nf, 3)     facet centres, m
- ``surface_areas``      (nf,)       facet areas, m^2
- ``surface_weights``    (nf, 3)     quadrature weights A/3 at the edge midpoints (the
                                     midpoint rule: exact for quadratics on a flat triangle)
- ``surface_values``     (nf, 3, m)  mass-normalised normal displacement phi_n,i there

so that an integral over the outer surface is sum(weights * f(midpoints)).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

__all__ = ["HousingSurface", "outer_surface", "SURFACE_FIELDS", "empty_surface_fields"]

SURFACE_FIELDS = ("surface_vertices", "surface_triangles", "surface_centers", "surface_areas",
                  "surface_weights", "surface_values")


def empty_surface_fields(m: int = 0) -> dict:
    """The surface fields of a housing without surface data (e.g. modes read from another
    program)."""
    return {"surface_vertices": np.zeros((0, 3)), "surface_triangles": np.zeros((0, 3), int),
            "surface_centers": np.zeros((0, 3)), "surface_areas": np.zeros(0),
            "surface_weights": np.zeros((0, 3)), "surface_values": np.zeros((0, 3, m))}


@dataclass(frozen=True, eq=False)
class HousingSurface:
    vertices: np.ndarray
    triangles: np.ndarray
    centers: np.ndarray
    areas: np.ndarray
    weights: np.ndarray
    values: np.ndarray

    def as_fields(self) -> dict:
        return dict(zip(SURFACE_FIELDS, (self.vertices, self.triangles, self.centers, self.areas,
                                         self.weights, self.values)))


def merge_vertices(tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    pts = tri.reshape(-1, 3)
    scale = max(float(np.ptp(pts, axis=0).max()), 1e-300) if len(pts) else 1.0
    keys = np.round(pts / (1e-9 * scale)).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    return pts[first], inverse.reshape(-1, 3)


def outer_surface(tri, values, *, rel_tol: float = 1e-6) -> HousingSurface:
    """The outer skin of the exterior facets ``tri`` (nf, 3, 3) with the normal values
    ``values`` (nf, 3, m) at their edge midpoints: the connected pieces (facets sharing a
    vertex) with a vertex on the bounding box of all of them."""
    tri = np.asarray(tri, dtype=float).reshape(-1, 3, 3)
    values = np.asarray(values, dtype=float)
    values = values.reshape(len(tri), 3, -1 if values.size else 0)
    verts, faces = merge_vertices(tri)
    nf = len(faces)
    if nf:
        inc = sp.csr_matrix((np.ones(3 * nf), (np.repeat(np.arange(nf), 3), faces.ravel())),
                            shape=(nf, len(verts)))
        _, label = connected_components(inc @ inc.T, directed=False)
        lo, hi = verts.min(axis=0), verts.max(axis=0)
        tol = rel_tol * float(np.linalg.norm(hi - lo))
        on_box = np.any((np.abs(verts - lo) <= tol) | (np.abs(verts - hi) <= tol), axis=1)
        outer = np.unique(label[np.any(on_box[faces], axis=1)])
        keep = np.isin(label, outer)
    else:
        keep = np.zeros(0, dtype=bool)
    tri, values, faces = tri[keep], values[keep], faces[keep]
    used, faces = np.unique(faces, return_inverse=True)
    faces = faces.reshape(-1, 3)
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    return HousingSurface(vertices=verts[used], triangles=faces.astype(np.int64),
                          centers=tri.mean(axis=1), areas=area,
                          weights=np.repeat(area[:, None] / 3.0, 3, axis=1), values=values)
