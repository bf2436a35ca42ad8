"""Parametric gearbox housing (and a verification cantilever) with gmsh's OCC kernel.

The only module that imports gmsh (inside the functions).  The contract with the FE model is
:class:`HousingMesh`: the ``.msh`` file and the physical-group tags of the base and of each bore
surface.  :func:`bore_layout` gives the bearing coupling points from the config alone (pure
geometry, no gmsh), so the FE model and the gearbox synthesis agree on them.

Coordinates: see :mod:`vibrogear.config.model.housing`.  Bores are ordered shaft by shaft, and per
shaft wall by wall from the front wall (y = 0) to the back wall (y = width): without inner
walls bore ``2 i`` and ``2 i + 1`` belong to ``bores[i]``; with n inner walls bore
``i (n + 2) + j`` (j = 0 front, 1..n the inner walls, n + 1 back), see
:mod:`vibrogear.config.model.housing_walls`.
"""
from __future__ import annotations

import math
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..config.base import ConfigError
from ..config.model.housing import HousingConfig
from ..config.model.housing_walls import bore_walls
from .mesh_size import add_size_field, junction_curves, size_field  # noqa: F401  (housing_import, tests)

__all__ = ["HousingMesh", "BoreGeometry", "MeshingError", "bore_layout", "build_housing_mesh",
           "build_beam_mesh", "housing_volume", "read_msh_arrays", "ring_frame", "size_field", "junction_curves", "write_housing_step", "VOLUME_TAG", "BASE_TAG", "BORE_TAG0"]

VOLUME_TAG = 1
BASE_TAG = 1
BORE_TAG0 = 101
_TOL = 1e-5  # gmsh pads bounding boxes by 1e-7: select with a tolerance well above it


class MeshingError(RuntimeError):
    """gmsh failed; the message is gmsh's own."""


class HousingMesh(NamedTuple):
    path: Path                   # gmsh .msh (version 4.1), physical groups only; hexahedra: .npz
    base_tag: int                # facet tag of the supported (base) surface
    bore_tags: tuple[int, ...]   # facet tag of each bore surface, in bore_layout order
    volume_tag: int
    n_nodes: int
    n_tets: int                  # number of cells (tetrahedra, or hexahedra)
    seconds: float
    cell_type: str = "tetrahedron"   # or "hexahedron" (geometry.housing_hex)


@dataclass(frozen=True)
class BoreGeometry:
    """One bore surface: a cylinder of ``radius`` about ``axis`` through ``center``."""
    name: str
    center: tuple[float, float, float]   # on the axis, at the middle of the bore length
    axis: tuple[float, float, float]     # unit, pointing out of the housing
    radius: float
    y_range: tuple[float, float]
    n_points: int

    def points(self) -> np.ndarray:
        """Coupling points (n_points, 3): theta_k = 2 pi k / n from e1 towards e2 (:func:`ring_frame`;
        for an axis along y: from +x towards +z)."""
        th = 2 * np.pi * np.arange(self.n_points) / self.n_points
        e1, e2 = ring_frame(self.axis)
        c = np.asarray(self.center, dtype=float)
        return c + self.radius * (np.cos(th)[:, None] * e1 + np.sin(th)[:, None] * e2)


