"""``[housing.mesh]``: how the housing is discretised, and the default size rules.

Two element families:

- ``element = "tet"`` (every source): Lagrange tetrahedra of ``degree`` from gmsh, sizes ``size``
  (default by degree, :data:`DEFAULT_SIZE_PER_WALL`), ``bore_size`` (default size / 2) and the
  optional junction grading ``edge_size`` / ``edge_distance``.
- ``element = "hex"`` (parametric housings only): Lagrange hexahedra of ``degree`` (Q2 or Q3) on a
  structured grid, one element through each wall (:mod:`vibrogear.geometry.housing_hex`).  The
  sizes mean, in the wall planes: ``size`` the bulk cell size, ``edge_size`` the size of the cell
  function at the wall junctions (growing linearly with the distance from them, by
  :data:`HEX_SIZE_GRADIENT` per metre, up to ``size``), ``bore_size`` the
  spacing of the block of cells around each bore (its rings).  Defaults :func:`hex_rule`
  (docs/housing.md, "Hexahedra").
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..base import ConfigError, spec

__all__ = ["HousingMeshConfig", "ELEMENTS", "MAX_SIZE_PER_WALL", "DEFAULT_SIZE_PER_WALL",
           "HEX_SIZE_GRADIENT", "HEX_DEFAULT_PER_WALL", "HexMeshRule", "hex_rule", "HexBlock", "hex_blocks"]

ELEMENTS = ("tet", "hex")
#: largest global mesh size, in wall thicknesses, that still puts an element across the wall
MAX_SIZE_PER_WALL = 2.0
#: the default element size per wall thickness by Lagrange degree (issue 23 study of
#: configs/housing.toml, 100 modes against a p-refinement reference: P3 at 2 x wall is within
#: 0.7 % for every mode, 34 s under mpirun -n 2; P2 at 1.3 x wall 2.1 %, no P2 mesh within 1 %)
DEFAULT_SIZE_PER_WALL = {1: 1.3, 2: 1.3, 3: 2.0}
#: hexahedra: growth of the in-plane cell size per metre of distance from a junction or a bore block
#: (consecutive cells ~1.65 x apart; :mod:`vibrogear.geometry.hex_grid`)
HEX_SIZE_GRADIENT = 0.5
#: hexahedra: default (size, edge_size, bore_size) in wall thicknesses (docs/housing.md, "Hexahedra")
HEX_DEFAULT_PER_WALL = (6.0, 1.0, 2.5)
#: hexahedra: the bulk size may not exceed this many wall thicknesses
HEX_MAX_SIZE_PER_WALL = 12.0


@dataclass(frozen=True, kw_only=True)
class HousingMeshConfig:
    element: str = spec("tet", choices=ELEMENTS, doc="tetrahedra (gmsh, any source) or hexahedra "
                        "(structured, one element through each wall: parametric housings only)")
    size: float | None = spec(None, gt=0.0, doc="global element size, m (tet: default 1.3 x wall for "
                              "P2, 2 x wall for P3; hex: the in-plane bulk size, default 6 x wall)")
    bore_size: float | None = spec(None, gt=0.0, doc="element size at the bores, m (tet: default size/2; "
                                   "hex: the spacing around the bores, default 2.5 x wall)")
    degree: int = spec(2, ge=1, le=3, doc="Lagrange degree (tet: 2 for thin walls, 3: p-refinement; hex: 2 or 3)")
    refine: int = spec(0, ge=0, le=3, doc="uniform splits of every tet (nested meshes, h / 2^refine)")
    edge_size: float | None = spec(None, gt=0.0, doc="element size at the re-entrant junction edges "
                                   "(wall/base, wall/wall, rib and boss junctions), m (tet default: no "
                                   "grading; hex default: 1 x wall)")
    edge_distance: float | None = spec(None, gt=0.0, doc="distance from those edges over which the size "
                                       "grows linearly from edge_size to size, m (tet only; default 2 x wall)")

    def validate(self, path: str) -> None:
        if self.element == "hex":
            self._validate_hex(path)
            return
        if self.size is not None and self.bore_size is not None and self.bore_size > self.size:
            raise ConfigError(f"{path}.bore_size", f"must be <= size = {self.size:g}, got {self.bore_size:g}")
        if self.edge_distance is not None and self.edge_size is None:
            raise ConfigError(f"{path}.edge_distance", "only with edge_size (the size at the junction edges)")

    def _validate_hex(self, path: str) -> None:
        if self.degree < 2:
            raise ConfigError(f"{path}.degree", "must be 2 or 3 with element = 'hex' (one trilinear "
                              "element through a wall locks in bending), got 1")
        if self.refine:
            raise ConfigError(f"{path}.refine", "only for element = 'tet' (the hex grid is set by "
                              f"size, edge_size and bore_size), got {self.refine}")
        if self.edge_distance is not None:
            raise ConfigError(f"{path}.edge_distance", "only for element = 'tet'; hex cells grow "
                              f"linearly (by {HEX_SIZE_GRADIENT:g} x distance) from edge_size to size")


@dataclass(frozen=True)
class HexMeshRule:
    """Resolved in-plane sizes of the hex grid, m: bulk, next to the junctions, around the bores."""
    size: float
    edge: float
    bore: float
    gradient: float = HEX_SIZE_GRADIENT

    def key_data(self) -> dict:
        return {"size": self.size, "edge_size": self.edge, "bore_size": self.bore, "size_gradient": self.gradient}


def hex_rule(mesh: HousingMeshConfig, wall: float | None, path: str = "housing.mesh") -> HexMeshRule:
    """The hex grid's sizes: the given ones, the rest from :data:`HEX_DEFAULT_PER_WALL` (edge and
    bore at most ``size``); checked
    against the wall thickness (ConfigError naming the key)."""
    t = wall if wall is not None else math.nan
    ds, de, db = HEX_DEFAULT_PER_WALL
    size = mesh.size if mesh.size is not None else ds * t
    rule = HexMeshRule(size=size,                   # defaults of edge and bore: at most the size
                       edge=mesh.edge_size if mesh.edge_size is not None else min(de * t, size),
                       bore=mesh.bore_size if mesh.bore_size is not None else min(db * t, size))
    if wall is None:
        return rule
    if not t / 4 <= rule.size <= HEX_MAX_SIZE_PER_WALL * t:
        raise ConfigError(f"{path}.size", f"with element = 'hex' must lie in [wall_thickness / 4, "
                          f"{HEX_MAX_SIZE_PER_WALL:g} x wall_thickness] = [{t / 4:g}, "
                          f"{HEX_MAX_SIZE_PER_WALL * t:g}] m, got {rule.size:g}")
    for key, v in (("edge_size", rule.edge), ("bore_size", rule.bore)):
        if not t / 4 <= v <= rule.size:
            raise ConfigError(f"{path}.{key}", f"with element = 'hex' must lie in [wall_thickness / 4, "
                              f"size] = [{t / 4:g}, {rule.size:g}] m, got {v:g}")
    return rule


@dataclass
class HexBlock:
    """The rectangle [x0, x1] x [z0, z1] of the front and back walls that holds one bore's rings."""
    bx: float
    bz: float
    r: float
    R: float
    lb: float
    rib: float          # rib thickness, 0: no rib
    x0: float
    x1: float
    z0: float
    z1: float


