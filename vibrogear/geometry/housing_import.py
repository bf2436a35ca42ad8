"""Imported housings: a CAD solid (STEP, gmsh's OpenCASCADE importer) or another FE program's
tetrahedral mesh (meshio), written as the same tagged ``.msh`` as the parametric housing.

Both return :class:`ImportedHousing`: the :class:`~.housing.HousingMesh` contract (clamped
facets in group ``BASE_TAG``, one group per bore from ``BORE_TAG0``) plus the bore layout, which
for an imported housing comes from the geometry:

* ``fixed_region``: every boundary face (STEP: OCC face; mesh: triangle) lying wholly inside the
  box, padded by 1e-5 m (gmsh pads entity boxes by 1e-7), is clamped (or sits on the Winkler
  foundation with ``support = "elastic"``).
* each ``[[housing.bores]]`` entry is a shaft line through ``center`` along ``axis``: the bore
  surfaces are the boundary faces lying on the cylinder of ``bore_radius`` about the line (all
  sample points / vertices within 1e-6 m + 1e-4 r of it; with ``length``, only those within
  ``center +- length/2`` along the axis).  Faces touching along the axis form one bore; two bores
  are named ``<name>/front`` (smaller axial coordinate, outward axis ``-axis``) and
  ``<name>/back`` (outward ``+axis``), as the parametric housing's; one bore keeps ``<name>``;
  more are ``<name>/0``, ``<name>/1``, ...  The coupling ring lies at the bore's axial middle.

Units: a STEP file is read in its own unit and converted to metres (``Geometry.OCCTargetUnit``);
a mesh file's coordinates are multiplied by ``LENGTH_UNITS[cfg.length_unit]``.  10-node
tetrahedra keep their 4 vertices (straight-sided geometry; the FE degree is ``mesh.degree``).
"""
from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..config.base import ConfigError
from ..config.model.housing import LENGTH_UNITS, HousingConfig
from .housing import (BASE_TAG, BORE_TAG0, VOLUME_TAG, BoreGeometry, HousingMesh, MeshingError,
                      gmsh_session, size_field, write_msh)

__all__ = ["ImportedHousing", "build_mesh", "mesh_bores", "mesh_info", "save_layout", "build_step_mesh",
           "build_imported_mesh", "read_tet_mesh", "bore_segments", "segment_bores",
           "write_tagged_msh", "BOX_TOL", "face_samples", "select_bores", "fixed_faces",
           "check_step_housing"]

log = logging.getLogger(__name__)

#: padding of the fixed_region box, m (above gmsh's 1e-7 bounding-box padding)
BOX_TOL = 1e-5
_SAMPLES = 7          # parametric samples per direction on a STEP face


class ImportedHousing(NamedTuple):
    mesh: HousingMesh
    bores: tuple[BoreGeometry, ...]
    info: dict           # what was read: file, unit, solids, volume, faces per group, bbox


def _as_array(samples) -> tuple[np.ndarray, np.ndarray | list]:
    """(face ids, points (k, n, 3) or a list of (n_i, 3) arrays)."""
    if isinstance(samples, np.ndarray):
        return np.arange(len(samples)), samples
    return np.array(list(samples), dtype=np.int64), list(samples.values())


def _cylinder_faces(samples, c: np.ndarray, u: np.ndarray, r: float):
    """(mask of faces with every sample point on the cylinder, s_min, s_max along the axis)."""
    ids, pts = _as_array(samples)
    if isinstance(pts, np.ndarray):                       # triangles: all at once
        d = pts - c
        s = d @ u
        rad = np.linalg.norm(d - s[..., None] * u, axis=-1)
        return ids, np.all(np.abs(rad - r) <= 1e-6 + 1e-4 * r, axis=1), s.min(axis=1), s.max(axis=1)
    out = np.zeros(len(pts), bool), np.zeros(len(pts)), np.zeros(len(pts))
    for k, p in enumerate(pts):
        d = p - c
        sk = d @ u
        rad = np.linalg.norm(d - sk[:, None] * u, axis=1)
        out[0][k], out[1][k], out[2][k] = np.all(np.abs(rad - r) <= 1e-6 + 1e-4 * r), sk.min(), sk.max()
    return (ids, *out)


