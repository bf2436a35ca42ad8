"""All-hexahedron mesh of the parametric housing (``[housing.mesh] element = "hex"``).

A structured grid, pure numpy (no gmsh): the box's walls, the base plate or feet and the ribs are
cells of one tensor grid (lines from :func:`.hex_grid.axis_lines`); each bore sits in a rectangular
*block* of the front and back walls whose cells are rings (an O-grid):

- one element through each wall (the wall's two faces are grid lines, nothing between them);
- in the wall planes the cells are ~``edge`` next to the wall junctions (the inner wall faces) and
  grow with the distance from them (``gradient``, :mod:`.hex_grid`) up to ``size``; the block
  edges carry cells of ``bore`` size;
- a block's boundary nodes (every grid line crossing it) are mapped radially onto the boss circle
  (``boss_radius``) and the bore circle; rings of cells join square, boss circle and bore circle;
  the boss is the rings inside the boss circle extruded outwards by ``boss_length``; a rib is the
  column of cells ``rib_thickness`` wide under the block plus the ring cells between its two edge
  nodes (mapped vertically onto the boss circle so that the rib keeps its width);
- cells are straight-sided (trilinear geometry): bore and boss are polygons with one side per
  ring cell (about 2 pi r / bore_size sides; the volume error is ~(2 pi / n)^2 / 6 of their areas).

Blocks of bores at overlapping heights share one z-range (so their edges carry the same lines);
blocks that would overlap are made to abut half-way between the bosses; blocks that cannot be laid
out (a boss reaching the junction of two walls, bosses touching, ribs under a stacked bore) are
refused with a ConfigError naming the bore.  The mesh file is ``.npz``: ``x`` (N, 3), ``cells``
(n, 8) in dolfinx's hexahedron vertex order, ``facets`` (k, 4) with their physical tags ``values``
(BASE_TAG: the supported bottom, BORE_TAG0 + k: the bores in :func:`.housing.bore_layout` order).
"""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from ..config.base import ConfigError
from ..config.model.housing import HousingConfig
from ..config.model.housing_mesh import HexBlock, hex_blocks
from .hex_grid import CellCounts, TopologyChange, axis_lines, boundary_quads, merge_hexes
from .housing import BASE_TAG, BORE_TAG0, VOLUME_TAG, HousingMesh, bore_layout

__all__ = ["build_hex_housing_mesh", "build_hex_beam_mesh", "hex_housing_arrays", "moved_hex_nodes", "read_hex_mesh",
           "HEX_CELL_TYPE"]

HEX_CELL_TYPE = "hexahedron"


def _take(counts: CellCounts | None, n: int) -> int:
    return n if counts is None else counts.take(n)


def _block_lines(a: float, b: float, h: float, centre: float | None = None,
                 rib: float = 0.0, counts: CellCounts | None = None) -> np.ndarray:
    """Uniform lines over [a, b] with spacing <= h; with a rib, the lines centre +- rib / 2 and
    no line between them (``counts``: the numbers of cells recorded or replayed)."""
    if not rib:
        return np.linspace(a, b, _take(counts, max(2, math.ceil((b - a) / h - 1e-9))) + 1)
    lo, hi = centre - 0.5 * rib, centre + 0.5 * rib
    left = np.linspace(a, lo, _take(counts, max(1, math.ceil((lo - a) / h - 1e-9))) + 1)
    right = np.linspace(hi, b, _take(counts, max(1, math.ceil((b - hi) / h - 1e-9))) + 1)
    return np.concatenate([left, right])


