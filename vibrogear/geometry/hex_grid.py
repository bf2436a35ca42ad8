"""Building blocks of structured all-hexahedron meshes (pure numpy, no gmsh, no dolfinx).

- :func:`graded_fill` / :func:`axis_lines`: the grid lines along one axis.  Every *essential* line
  (a wall face, a block edge, a feature edge) is kept exactly; the interval between two of them is
  filled with cells whose size grows linearly with the distance from each end, by ``gradient`` per
  metre, from the size asked for there up to the bulk size: s(x) = min(h, h_a + gradient (x - a),
  h_b + gradient (b - x)), integrated: N = round(int dx / s) cells at equal steps of that integral.
  Consecutive cells then differ by a factor ~exp(gradient) (1.65 for 0.5), and the first cell is
  ~h_a (exp(gradient) - 1) / gradient (1.30 h_a for 0.5).
- :class:`CellCounts`: the cell counts a grid was generated with, recorded and replayed, so that
  another value of a parameter (a wall thickness) gives the same topology with moved nodes.
- :func:`merge_hexes`: hexahedra given by their corner coordinates -> shared nodes and cells in
  dolfinx's tensor-product vertex order (vertex ``i + 2 j + 4 k`` at local (i, j, k)), each with a
  positive Jacobian at its first corner.
- :func:`boundary_quads`: the faces used by one cell only, as quads in tensor order.
- :func:`hex_volumes` / :func:`min_corner_jacobian`: trilinear cell volumes (2x2x2 Gauss, exact for
  a trilinear map) and the smallest corner Jacobian determinant (> 0 for valid cells).
"""
from __future__ import annotations

import numpy as np

__all__ = ["graded_fill", "axis_lines", "CellCounts", "TopologyChange", "merge_hexes", "boundary_quads", "hex_volumes",
           "min_corner_jacobian", "HEX_FACES"]

#: the six faces of a hexahedron in dolfinx's vertex order, each a quad in tensor order
#: (x = 0, x = 1, y = 0, y = 1, z = 0, z = 1)
HEX_FACES = np.array([[0, 2, 4, 6], [1, 3, 5, 7], [0, 1, 4, 5], [2, 3, 6, 7], [0, 1, 2, 3], [4, 5, 6, 7]])
_SAMPLES = 2001


class TopologyChange(ValueError):
    """Replayed cell counts do not fit the grid of the new parameter value (another number of
    intervals or lines); the grid must be generated afresh."""


class CellCounts:
    """Cell counts of a generated grid, in the order the generator asks for them.

    ``CellCounts()`` records: :meth:`take` returns the count it is given and stores it.
    ``CellCounts(recorded.values)`` replays: :meth:`take` returns the stored counts in turn, so the
    generator lays the same number of cells into every interval (the same topology, with the lines
    at the new parameter's positions); :meth:`finish` raises TopologyChange where the generator asked
    for more or fewer counts than were recorded."""

    def __init__(self, values=None):
        self.replay = values is not None
        self.values = [int(v) for v in values] if values is not None else []
        self._next = 0

    def take(self, n: int) -> int:
        if not self.replay:
            self.values.append(int(n))
            return int(n)
        if self._next >= len(self.values):
            raise TopologyChange("the grid has more intervals than the one whose counts are replayed")
        n = self.values[self._next]
        self._next += 1
        return n

    def finish(self) -> None:
        if self.replay and self._next != len(self.values):
            raise TopologyChange(f"the grid has {self._next} intervals, the replayed one {len(self.values)}")


def graded_fill(a: float, b: float, ha: float, hb: float, h: float, gradient: float,
                n: int | None = None) -> np.ndarray:
    """Interior grid points of [a, b] (a < b): the size function ha + gradient x distance from a
    (hb from b), capped at ``h``, integrated (module docstring); ``n``: that many cells instead
    (the points at equal steps of the same integral)."""
    length = b - a
    g = gradient
    x = np.linspace(a, b, _SAMPLES)
    s = np.minimum(h, np.minimum(ha + g * (x - a), hb + g * (b - x)))
    s = np.maximum(s, 1e-12)
    inv = 1.0 / s
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (inv[1:] + inv[:-1]) * np.diff(x))])
    n = max(1, int(round(cum[-1]))) if n is None else int(n)
    if n == 1 or length <= 0:
        return np.zeros(0)
    return np.interp(np.arange(1, n) * cum[-1] / n, cum, x)