def bore_segments(intervals: list[tuple[float, float]], tol: float) -> list[tuple[float, float, list[int]]]:
    """Merge axial intervals (s0, s1) that overlap or touch within ``tol`` into bores:
    [(s0, s1, indices of the merged intervals)], sorted by s0."""
    order = sorted(range(len(intervals)), key=lambda i: intervals[i][0])
    out: list[tuple[float, float, list[int]]] = []
    for i in order:
        a, b = intervals[i]
        if out and a <= out[-1][1] + tol:
            s0, s1, idx = out[-1]
            out[-1] = (s0, max(s1, b), idx + [i])
        else:
            out.append((a, b, [i]))
    return out


def segment_bores(cfg: HousingConfig, i: int, segs, c: np.ndarray, u: np.ndarray) -> list[BoreGeometry]:
    """The bores (names, ring centres, outward axes) of config bore ``i`` from its merged axial
    segments (:func:`bore_segments`) on the line through ``c`` along the unit vector ``u``."""
    b = cfg.bores[i]
    label = b.name or f"shaft{i}"
    if len(segs) == 1:
        names, signs = [label], [1.0]
    elif len(segs) == 2:
        names, signs = [f"{label}/front", f"{label}/back"], [-1.0, 1.0]
    else:
        names, signs = [f"{label}/{k}" for k in range(len(segs))], [1.0] * len(segs)
    out = []
    for (s0, s1, _), name, sg in zip(segs, names, signs):
        mid = c + 0.5 * (s0 + s1) * u
        out.append(BoreGeometry(name=name, center=tuple(float(v) for v in mid),
                                axis=tuple(float(v) for v in sg * u), radius=b.bore_radius,
                                y_range=(float(min(c[1] + s0 * u[1], c[1] + s1 * u[1])),
                                         float(max(c[1] + s0 * u[1], c[1] + s1 * u[1]))),
                                n_points=b.rolling_elements))
    return out


def select_bores(cfg: HousingConfig, samples: dict[int, np.ndarray], file: str, scale: float):
    """(bore layout, [face ids per bore]) from boundary faces given by sample points."""
    bores, groups = [], []
    for i, b in enumerate(cfg.bores):
        c, u = np.asarray(b.center, float), np.asarray(b.unit_axis, float)
        ids, on, smin, smax = _cylinder_faces(samples, c, u, b.bore_radius)
        if b.length is not None:
            on &= (smin >= -0.5 * b.length - BOX_TOL) & (smax <= 0.5 * b.length + BOX_TOL)
        hits = [int(f) for f in ids[on]]
        intervals = list(zip(smin[on].tolist(), smax[on].tolist()))
        if not hits:
            raise ConfigError(f"housing.bores[{i}]", f"{file}: the bore cuts no boundary face: no face lies on "
                              f"the cylinder of radius {b.bore_radius:g} m about the line through "
                              f"{list(b.center)} along {list(b.axis)}"
                              + (f" within length {b.length:g} m" if b.length is not None else ""))
        segs = bore_segments(intervals, 1e-6 * scale)
        bores += segment_bores(cfg, i, segs, c, u)
        groups += [[hits[k] for k in idx] for _, _, idx in segs]
    return tuple(bores), groups


def fixed_faces(cfg: HousingConfig, samples, bore_groups, file: str) -> list[int]:
    if cfg.fixed_region is None:
        return []
    lo = np.asarray(cfg.fixed_region.min) - BOX_TOL
    hi = np.asarray(cfg.fixed_region.max) + BOX_TOL
    ids, pts = _as_array(samples)
    if isinstance(pts, np.ndarray):
        inside = np.all((pts >= lo) & (pts <= hi), axis=(1, 2))
    else:
        inside = np.array([bool(np.all((p >= lo) & (p <= hi))) for p in pts], dtype=bool)
    fixed = [int(f) for f in ids[inside]]
    if not fixed:
        raise ConfigError("housing.fixed_region", f"{file}: selects no boundary face: none lies inside "
                          f"min = {list(cfg.fixed_region.min)}, max = {list(cfg.fixed_region.max)} (m)")
    in_bores = set(fixed) & {f for g in bore_groups for f in g}
    if in_bores:
        raise ConfigError("housing.fixed_region", f"{file}: clamps {len(in_bores)} bore face(s); the bore "
                          "surfaces must stay free (make the box smaller)")
    return fixed


