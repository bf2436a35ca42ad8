"""Housing scene schema: ``[housing]`` and its sub-tables (the stator of paper eq. (3)).

``source`` says where the housing comes from: ``"parametric"`` (the default: the box below),
``"step"`` (a CAD solid, meshed here), ``"mesh"`` (another FE program's tetrahedral mesh) or
``"modal"`` (another FE program's modes at the coupling points).  The imported sources take
``file`` (relative to the scene file), ``fixed_region`` (every boundary face inside the box is
clamped) and bores given by ``center``, ``axis`` and ``bore_radius``; see
:mod:`vibrogear.geometry.housing_import` and docs/housing.md.

Parametric coordinates (metres): the box occupies ``0 <= x <= length``, ``0 <= y <= width``,
``0 <= z <= height`` (z up; the base plate or feet lie below z = 0).  Each
``[[housing.bores]]`` entry is one shaft: a pair of coaxial bearing bosses through the two
walls normal to y (the *front* wall at y = 0 and the *back* wall at y = width), with the shaft
axis parallel to y at (x, z).  Bosses protrude ``boss_length`` outwards from the wall.
``inner_walls`` adds walls parallel to those, each shaft axis bored through every wall
(:mod:`vibrogear.config.model.housing_walls`: their rules and the bores' numbering).
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..base import ConfigError, spec
from .housing_bores import BoreConfig, FixedRegionConfig
from .housing_walls import check_inner_walls, check_wall_counts
from .housing_mesh import (DEFAULT_SIZE_PER_WALL, ELEMENTS, MAX_SIZE_PER_WALL, HexMeshRule,
                           HousingMeshConfig, hex_blocks, hex_rule)

__all__ = ["HousingConfig", "BoreConfig", "FixedRegionConfig", "SOURCES", "FILE_SUFFIXES", "LENGTH_UNITS", "MaterialConfig", "HousingMeshConfig",
           "HousingModesConfig", "HOUSING_SOLVERS",
           "MAX_SIZE_PER_WALL", "DEFAULT_SIZE_PER_WALL", "ELEMENTS", "HexMeshRule", "hex_rule", "check_file", "resolve_file"]

#: ``[housing.modes] solver``: block Lanczos (own) or SLEPc Krylov-Schur / subspace iteration in
#: shift-and-invert on the Cholesky factor of K; ``krylovschur_gamg``: Krylov-Schur with CG + GAMG
#: inner solves, no factor (housings beyond the direct factor's memory).  SLEPc's LOBPCG is not
#: offered: it broke down on the clamped housing (docs/housing.md, "Solvers")
HOUSING_SOLVERS = ("block", "krylovschur", "subspace", "krylovschur_gamg")
SOURCES = ("parametric", "step", "mesh", "modal")
#: file suffixes (lower case) each imported source reads
FILE_SUFFIXES = {
    "step": (".step", ".stp"),
    "mesh": (".inp", ".bdf", ".nas", ".msh", ".vtu", ".xdmf"),
    "modal": (".npz", ".csv", ".unv", ".uff"),
}
#: metres per unit of a mesh / modal file (STEP files carry their own unit)
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3}
#: the parametric box's keys, refused with an imported source
_BOX_KEYS = ("length", "width", "height", "wall_thickness")


@dataclass(frozen=True, kw_only=True)
class MaterialConfig:
    """Isotropic linear elastic material; steel by default.  ``beta``: B_S = beta K_S."""
    E: float = spec(210e9, gt=0.0, doc="Young's modulus, Pa")
    nu: float = spec(0.3, gt=0.0, lt=0.5, doc="Poisson's ratio")
    rho: float = spec(7850.0, gt=0.0, doc="density, kg/m^3")
    beta: float = spec(0.0, ge=0.0, lt=1.0, doc="stiffness-proportional damping beta_S, s")


@dataclass(frozen=True, kw_only=True)
class HousingModesConfig:
    count: int = spec(20, ge=1, le=2000, doc="number of master modes (ignored with cutoff_hz)")
    cutoff_hz: float | None = spec(None, gt=0.0, doc="all modes below this (paper: >= 2 x highest excitation)")
    max_count: int = spec(400, ge=1, le=5000, doc="safety cap on the number of modes with cutoff_hz")
    tol: float = spec(1e-8, gt=0.0, le=1e-4, doc="relative eigen-tolerance (SLEPc's criterion)")
    solver: str = spec("block", choices=HOUSING_SOLVERS,
                       doc="eigen-solver: direct (block, krylovschur, subspace: Cholesky of K) or iterative "
                           "for housings beyond the direct factor (krylovschur_gamg: CG + GAMG)")
    shapes: int = spec(12, ge=0, le=5000, doc="mode shapes written to XDMF")
    plot: tuple[int, ...] = spec((1, 2, 3, 4, 5, 6), ge=1, le=5000, max_len=60,
                                 doc="modes (1-based) drawn as shaded surfaces, 6 per figure")


@dataclass(frozen=True, kw_only=True)
class HousingConfig:
    source: str = spec("parametric", choices=SOURCES, doc="parametric box, STEP solid, FE mesh or FE modes")
    file: str | None = spec(None, doc="STEP / mesh / modal file (relative to the scene file)")
    fixed_region: FixedRegionConfig | None = spec(None, doc="clamped boundary faces (imported housings)")
    length_unit: str = spec("m", choices=tuple(LENGTH_UNITS), doc="unit of a mesh or modal file's lengths")
    length: float | None = spec(None, gt=0.0, doc="outer box length (x), m")
    width: float | None = spec(None, gt=0.0, doc="outer box width (y, along the shafts), m")
    height: float | None = spec(None, gt=0.0, doc="outer box height (z), m")
    wall_thickness: float | None = spec(None, gt=0.0, doc="wall thickness, m")
    bores: tuple[BoreConfig, ...] = spec((), max_len=16, doc="one bearing-boss pair (or bore line) per shaft")
    inner_walls: tuple[float, ...] = spec((), max_len=8, gt=0.0, doc="middle plane y of each inner wall "
                                          "(parallel to front and back, full height and length, bored "
                                          "at every shaft axis), ascending, m")
    base: str = spec("plate", choices=("plate", "feet", "none"), doc="what the housing stands on")
    base_thickness: float = spec(0.02, gt=0.0, doc="thickness of the base plate or feet, m")
    base_overhang: float = spec(0.03, ge=0.0, doc="plate overhang beyond the box, m")
    foot_size: float = spec(0.06, gt=0.0, doc="edge of the square corner feet, m")
    ribs: bool = spec(False, doc="a vertical rib under each boss, outside the wall")
    rib_thickness: float | None = spec(None, gt=0.0, doc="rib thickness, m (default: wall)")
    support: str = spec("fixed", choices=("fixed", "elastic"), doc="base clamped or on a foundation")
    foundation_stiffness: float = spec(1e11, gt=0.0, doc="Winkler foundation stiffness, N/m^3")
    material: MaterialConfig = spec(MaterialConfig())
    mesh: HousingMeshConfig = spec(HousingMeshConfig())
    modes: HousingModesConfig = spec(HousingModesConfig())

    @property
    def hex_mesh(self) -> HexMeshRule:
        """The hex grid's resolved sizes (``mesh.element = "hex"``)."""
        return hex_rule(self.mesh, self.wall_thickness)

    @property
    def mesh_size(self) -> float:
        if self.mesh.element == "hex":
            return self.hex_mesh.size
        if self.mesh.size is not None:
            return self.mesh.size
        per_wall = DEFAULT_SIZE_PER_WALL[self.mesh.degree]
        return per_wall * self.wall_thickness if self.wall_thickness is not None else math.nan

    @property
    def bore_mesh_size(self) -> float:
        if self.mesh.element == "hex":
            return self.hex_mesh.bore
        return self.mesh.bore_size if self.mesh.bore_size is not None else 0.5 * self.mesh_size

    @property
    def edge_mesh_size(self) -> float | None:
        """Element size at the re-entrant junction edges; None: no grading."""
        return self.mesh.edge_size

    @property
    def edge_mesh_distance(self) -> float:
        if self.mesh.edge_distance is not None:
            return self.mesh.edge_distance
        return 2.0 * self.wall_thickness if self.wall_thickness is not None else math.nan

    @property
    def rib_t(self) -> float:
        return self.rib_thickness if self.rib_thickness is not None else self.wall_thickness

    def key_data(self) -> dict[str, Any]:
        """The config as cache-key data: a parametric housing's keys are those it had before the
        imported sources existed; an imported one adds the file's SHA-256 (content, not name)."""
        import dataclasses
        import hashlib

        d = dataclasses.asdict(self)
        d["modes"].pop("plot")               # what is drawn, not what is solved
        if not self.inner_walls:             # keys of scenes without inner walls unchanged
            d.pop("inner_walls")
        for b in d["bores"]:
            if not b["wall_rolling_elements"]:
                b.pop("wall_rolling_elements")
        # the edge grading enters the keys only where it is on (keys of ungraded scenes unchanged),
        # resolved and at the top level, so that the mesh entry's key (which replaces "mesh") has it
        for k in ("edge_size", "edge_distance", "element"):
            d["mesh"].pop(k)
        if self.mesh.element == "hex":           # a tet scene's keys stay as they were
            d["mesh_element"] = {"element": "hex", **self.hex_mesh.key_data()}
        elif self.edge_mesh_size is not None:
            d["mesh_grading"] = {"edge_size": self.edge_mesh_size, "edge_distance": self.edge_mesh_distance}
        if self.source == "parametric":
            for k in ("source", "file", "fixed_region", "length_unit"):
                d.pop(k)
            for b in d["bores"]:
                for k in ("center", "axis", "length"):
                    b.pop(k)
            return d
        h = hashlib.sha256()
        with open(self.file, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
        d["file"] = {"name": Path(self.file).name, "sha256": h.hexdigest()}
        return d

    def validate(self, path: str) -> None:
        p = path or "housing"
        if self.source != "parametric":
            check_inner_walls(self, p)
            if self.mesh.element != "tet":
                raise ConfigError(f"{p}.mesh.element", f"'hex' only for the parametric housing (its "
                                  f"walls are known); a {self.source!r} housing is meshed with 'tet'")
            if self.mesh.edge_size is not None:
                raise ConfigError(f"{p}.mesh.edge_size", "only for the parametric housing (its junction "
                                  "edges are known); an imported housing is meshed with size / bore_size")
            self._validate_imported(p)
            return
        for k in _BOX_KEYS:
            if getattr(self, k) is None:
                raise ConfigError(f"{p}.{k}", "missing required key (source = 'parametric')")
        for k in ("file", "fixed_region"):
            if getattr(self, k) is not None:
                raise ConfigError(f"{p}.{k}", "only for an imported housing (source = 'step', 'mesh' or "
                                  "'modal'); the parametric housing is clamped at its base")
        if not self.bores:
            raise ConfigError(f"{p}.bores", "needs at least 1 entries, got 0 (the parametric housing is "
                              "built around its bores)")
        for i, b in enumerate(self.bores):
            if b.center is not None or b.axis is not None:
                raise ConfigError(f"{p}.bores[{i}].center", "only for an imported housing; the parametric "
                                  "housing's bores are given by x and z")
            for k in ("x", "z", "boss_radius"):
                if getattr(b, k) is None:
                    raise ConfigError(f"{p}.bores[{i}].{k}", "missing required key (source = 'parametric')")
            b.validate(f"{p}.bores[{i}]")
        t = self.wall_thickness
        dims = {"length": self.length, "width": self.width, "height": self.height}
        name, smallest = min(dims.items(), key=lambda kv: kv[1])
        if not t < 0.5 * smallest:
            raise ConfigError(f"{p}.wall_thickness", f"must be < half the smallest outer dimension "
                              f"({name} = {smallest:g}, so < {0.5 * smallest:g}), got {t:g}")
        if self.base == "feet" and not self.foot_size < 0.5 * min(self.length, self.width):
            raise ConfigError(f"{p}.foot_size", f"must be < half of min(length, width) = "
                              f"{0.5 * min(self.length, self.width):g}, got {self.foot_size:g}")
        self._validate_bores(p)
        check_inner_walls(self, p)
        check_wall_counts(self, p)
        if self.mesh.element == "hex":
            hex_rule(self.mesh, t, f"{p}.mesh")
            hex_blocks(self)                   # a layout the structured grid cannot take: refused
            self._validate_modes(p)
            return
        size = self.mesh_size
        if size > MAX_SIZE_PER_WALL * t:
            raise ConfigError(f"{p}.mesh.size", f"too coarse to put an element across the wall: must be "
                              f"<= {MAX_SIZE_PER_WALL:g} x wall_thickness = {MAX_SIZE_PER_WALL * t:g}, got {size:g}")
        if self.mesh.bore_size is not None and self.mesh.size is None and self.mesh.bore_size > size:
            raise ConfigError(f"{p}.mesh.bore_size", f"must be <= size = {size:g}, got {self.mesh.bore_size:g}")
        if size < t / 50:
            raise ConfigError(f"{p}.mesh.size", f"must be >= wall_thickness / 50 = {t / 50:g} "
                              f"(millions of elements), got {size:g}")
        he = self.edge_mesh_size
        if he is not None and not t / 50 <= he <= size:
            raise ConfigError(f"{p}.mesh.edge_size", f"must be in [wall_thickness / 50, size] = "
                              f"[{t / 50:g}, {size:g}], got {he:g}")
        self._validate_modes(p)

    def _validate_modes(self, p: str) -> None:
        m = self.modes
        if m.cutoff_hz is None and m.count > m.max_count:
            raise ConfigError(f"{p}.modes.count", f"must be <= max_count = {m.max_count}, got {m.count}")

    def _validate_imported(self, p: str) -> None:
        src = self.source
        for k in _BOX_KEYS:
            if getattr(self, k) is not None:
                raise ConfigError(f"{p}.{k}", f"only for source = 'parametric'; a {src!r} housing takes its "
                                  "geometry from its file")
        check_file(self.file, src, f"{p}.file")
        if src in ("step", "mesh") and self.fixed_region is None and self.support == "fixed":
            raise ConfigError(f"{p}.fixed_region", f"missing required key: a {src!r} housing is clamped on "
                              "the boundary faces inside fixed_region = { min = [x, y, z], max = [x, y, z] }")
        if src == "modal" and self.fixed_region is not None:
            raise ConfigError(f"{p}.fixed_region", "not for source = 'modal': the modes were computed with "
                              "their supports already")
        if src == "step" and self.mesh.size is None:
            raise ConfigError(f"{p}.mesh.size", "missing required key: a STEP housing needs the global "
                              "element size, m (no wall thickness to derive it from)")
        names = set()
        for i, b in enumerate(self.bores):
            bp = f"{p}.bores[{i}]"
            if b.center is None or b.axis is None:
                raise ConfigError(f"{bp}.center", f"missing required key: a {src!r} housing's bores are given "
                                  "by center = [x, y, z], axis = [ax, ay, az] and bore_radius")
            b.validate(bp)
            label = b.name or f"shaft{i}"
            if label in names:
                raise ConfigError(f"{bp}.name", f"duplicate bore name {label!r}")
            names.add(label)
        self._validate_modes(p)

    def _validate_bores(self, p: str) -> None:
        t, L, H = self.wall_thickness, self.length, self.height
        for i, b in enumerate(self.bores):
            bp = f"{p}.bores[{i}]"
            R, r = b.boss_radius, b.bore_radius
            if not (R <= b.x <= L - R):
                raise ConfigError(f"{bp}.x", f"boss outside the wall: x must lie in [boss_radius, length - "
                                  f"boss_radius] = [{R:g}, {L - R:g}], got {b.x:g}")
            if not (R <= b.z <= H - R):
                raise ConfigError(f"{bp}.z", f"boss outside the wall: z must lie in [boss_radius, height - "
                                  f"boss_radius] = [{R:g}, {H - R:g}], got {b.z:g}")
            if not (t + r < b.x < L - t - r):
                raise ConfigError(f"{bp}.x", f"bore overlaps the box edge: x must lie in (wall_thickness + "
                                  f"bore_radius, length - wall_thickness - bore_radius) = "
                                  f"({t + r:g}, {L - t - r:g}), got {b.x:g}")
            if not (t + r < b.z < H - t - r):
                raise ConfigError(f"{bp}.z", f"bore overlaps the box edge: z must lie in (wall_thickness + "
                                  f"bore_radius, height - wall_thickness - bore_radius) = "
                                  f"({t + r:g}, {H - t - r:g}), got {b.z:g}")
            if b.boss_length > 0 and b.boss_radius - b.bore_radius < 0.25 * t:
                raise ConfigError(f"{bp}.boss_radius", f"boss ring too thin: boss_radius - bore_radius must be "
                                  f">= wall_thickness / 4 = {0.25 * t:g}, got {R - r:g}")
            for j in range(i):
                o = self.bores[j]
                d = math.hypot(b.x - o.x, b.z - o.z)
                need = b.bore_radius + o.bore_radius + t
                if d < need:
                    raise ConfigError(bp, f"bores overlap bores[{j}]: centre distance must be >= the sum of "
                                      f"the bore radii + wall_thickness = {need:g}, got {d:g}")


def check_file(file: str | None, source: str, path: str) -> Path:
    """The file of an imported housing: given, existing, readable, with a supported suffix."""
    suffixes = FILE_SUFFIXES[source]
    if file is None:
        raise ConfigError(path, f"missing required key: source = {source!r} reads a file "
                          f"({', '.join(suffixes)})")
    f = Path(file)
    if f.suffix.lower() not in suffixes:
        raise ConfigError(path, f"{file}: unsupported file type {f.suffix or '(no suffix)'!r} for source = "
                          f"{source!r}; expected one of {', '.join(suffixes)}")
    if not f.is_file():
        raise ConfigError(path, f"{file}: no such file")
    if not os.access(f, os.R_OK):
        raise ConfigError(path, f"{file}: not readable (permission denied)")
    return f


def resolve_file(data: dict[str, Any], base_dir: str | Path) -> None:
    """Make a relative ``housing.file`` of the scene ``data`` relative to ``base_dir`` (the scene
    file's folder), in place."""
    h = data.get("housing")
    if isinstance(h, dict) and isinstance(h.get("file"), str) and h["file"]:
        f = Path(h["file"]).expanduser()
        if not f.is_absolute():
            h["file"] = str(Path(base_dir) / f)