def _fill_count(a: float, b: float, ha: float, hb: float, h: float, gradient: float) -> int:
    """The number of cells :func:`graded_fill` lays into [a, b]."""
    return len(graded_fill(a, b, ha, hb, h, gradient)) + 1


def axis_lines(essential: dict[float, float], h: float, gradient: float,
               counts: CellCounts | None = None) -> np.ndarray:
    """Sorted grid lines: the keys of ``essential`` (line -> cell size wanted next to it; lines
    closer than 1e-9 merged, the smaller size kept) and the graded fill between neighbours;
    ``counts`` records (or replays) the number of cells of each interval."""
    keys = sorted(essential)
    lines, sizes = [], []
    for v in keys:
        if lines and v - lines[-1] < 1e-9:
            sizes[-1] = min(sizes[-1], essential[v])
            continue
        lines.append(v)
        sizes.append(essential[v])
    out = [lines[0]]
    for (a, ha), (b, hb) in zip(zip(lines[:-1], sizes[:-1]), zip(lines[1:], sizes[1:])):
        n = None if counts is None else counts.take(_fill_count(a, b, ha, hb, h, gradient))
        out.extend(graded_fill(a, b, ha, hb, h, gradient, n))
        out.append(b)
    return np.array(out)


def merge_hexes(corners: np.ndarray, tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """(nodes (N, 3), cells (n, 8)) from the corner coordinates (n, 8, 3) in tensor order; corners
    closer than ``tol`` (m) become one node; cells with a negative Jacobian are mirrored."""
    pts = corners.reshape(-1, 3)
    key = np.round(pts / tol).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    nodes = pts[first]
    cells = inv.reshape(-1, 8)
    X = nodes[cells]
    det = np.einsum("ij,ij->i", np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]), X[:, 4] - X[:, 0])
    flip = det < 0
    cells[flip] = cells[flip][:, [0, 2, 1, 3, 4, 6, 5, 7]]
    return nodes, cells


def boundary_quads(cells: np.ndarray) -> np.ndarray:
    """Faces (k, 4) of ``cells`` (n, 8) that belong to one cell only, vertices in tensor order."""
    faces = cells[:, HEX_FACES].reshape(-1, 4)
    key = np.sort(faces, axis=1)
    _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return faces[count[inv] == 1]


def _trilinear_grads(a: float, b: float, c: float) -> np.ndarray:
    """d N_v / d(a, b, c) of the 8 trilinear shape functions at (a, b, c) in [0, 1]^3: (3, 8)."""
    out = np.zeros((3, 8))
    for v in range(8):
        i, j, k = v & 1, (v >> 1) & 1, (v >> 2) & 1
        fa, fb, fc = (a if i else 1 - a), (b if j else 1 - b), (c if k else 1 - c)
        da, db, dc = (1 if i else -1), (1 if j else -1), (1 if k else -1)
        out[:, v] = (da * fb * fc, fa * db * fc, fa * fb * dc)
    return out


def _jacobians(nodes: np.ndarray, cells: np.ndarray, a: float, b: float, c: float) -> np.ndarray:
    G = _trilinear_grads(a, b, c)
    J = np.einsum("dv,nvx->ndx", G, nodes[cells])
    return np.linalg.det(J)


def hex_volumes(nodes: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Volume of each trilinear hexahedron (2x2x2 Gauss: exact, det J is a polynomial of degree
    <= 2 in each reference coordinate)."""
    g = (0.5 - 0.5 / np.sqrt(3.0), 0.5 + 0.5 / np.sqrt(3.0))
    return sum(_jacobians(nodes, cells, a, b, c) for a in g for b in g for c in g) / 8.0


def min_corner_jacobian(nodes: np.ndarray, cells: np.ndarray) -> float:
    """The smallest Jacobian determinant over all cells' corners (m^3 per unit reference volume)."""
    return float(min(_jacobians(nodes, cells, a, b, c).min() for a in (0, 1) for b in (0, 1)
                     for c in (0, 1)))