def _read_step_solid(gmsh, file: str):
    """Import the STEP file into the open gmsh session (OCC, metres): (volumes, solids in the
    file, volume m^3, bounding box, its diagonal m, boundary faces, their sample points);
    ConfigError naming ``housing.file`` for a file OCC cannot read or one without a solid."""
    gmsh.option.setString("Geometry.OCCTargetUnit", "M")
    occ = gmsh.model.occ
    try:
        occ.importShapes(file)
    except Exception:
        msg = gmsh.logger.getLastError() or "OpenCASCADE could not read it"
        raise ConfigError("housing.file", f"{file}: not a readable STEP file ({msg})") from None
    occ.synchronize()
    vols = gmsh.model.getEntities(3)
    if not vols:
        n_s = len(gmsh.model.getEntities(2))
        raise ConfigError("housing.file", f"{file}: holds no solid ({n_s} surfaces, 0 volumes): an open "
                          "shell or surface model cannot be meshed with tetrahedra")
    n_solids = len(vols)
    if n_solids > 1:                      # conformal interfaces between touching solids
        occ.fragment(vols[:1], vols[1:])
        occ.synchronize()
        vols = gmsh.model.getEntities(3)
    volume = float(sum(occ.getMass(3, t) for _, t in vols))
    bbox = gmsh.model.getBoundingBox(-1, -1)
    scale = float(np.linalg.norm(np.subtract(bbox[3:], bbox[:3])))
    faces = sorted({abs(t) for _, t in gmsh.model.getBoundary(vols, combined=True, oriented=False)})
    return vols, n_solids, volume, bbox, scale, faces, {f: face_samples(gmsh, f) for f in faces}


def check_step_housing(cfg: HousingConfig) -> None:
    """The STEP housing's bores and clamped faces selected as the mesher selects them, without
    meshing (``vibrogear check``): ConfigError naming the bore or ``housing.fixed_region``."""
    file = str(cfg.file)
    with gmsh_session(False) as gmsh:
        _, _, _, _, scale, _, samples = _read_step_solid(gmsh, file)
        _, groups = select_bores(cfg, samples, file, scale)
        fixed_faces(cfg, samples, groups, file)


def build_step_mesh(cfg: HousingConfig, path: str | Path, *, verbose: bool = False) -> ImportedHousing:
    """Import ``cfg.file`` (STEP) with OCC in metres, tag, mesh (P2 rules) and write ``path`` (.msh)."""
    path, file = Path(path), str(cfg.file)
    t0 = time.perf_counter()
    with gmsh_session(verbose) as gmsh:
        vols, n_solids, volume, bbox, scale, faces, samples = _read_step_solid(gmsh, file)
        bores, groups = select_bores(cfg, samples, file, scale)
        fixed = fixed_faces(cfg, samples, groups, file)
        gmsh.model.addPhysicalGroup(3, [t for _, t in vols], VOLUME_TAG)
        gmsh.model.setPhysicalName(3, VOLUME_TAG, "housing")
        if fixed:
            gmsh.model.addPhysicalGroup(2, fixed, BASE_TAG)
            gmsh.model.setPhysicalName(2, BASE_TAG, "fixed")
        for k, (g, faces_k) in enumerate(zip(bores, groups)):
            gmsh.model.addPhysicalGroup(2, faces_k, BORE_TAG0 + k)
            gmsh.model.setPhysicalName(2, BORE_TAG0 + k, f"bore_{g.name.replace('/', '_')}")
        h, hb = cfg.mesh_size, cfg.bore_mesh_size
        rmax = max((b.bore_radius for b in cfg.bores), default=0.0)
        size_field(gmsh, h, hb, [f for g in groups for f in g], dist_min=hb, dist_max=max(2 * hb, rmax + h))
        gmsh.model.mesh.generate(3)
        gmsh.option.setNumber("Mesh.SecondOrderLinear", 1)
        for _ in range(cfg.mesh.refine):
            gmsh.model.mesh.refine()
        n_nodes = len(gmsh.model.mesh.getNodes()[0])
        n_tets = sum(len(x) for x in gmsh.model.mesh.getElements(3)[1])
        if n_tets == 0:
            raise MeshingError(f"{file}: gmsh produced no tetrahedra")
        write_msh(gmsh, path)
    info = {"source": "step", "file": file, "unit": "STEP file's own, converted to m", "solids": n_solids,
            "volume_m3": volume, "bbox_m": [list(bbox[:3]), list(bbox[3:])], "boundary_faces": len(faces),
            "fixed_faces": len(fixed), "bore_faces": [len(g) for g in groups]}
    _log(info, bores)
    hm = HousingMesh(path, BASE_TAG, tuple(BORE_TAG0 + k for k in range(len(bores))), VOLUME_TAG,
                     n_nodes, n_tets, time.perf_counter() - t0)
    return ImportedHousing(hm, bores, info)