def ring_frame(axis) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors (e1, e2) across a bore axis, the same for +axis and -axis: e1 is the first of
    x, z, y projected off the axis (normalised), e2 = e1 x u with u = the axis signed so that its
    largest component is positive.  Axis along y: e1 = +x, e2 = +z."""
    a = np.asarray(axis, dtype=float)
    u = a / np.linalg.norm(a)
    if u[np.argmax(np.abs(u))] < 0:
        u = -u
    for ref in (np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), np.array([0, 1.0, 0])):
        p = ref - (ref @ u) * u
        if np.linalg.norm(p) > 0.5:
            break
    e1 = p / np.linalg.norm(p)
    return e1, np.cross(e1, u)


def bore_layout(cfg: HousingConfig) -> tuple[BoreGeometry, ...]:
    """The bore surfaces and their coupling points, from the config alone."""
    out = []
    for i, b in enumerate(cfg.bores):
        label = b.name or f"shaft{i}"
        for side, (y0, y1), ay, n in bore_walls(cfg, b):
            out.append(BoreGeometry(name=f"{label}/{side}", center=(b.x, 0.5 * (y0 + y1), b.z),
                                    axis=(0.0, ay, 0.0), radius=b.bore_radius, y_range=(y0, y1),
                                    n_points=n))
    return tuple(out)


def housing_volume(cfg: HousingConfig) -> float:
    """Closed-form solid volume of the housing (box shell + inner walls + base + bosses + ribs
    - bores); each inner wall is a (length - 2 t) x t x (height - 2 t) plate less one bore
    cylinder (radius r, length t) per shaft."""
    L, W, H, t = cfg.length, cfg.width, cfg.height, cfg.wall_thickness
    v = L * W * H - (L - 2 * t) * (W - 2 * t) * (H - 2 * t)
    for _ in cfg.inner_walls:
        v += (L - 2 * t) * t * (H - 2 * t) - sum(math.pi * b.bore_radius ** 2 * t for b in cfg.bores)
    if cfg.base == "plate":
        v += (L + 2 * cfg.base_overhang) * (W + 2 * cfg.base_overhang) * cfg.base_thickness
    elif cfg.base == "feet":
        v += 4 * cfg.foot_size ** 2 * cfg.base_thickness
    for b in cfg.bores:
        R, r, lb = b.boss_radius, b.bore_radius, b.boss_length
        v += 2 * math.pi * (R * R * lb - r * r * (lb + t))
        if cfg.ribs and lb > 0:
            rt = cfg.rib_t
            # rib block x in [x - rt/2, x + rt/2], z in [0, zc], y in [-lb, 0]: minus its overlap with
            # the boss disc (circular segment of half-width rt/2 below the centre, radius R)
            seg = _segment_below(R, rt / 2)
            v += 2 * lb * (rt * b.z - seg)
    return v


def _segment_below(R: float, a: float) -> float:
    """Area of {|x| <= a, -R <= z <= 0, x^2 + z^2 <= R^2}."""
    return a * math.sqrt(R * R - a * a) + R * R * math.asin(a / R)


def _start(verbose: bool):
    import gmsh
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 1 if verbose else 0)
    gmsh.clear()
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.logger.start()
    return gmsh


def _fail(gmsh, exc: Exception) -> MeshingError:
    log = [m for m in gmsh.logger.get() if "rror" in m]
    msg = "; ".join(log[-3:]) or str(exc) or gmsh.logger.getLastError()
    return MeshingError(f"gmsh failed: {msg}")


@contextmanager
def gmsh_session(verbose: bool = False):
    """An initialised gmsh, finalised on exit whatever happens.  gmsh's own failures (plain
    Exceptions) become a MeshingError carrying gmsh's last error lines; MeshingError and
    ConfigError raised by the caller pass through unchanged."""
    gmsh = _start(verbose)
    try:
        yield gmsh
    except (MeshingError, ConfigError):
        raise
    except Exception as exc:
        raise _fail(gmsh, exc) from None
    finally:
        gmsh.logger.stop()
        gmsh.finalize()


def write_msh(gmsh, path: Path) -> None:
    """Write the current mesh as gmsh .msh 4.1 (creating the folder)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.write(str(path))


def _surfaces_in_box(gmsh, lo, hi) -> list[int]:
    ents = gmsh.model.getEntitiesInBoundingBox(lo[0] - _TOL, lo[1] - _TOL, lo[2] - _TOL,
                                               hi[0] + _TOL, hi[1] + _TOL, hi[2] + _TOL, 2)
    return [tag for _, tag in ents]


