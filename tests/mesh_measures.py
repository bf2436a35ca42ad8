"""Volumes and areas of a mesh's simplices, written out here (numpy only) so that the
housing-geometry tests measure meshes independently of the project's own code."""
from __future__ import annotations

import numpy as np

__all__ = ["tet_volume", "tri_area"]


def tet_volume(x, tets) -> float:
    """Total volume of the tetrahedra ``tets`` (n, 4) over the nodes ``x`` (N, 3)."""
    a, b, c, d = (x[tets[:, i]] for i in range(4))
    return np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))).sum() / 6.0


def tri_area(x, tris) -> float:
    """Total area of the triangles ``tris`` (n, 3) over the nodes ``x`` (N, 3)."""
    a, b, c = (x[tris[:, i]] for i in range(3))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