def face_samples(gmsh, tag: int) -> np.ndarray:
    """Points on an OCC face: a parametric grid over its bounds plus its vertices."""
    lo, hi = gmsh.model.getParametrizationBounds(2, tag)
    uu, vv = np.meshgrid(np.linspace(lo[0], hi[0], _SAMPLES), np.linspace(lo[1], hi[1], _SAMPLES))
    pts = np.asarray(gmsh.model.getValue(2, tag, np.column_stack([uu.ravel(), vv.ravel()]).ravel())).reshape(-1, 3)
    verts = gmsh.model.getBoundary([(2, tag)], combined=False, oriented=False, recursive=True)
    vx = [gmsh.model.getValue(0, abs(t), []) for d, t in verts if d == 0]
    return np.vstack([pts] + [np.asarray(v).reshape(1, 3) for v in vx])


def _log(info: dict, bores) -> None:
    log.info("housing %s %s: %s; bores %s", info["source"], info["file"],
             ", ".join(f"{k} = {v}" for k, v in info.items() if k not in ("source", "file")),
             ", ".join(f"{b.name} at {np.round(b.center, 6).tolist()}" for b in bores) or "none")


# ----------------------------------------------------------------------------- FE meshes (meshio)

def read_tet_mesh(file: str | Path, unit: float = 1.0) -> tuple[np.ndarray, np.ndarray, dict]:
    """(x (N, 3) in m, tets (n, 4) 0-based vertex rows, info) of a 4- or 10-node tetrahedral mesh
    read with meshio (Abaqus .inp, Nastran .bdf, Gmsh .msh, VTU, XDMF); nodes not used by a
    tetrahedron vertex (10-node mid-side nodes) are dropped."""
    import meshio

    file = str(file)
    try:
        m = meshio.read(file)
    except Exception as exc:  # meshio raises ReadError, KeyError, ValueError... on bad files
        raise ConfigError("housing.file", f"{file}: meshio cannot read it ({type(exc).__name__}: {exc})") from None
    kinds = {}
    tets = []
    for cb in m.cells:
        kinds[cb.type] = kinds.get(cb.type, 0) + len(cb.data)
        if cb.type in ("tetra", "tetra10"):
            tets.append(np.asarray(cb.data[:, :4], dtype=np.int64))
    solid = [k for k in kinds if k in ("hexahedron", "hexahedron20", "hexahedron27", "wedge", "wedge15",
                                      "pyramid", "pyramid13")]
    if not tets:
        raise ConfigError("housing.file", f"{file}: no tetrahedra (cell blocks: "
                          f"{', '.join(f'{k} x {n}' for k, n in kinds.items()) or 'none'})")
    if solid:
        raise ConfigError("housing.file", f"{file}: only tetrahedral meshes are supported; it also holds "
                          f"{', '.join(f'{k} x {kinds[k]}' for k in solid)}")
    tets = np.vstack(tets)
    used, inv = np.unique(tets, return_inverse=True)
    x = np.asarray(m.points, dtype=float)
    if x.shape[1] != 3:
        raise ConfigError("housing.file", f"{file}: needs 3D points, got {x.shape[1]} coordinates")
    x = x[used] * unit
    tets = inv.reshape(-1, 4)
    e = x[tets[:, 1:]] - x[tets[:, :1]]
    vol = np.abs(np.linalg.det(e)) / 6.0
    h3 = np.ptp(x, axis=0).max() ** 3
    if np.any(vol <= 1e-14 * h3):
        raise ConfigError("housing.file", f"{file}: {int(np.sum(vol <= 1e-14 * h3))} degenerate (zero-volume) "
                          "tetrahedra")
    info = {"cells": kinds, "nodes_read": int(len(m.points)), "volume_m3": float(vol.sum())}
    return x, tets, info


def _boundary_facets(tets: np.ndarray) -> np.ndarray:
    faces = tets[:, [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]]].reshape(-1, 3)
    key = np.sort(faces, axis=1)
    _, idx, cnt = np.unique(key, axis=0, return_index=True, return_counts=True)
    return faces[idx[cnt == 1]]