def _housing_solid(gmsh, cfg: HousingConfig, scale: float = 1.0) -> None:
    """The housing solid in gmsh's OCC model (lengths x ``scale``: 1 for metres), synchronized."""
    occ = gmsh.model.occ
    k = scale
    L, W, H, t = k * cfg.length, k * cfg.width, k * cfg.height, k * cfg.wall_thickness
    tb, eps = k * cfg.base_thickness, k * 1e-3
    outer = occ.addBox(0, 0, 0, L, W, H)
    inner = occ.addBox(t, t, t, L - 2 * t, W - 2 * t, H - 2 * t)
    shell, _ = occ.cut([(3, outer)], [(3, inner)])
    parts = [(3, occ.addBox(t, k * y - t / 2, t, L - 2 * t, t, H - 2 * t)) for y in cfg.inner_walls]
    if cfg.base == "plate":
        o = k * cfg.base_overhang
        parts.append((3, occ.addBox(-o, -o, -tb, L + 2 * o, W + 2 * o, tb)))
    elif cfg.base == "feet":
        f = k * cfg.foot_size
        for x in (0.0, L - f):
            for y in (0.0, W - f):
                parts.append((3, occ.addBox(x, y, -tb, f, f, tb)))
    holes = []
    for b in cfg.bores:
        lb, bx, bz = k * b.boss_length, k * b.x, k * b.z
        if lb > 0:
            parts.append((3, occ.addCylinder(bx, -lb, bz, 0, lb, 0, k * b.boss_radius)))
            parts.append((3, occ.addCylinder(bx, W, bz, 0, lb, 0, k * b.boss_radius)))
            if cfg.ribs:
                rt = k * cfg.rib_t
                parts.append((3, occ.addBox(bx - rt / 2, -lb, 0, rt, lb, bz)))
                parts.append((3, occ.addBox(bx - rt / 2, W, 0, rt, lb, bz)))
        holes.append((3, occ.addCylinder(bx, -lb - eps, bz, 0, W + 2 * lb + 2 * eps, 0, k * b.bore_radius)))
    body = shell
    if parts:
        body, _ = occ.fuse(shell, parts)
    occ.cut(body, holes)
    occ.synchronize()


def write_housing_step(cfg: HousingConfig, path: str | Path) -> Path:
    """The parametric housing's solid as a STEP file in millimetres (what a CAD system exports):
    gmsh writes its model coordinates with a millimetre unit label, so the model is built in mm."""
    path = Path(path)
    with gmsh_session(False) as gmsh:
        # OCC's STEP unit is process-wide: after an import in metres the writer would convert
        gmsh.option.setString("Geometry.OCCTargetUnit", "MM")
        gmsh.model.add("housing")
        _housing_solid(gmsh, cfg, scale=1000.0)  # in mm: OCC's dilation approximates cylinders
        path.parent.mkdir(parents=True, exist_ok=True)
        gmsh.write(str(path))
    return path