def _grid(cfg: HousingConfig, blocks: list[HexBlock], counts: CellCounts | None = None):
    L, W, H, t = cfg.length, cfg.width, cfg.height, cfg.wall_thickness
    rule = cfg.hex_mesh
    # the outer faces and the parts outside the box (overhang, base plate, bosses) are sized from
    # the junction size ``edge`` (by default the wall thickness), so that a sweep that fixes the
    # mesh sizes (the reusing housing sweep) keeps one grid while the wall changes
    e, hb = rule.edge, rule.bore
    out_size = 2.5 * e
    ex = {0.0: e, t: e, L - t: e, L: e}
    ey = {0.0: e, t: e, W - t: e, W: e}
    ez = {0.0: e, t: e, H - t: e, H: e}
    for blk in blocks:
        for v in _block_lines(blk.x0, blk.x1, hb, blk.bx, blk.rib, counts):
            ex[float(v)] = hb
        for v in _block_lines(blk.z0, blk.z1, hb, counts=counts):
            ez[float(v)] = hb
        if blk.lb > 0:
            ey[-blk.lb] = ey[W + blk.lb] = out_size
    if cfg.base == "plate":
        o = cfg.base_overhang
        if o > 0:
            ex[-o] = ex[L + o] = ey[-o] = ey[W + o] = out_size
        ez[-cfg.base_thickness] = out_size
    elif cfg.base == "feet":
        f = cfg.foot_size
        ex[f] = ex[L - f] = e
        ey[f] = ey[W - f] = e
        ez[-cfg.base_thickness] = out_size
    return tuple(axis_lines(d, rule.size, rule.gradient, counts) for d in (ex, ey, ez))


def _tensor_cells(cfg, blocks, xs, ys, zs) -> np.ndarray:
    """Corner coordinates (n, 8, 3) of the tensor-grid cells of the housing (all but the blocks)."""
    L, W, H, t = cfg.length, cfg.width, cfg.height, cfg.wall_thickness
    i, j, k = (a.ravel() for a in np.meshgrid(np.arange(len(xs) - 1), np.arange(len(ys) - 1),
                                              np.arange(len(zs) - 1), indexing="ij"))
    cx, cy, cz = 0.5 * (xs[i] + xs[i + 1]), 0.5 * (ys[j] + ys[j + 1]), 0.5 * (zs[k] + zs[k + 1])
    box = (cx > 0) & (cx < L) & (cy > 0) & (cy < W) & (cz > 0) & (cz < H)
    cavity = (cx > t) & (cx < L - t) & (cy > t) & (cy < W - t) & (cz > t) & (cz < H - t)
    keep = box & ~cavity
    below = (cz < 0) & (cz > -cfg.base_thickness)
    if cfg.base == "plate":
        o = cfg.base_overhang
        keep |= below & (cx > -o) & (cx < L + o) & (cy > -o) & (cy < W + o)
    elif cfg.base == "feet":
        f = cfg.foot_size
        keep |= below & (cx > 0) & (cx < L) & (cy > 0) & (cy < W) & ((cx < f) | (cx > L - f)) & \
            ((cy < f) | (cy > W - f))
    walls = (cy < t) | (cy > W - t)
    for blk in blocks:
        keep &= ~(walls & (cx > blk.x0) & (cx < blk.x1) & (cz > blk.z0) & (cz < blk.z1))
        if blk.rib:
            keep |= ((np.abs(cx - blk.bx) < 0.5 * blk.rib) & (cz > 0) & (cz < blk.z0)
                     & (((cy > -blk.lb) & (cy < 0)) | ((cy > W) & (cy < W + blk.lb))))
    i, j, k = i[keep], j[keep], k[keep]
    return np.stack([np.c_[xs[i + di], ys[j + dj], zs[k + dk]]
                     for dk in (0, 1) for dj in (0, 1) for di in (0, 1)], axis=1)