def build_imported_mesh(cfg: HousingConfig, path: str | Path) -> ImportedHousing:
    """Read ``cfg.file`` (a tetrahedral FE mesh), tag the clamped and bore facets, write ``path``."""
    path, file = Path(path), str(cfg.file)
    t0 = time.perf_counter()
    x, tets, info = read_tet_mesh(file, LENGTH_UNITS[cfg.length_unit])
    facets = _boundary_facets(tets)
    samples = x[facets]                                   # (k, 3, 3): every triangle's vertices
    scale = float(np.linalg.norm(np.ptp(x, axis=0)))
    bores, groups = select_bores(cfg, samples, file, scale)
    fixed = fixed_faces(cfg, samples, groups, file)
    tagged = [(BASE_TAG, facets[fixed])] if fixed else []
    tagged += [(BORE_TAG0 + k, facets[g]) for k, g in enumerate(groups)]
    write_tagged_msh(path, x, tets, tagged)
    info = {"source": "mesh", "file": file, "unit": cfg.length_unit, **info,
            "bbox_m": [x.min(axis=0).tolist(), x.max(axis=0).tolist()], "boundary_faces": len(facets),
            "fixed_faces": len(fixed), "bore_faces": [len(g) for g in groups]}
    _log(info, bores)
    hm = HousingMesh(path, BASE_TAG, tuple(BORE_TAG0 + k for k in range(len(bores))), VOLUME_TAG,
                     len(x), len(tets), time.perf_counter() - t0)
    return ImportedHousing(hm, bores, info)


def write_tagged_msh(path: str | Path, x: np.ndarray, tets: np.ndarray,
                     tagged: list[tuple[int, np.ndarray]]) -> Path:
    """Write linear tetrahedra (group VOLUME_TAG) and tagged triangles (one physical group per
    (tag, facets) pair) as gmsh .msh 4.1 through gmsh's discrete entities."""
    path = Path(path)
    with gmsh_session(False) as gmsh:
        gmsh.model.add("imported")
        gmsh.model.addDiscreteEntity(3, 1)
        gmsh.model.mesh.addNodes(3, 1, np.arange(1, len(x) + 1), np.ascontiguousarray(x).ravel())
        gmsh.model.mesh.addElementsByType(1, 4, np.arange(1, len(tets) + 1), (tets + 1).ravel())
        gmsh.model.addPhysicalGroup(3, [1], VOLUME_TAG)
        next_el = len(tets) + 1
        for k, (tag, f) in enumerate(tagged):
            ent = gmsh.model.addDiscreteEntity(2, k + 1)
            gmsh.model.mesh.addElementsByType(ent, 2, np.arange(next_el, next_el + len(f)), (f + 1).ravel())
            next_el += len(f)
            gmsh.model.addPhysicalGroup(2, [ent], tag)
        write_msh(gmsh, path)
    return path


# ----------------------------------------------------------------------------- dispatch and layout file

_LAYOUT = "bores.json"


def build_mesh(cfg: HousingConfig, path: str | Path) -> HousingMesh:
    """The tagged .msh of any meshed source (parametric, step, mesh); an imported housing's bore
    layout and import summary are written beside it (``bores.json``, read by :func:`mesh_bores`)."""
    from .housing import build_housing_mesh

    if cfg.source == "parametric":
        if cfg.mesh.element == "hex":
            from .housing_hex import build_hex_housing_mesh
            return build_hex_housing_mesh(cfg, path)
        return build_housing_mesh(cfg, path)
    if cfg.source == "step":
        res = build_step_mesh(cfg, path)
    elif cfg.source == "mesh":
        res = build_imported_mesh(cfg, path)
    else:
        raise ValueError(f"source {cfg.source!r} has no mesh")
    save_layout(res.mesh.path.parent / _LAYOUT, res.bores, res.info)
    return res.mesh


def save_layout(path: Path, bores, info: dict) -> None:
    import dataclasses
    import json

    path.write_text(json.dumps({"bores": [dataclasses.asdict(b) for b in bores], "info": info}, indent=1))


def _read_layout(hm: HousingMesh) -> dict:
    import json

    return json.loads((Path(hm.path).parent / _LAYOUT).read_text())


def mesh_bores(cfg: HousingConfig, hm: HousingMesh) -> tuple[BoreGeometry, ...]:
    """The bore layout of the mesh ``hm``: from the config (parametric) or its ``bores.json``."""
    from .housing import bore_layout

    if cfg.source == "parametric":
        return bore_layout(cfg)
    out = []
    for d in _read_layout(hm)["bores"]:
        d.update({k: tuple(d[k]) for k in ("center", "axis", "y_range")})
        out.append(BoreGeometry(**d))
    return tuple(out)


def mesh_info(cfg: HousingConfig, hm: HousingMesh) -> dict:
    """What an imported mesh was made from (file, unit, solids, faces per group, ...); {} otherwise."""
    return {} if cfg.source == "parametric" else _read_layout(hm)["info"]