def build_housing_mesh(cfg: HousingConfig, path: str | Path, *, verbose: bool = False) -> HousingMesh:
    """Build, mesh and write the housing to ``path`` (.msh).  Raises MeshingError."""
    path = Path(path)
    t0 = time.perf_counter()
    with gmsh_session(verbose) as gmsh:
        gmsh.model.add("housing")
        _housing_solid(gmsh, cfg)
        L, W = cfg.length, cfg.width
        vols = gmsh.model.getEntities(3)
        if len(vols) != 1:
            raise MeshingError(f"housing geometry is not one connected solid ({len(vols)} volumes)")
        gmsh.model.addPhysicalGroup(3, [vols[0][1]], VOLUME_TAG)
        gmsh.model.setPhysicalName(3, VOLUME_TAG, "housing")
        zb = -cfg.base_thickness if cfg.base != "none" else 0.0
        pad = max([cfg.base_overhang] + [b.boss_length for b in cfg.bores])
        base = _surfaces_in_box(gmsh, (-pad, -pad, zb), (L + pad, W + pad, zb))
        if not base:
            raise MeshingError("could not find the base surface")
        gmsh.model.addPhysicalGroup(2, base, BASE_TAG)
        gmsh.model.setPhysicalName(2, BASE_TAG, "base")
        bore_tags, bore_surfs = [], []
        for k, g in enumerate(bore_layout(cfg)):
            cx, _, cz = g.center
            surfs = _surfaces_in_box(gmsh, (cx - g.radius, g.y_range[0], cz - g.radius),
                                     (cx + g.radius, g.y_range[1], cz + g.radius))
            if not surfs:
                raise MeshingError(f"could not find the surface of bore {g.name}")
            tag = BORE_TAG0 + k
            gmsh.model.addPhysicalGroup(2, surfs, tag)
            gmsh.model.setPhysicalName(2, tag, f"bore_{g.name.replace('/', '_')}")
            bore_tags.append(tag)
            bore_surfs += surfs
        add_size_field(gmsh, cfg, bore_surfs)
        gmsh.model.mesh.generate(3)
        gmsh.option.setNumber("Mesh.SecondOrderLinear", 1)  # split at straight midpoints: nested
        for _ in range(cfg.mesh.refine):
            gmsh.model.mesh.refine()
        n_nodes = len(gmsh.model.mesh.getNodes()[0])
        types, tags, _ = gmsh.model.mesh.getElements(3)
        n_tets = sum(len(x) for x in tags)
        if n_tets == 0:
            raise MeshingError("gmsh produced no tetrahedra")
        write_msh(gmsh, path)
    return HousingMesh(path, BASE_TAG, tuple(bore_tags), VOLUME_TAG, n_nodes, n_tets,
                       time.perf_counter() - t0)


def build_beam_mesh(length: float, width: float, height: float, path: str | Path, *,
                    size: float, verbose: bool = False) -> HousingMesh:
    """A solid cantilever along x, clamped at x = 0 (group BASE_TAG); no bores."""
    path = Path(path)
    t0 = time.perf_counter()
    with gmsh_session(verbose) as gmsh:
        gmsh.model.add("beam")
        vol = gmsh.model.occ.addBox(0, 0, 0, length, width, height)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [vol], VOLUME_TAG)
        clamp = _surfaces_in_box(gmsh, (0, 0, 0), (0, width, height))
        gmsh.model.addPhysicalGroup(2, clamp, BASE_TAG)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.5 * size)
        gmsh.model.mesh.generate(3)
        n_nodes = len(gmsh.model.mesh.getNodes()[0])
        n_tets = sum(len(x) for x in gmsh.model.mesh.getElements(3)[1])
        write_msh(gmsh, path)
    return HousingMesh(path, BASE_TAG, (), VOLUME_TAG, n_nodes, n_tets, time.perf_counter() - t0)


def read_msh_arrays(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(x (N, 3), tets (n, 4), facets (k, 3), facet physical tags (k,)) of a linear tet .msh.

    Node indices are 0-based rows of ``x``; the vertex order is gmsh's, which for linear
    tetrahedra and triangles is also dolfinx's.
    """
    with gmsh_session(False) as gmsh:
        gmsh.merge(str(path))
        tags, coords, _ = gmsh.model.mesh.getNodes()
        index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
        index[tags.astype(np.int64)] = np.arange(len(tags))
        x = coords.reshape(-1, 3)
        tets = []
        for _, ent in gmsh.model.getEntities(3):
            for etype, _, nodes in zip(*gmsh.model.mesh.getElements(3, ent)):
                if etype != 4:
                    raise MeshingError(f"{path}: expected linear tetrahedra, got gmsh element type {etype}")
                tets.append(index[nodes.astype(np.int64)].reshape(-1, 4))
        facets, values = [], []
        for dim, ptag in gmsh.model.getPhysicalGroups(2):
            for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, ptag):
                for etype, _, nodes in zip(*gmsh.model.mesh.getElements(2, ent)):
                    f = index[nodes.astype(np.int64)].reshape(-1, 3)
                    facets.append(f)
                    values.append(np.full(len(f), ptag, dtype=np.int32))
    return (x, np.vstack(tets), np.vstack(facets) if facets else np.zeros((0, 3), np.int64),
            np.concatenate(values) if values else np.zeros(0, np.int32))