def _ring_cells(cfg, blk: HexBlock, xs, ys, zs, rule, counts: CellCounts | None = None) -> list[np.ndarray]:
    """Corner coordinates of the O-grid cells of one block in both walls and its two bosses."""
    W, t = cfg.width, cfg.wall_thickness
    bxl = xs[(xs >= blk.x0 - 1e-12) & (xs <= blk.x1 + 1e-12)]
    bzl = zs[(zs >= blk.z0 - 1e-12) & (zs <= blk.z1 + 1e-12)]
    loop = ([(x, bzl[0]) for x in bxl[:-1]] + [(bxl[-1], z) for z in bzl[:-1]]
            + [(x, bzl[-1]) for x in bxl[:0:-1]] + [(bxl[0], z) for z in bzl[:0:-1]])
    P = np.array(loop)                                      # counter-clockwise in (x, z)
    d = P - (blk.bx, blk.bz)
    unit = d / np.linalg.norm(d, axis=1, keepdims=True)
    c = np.array([blk.bx, blk.bz])
    CR, Cr = c + blk.R * unit, c + blk.r * unit
    rib_nodes = np.zeros(len(P), bool)
    if blk.rib:                                             # the rib's edges keep their x on the boss
        rib_nodes = (np.abs(np.abs(P[:, 0] - blk.bx) - 0.5 * blk.rib) < 1e-9) & (np.abs(P[:, 1] - blk.z0) < 1e-12)
        dx = P[rib_nodes, 0] - blk.bx
        CR[rib_nodes] = np.c_[P[rib_nodes, 0], blk.bz - np.sqrt(blk.R ** 2 - dx ** 2)]
    n_in = _take(counts, max(1, math.ceil((blk.R - blk.r) / (2.0 * rule.edge) - 1e-9)))  # rings bore -> boss
    rings = [Cr + (q / n_in) * (CR - Cr) for q in range(n_in)] + [CR, P]
    m = len(P)
    seg = np.arange(m)
    nxt = (seg + 1) % m
    rib_seg = np.flatnonzero(rib_nodes & rib_nodes[nxt])

    def extrude(q_range, segs, ylines):
        out = []
        for q in q_range:
            quad = np.stack([rings[q][segs], rings[q][nxt[segs]], rings[q + 1][segs], rings[q + 1][nxt[segs]]], 1)
            for y0, y1 in zip(ylines[:-1], ylines[1:]):
                corners = [np.c_[quad[:, v, 0], np.full(len(segs), y), quad[:, v, 1]] for y in (y0, y1)
                           for v in range(4)]
                out.append(np.stack(corners, axis=1))
        return out

    cells = []
    for wall in (ys[(ys >= -1e-12) & (ys <= t + 1e-12)], ys[(ys >= W - t - 1e-12) & (ys <= W + 1e-12)]):
        cells += extrude(range(len(rings) - 1), seg, wall)
    if blk.lb > 0:
        for boss in (ys[(ys >= -blk.lb - 1e-12) & (ys <= 1e-12)], ys[(ys >= W - 1e-12) & (ys <= W + blk.lb + 1e-12)]):
            cells += extrude(range(n_in), seg, boss)
            if len(rib_seg):
                cells += extrude([n_in], rib_seg, boss)
    return cells


def hex_housing_arrays(cfg: HousingConfig, counts: CellCounts | None = None):
    """(x (N, 3), cells (n, 8), facets (k, 4), facet tags (k,)) of the parametric housing.

    ``counts``: a recording :class:`.hex_grid.CellCounts` stores the number of cells of every
    interval and ring; a replaying one lays those numbers instead of the ones the mesh rule asks for
    (TopologyChange where the intervals differ), so that another parameter value (a wall thickness)
    gives the mesh of the recorded one with moved nodes (the housing sweep's reuse, see
    :func:`moved_hex_nodes`)."""
    blocks = hex_blocks(cfg)
    xs, ys, zs = _grid(cfg, blocks, counts)
    parts = [_tensor_cells(cfg, blocks, xs, ys, zs)]
    for blk in blocks:
        parts += _ring_cells(cfg, blk, xs, ys, zs, cfg.hex_mesh, counts)
    if counts is not None:
        counts.finish()
    x, cells = merge_hexes(np.concatenate(parts, axis=0))
    faces = boundary_quads(cells)
    fx = x[faces]                                           # (k, 4, 3)
    zb = -cfg.base_thickness if cfg.base != "none" else 0.0
    tags = [(BASE_TAG, np.all(np.abs(fx[..., 2] - zb) < 1e-9, axis=1))]
    for k, g in enumerate(bore_layout(cfg)):
        rad = np.hypot(fx[..., 0] - g.center[0], fx[..., 2] - g.center[2])
        y = fx[..., 1]
        on = (np.all(np.abs(rad - g.radius) < 1e-9 + 1e-6 * g.radius, axis=1)
              & np.all((y >= g.y_range[0] - 1e-9) & (y <= g.y_range[1] + 1e-9), axis=1))
        if not on.any():
            raise ConfigError("housing.bores", f"the hex mesh has no faces on bore {g.name}")
        tags.append((BORE_TAG0 + k, on))
    facets = np.concatenate([faces[m] for _, m in tags])
    values = np.concatenate([np.full(int(m.sum()), tag, np.int32) for tag, m in tags])
    return x, cells, facets, values