def hex_blocks(cfg) -> list[HexBlock]:
    """One block per bore of the parametric housing ``cfg`` (:mod:`vibrogear.geometry.housing_hex`);
    a ConfigError naming the field where a structured grid cannot take the layout."""
    L, H, t = cfg.length, cfg.height, cfg.wall_thickness
    gap = 0.25 * t
    out = []
    for i, b in enumerate(cfg.bores):
        R = b.boss_radius
        s = R + max(0.5 * t, 0.1 * R)
        for c, lo_wall, hi_wall, key in ((b.x, t, L - t, "x"), (b.z, t, H - t, "z")):
            if not (lo_wall + gap <= c - R and c + R <= hi_wall - gap):
                raise ConfigError(f"housing.bores[{i}].{key}", f"with element = 'hex' the boss "
                                  f"(boss_radius = {R:g}) must keep {gap:g} m from the inner wall faces: "
                                  f"{key} in [{lo_wall + gap + R:g}, {hi_wall - gap - R:g}], got {c:g}; "
                                  "use element = 'tet'")
        rib = cfg.rib_t if cfg.ribs and b.boss_length > 0 else 0.0
        out.append(HexBlock(b.x, b.z, b.bore_radius, R, b.boss_length, rib,
                          max(b.x - s, t + gap), min(b.x + s, L - t - gap),
                          max(b.z - s, t + gap), min(b.z + s, H - t - gap)))
    for _ in range(2 * len(out)):
        changed = _unify(out, "z0", "z1", gap) | _unify(out, "x0", "x1", gap)
        if not changed:
            break
    for i, a in enumerate(out):
        for j in range(i):
            o = out[j]
            if a.z0 < o.z1 - 1e-12 and o.z0 < a.z1 - 1e-12 and a.x0 < o.x1 - 1e-12 and o.x0 < a.x1 - 1e-12:
                raise ConfigError(f"housing.bores[{i}]", f"too close to bores[{j}] for element = 'hex' "
                                  "(their bosses need separate blocks of ring cells); use element = 'tet'")
            if (a.rib and a.x0 < o.x1 and o.x0 < a.x1 and o.z1 <= a.z0) or \
                    (o.rib and a.x0 < o.x1 and o.x0 < a.x1 and a.z1 <= o.z0):
                raise ConfigError("housing.ribs", f"bores[{i}] and bores[{j}] are stacked: a rib would run "
                                  "through the lower boss; use element = 'tet' or ribs = false")
    return out


def _unify(blocks: list[HexBlock], lo: str, hi: str, gap: float) -> bool:
    """Blocks whose [lo, hi] ranges overlap and whose bosses are apart (by >= ``gap``) in the other
    direction get one common range; in the other direction they then abut half-way between the
    bosses where they would overlap or leave less than ``gap`` between them."""
    olo, ohi = ("x0", "x1") if lo == "z0" else ("z0", "z1")
    centre = (lambda blk: blk.bx) if olo == "x0" else (lambda blk: blk.bz)
    changed = False
    for i, a in enumerate(blocks):
        for o in blocks[:i]:
            if not (getattr(a, lo) < getattr(o, hi) - 1e-12 and getattr(o, lo) < getattr(a, hi) - 1e-12):
                continue
            if abs(centre(a) - centre(o)) < a.R + o.R + gap:
                continue                                    # not apart: refused by _blocks
            lo_v, hi_v = min(getattr(a, lo), getattr(o, lo)), max(getattr(a, hi), getattr(o, hi))
            for blk in (a, o):
                if (getattr(blk, lo), getattr(blk, hi)) != (lo_v, hi_v):
                    setattr(blk, lo, lo_v)
                    setattr(blk, hi, hi_v)
                    changed = True
            left, right = sorted((a, o), key=centre)
            if getattr(left, ohi) > getattr(right, olo) - gap:
                mid = 0.5 * (centre(left) + left.R + centre(right) - right.R)
                if (getattr(left, ohi), getattr(right, olo)) != (mid, mid):
                    setattr(left, ohi, mid)
                    setattr(right, olo, mid)
                    changed = True
    return changed