def moved_hex_nodes(cfg: HousingConfig, counts: CellCounts, cells: np.ndarray, facets: np.ndarray,
                    values: np.ndarray) -> np.ndarray:
    """Node coordinates (N, 3) of housing ``cfg`` on the mesh ``cells`` / ``facets`` (tags ``values``)
    generated with the recorded ``counts``: the grid of ``cfg`` with those cell counts, its nodes
    renumbered to the given mesh's numbering.  Raises :class:`.hex_grid.TopologyChange` where the
    new grid's cells, facets or tags are not those of the given mesh (then mesh afresh)."""
    x2, c2, f2, v2 = hex_housing_arrays(cfg, CellCounts(counts.values))
    if c2.shape != cells.shape or len(x2) != int(cells.max()) + 1 or f2.shape != facets.shape:
        raise TopologyChange(f"{len(c2)} cells and {len(x2)} nodes against {len(cells)} and {int(cells.max()) + 1}")
    # the cells come out in the same order (the same grid indices); their node numbers may differ
    # where moved nodes sort differently: perm[old node] = new node, one-to-one and consistent
    perm = np.full(len(x2), -1, np.int64)
    perm[cells.ravel()] = c2.ravel()
    if np.any(perm < 0) or np.any(perm[cells] != c2) or len(np.unique(perm)) != len(perm):
        raise TopologyChange("the cells of the new grid do not map one-to-one onto the given mesh")
    key = lambda f, v: np.lexsort(np.c_[np.sort(f, axis=1), v].T)   # noqa: E731
    a = np.c_[np.sort(perm[facets], axis=1), values][key(perm[facets], values)]
    b = np.c_[np.sort(f2, axis=1), v2][key(f2, v2)]
    if not np.array_equal(a, b):
        raise TopologyChange("the new grid's base or bore facets differ from the given mesh's")
    return x2[perm]


def build_hex_housing_mesh(cfg: HousingConfig, path: str | Path) -> HousingMesh:
    """Build the hex mesh and write it to ``path`` (its suffix becomes ``.npz``)."""
    t0 = time.perf_counter()
    path = Path(path).with_suffix(".npz")
    x, cells, facets, values = hex_housing_arrays(cfg)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as fh:
        np.savez(fh, x=x, cells=cells, facets=facets, values=values)
    n_bores = 2 * len(cfg.bores)
    return HousingMesh(path, BASE_TAG, tuple(BORE_TAG0 + k for k in range(n_bores)), VOLUME_TAG,
                       len(x), len(cells), time.perf_counter() - t0, HEX_CELL_TYPE)


def read_hex_mesh(path: str | Path):
    """(x, cells, facets, facet tags) of a mesh written by :func:`build_hex_housing_mesh`."""
    with np.load(path) as z:
        return z["x"], z["cells"].astype(np.int64), z["facets"].astype(np.int64), z["values"].astype(np.int32)


def build_hex_beam_mesh(length: float, width: float, height: float, path: str | Path, *,
                        cells: tuple[int, int, int]) -> HousingMesh:
    """A solid cantilever along x of ``cells`` = (nx, ny, nz) equal hexahedra, clamped at x = 0
    (group BASE_TAG); no bores (the hex counterpart of :func:`.housing.build_beam_mesh`)."""
    t0 = time.perf_counter()
    xs, ys, zs = (np.linspace(0.0, a, n + 1) for a, n in zip((length, width, height), cells))
    i, j, k = (a.ravel() for a in np.meshgrid(*(np.arange(n) for n in cells), indexing="ij"))
    corners = np.stack([np.c_[xs[i + di], ys[j + dj], zs[k + dk]]
                        for dk in (0, 1) for dj in (0, 1) for di in (0, 1)], axis=1)
    x, hexes = merge_hexes(corners)
    faces = boundary_quads(hexes)
    clamp = faces[np.all(np.abs(x[faces][..., 0]) < 1e-12, axis=1)]
    path = Path(path).with_suffix(".npz")
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as fh:
        np.savez(fh, x=x, cells=hexes, facets=clamp, values=np.full(len(clamp), BASE_TAG, np.int32))
    return HousingMesh(path, BASE_TAG, (), VOLUME_TAG, len(x), len(hexes), time.perf_counter() - t0,
                       HEX_CELL_TYPE)
