"""Mesh-size fields of the housing meshes (gmsh): finer towards the bearing bores and,
optionally (``[housing.mesh] edge_size``), towards the re-entrant junction edges of the
solid, where the frequencies converge slowly (docs/housing.md)."""
from __future__ import annotations

import math

import numpy as np

from ..config.model.housing import HousingConfig

__all__ = ["size_field", "junction_curves"]


def add_size_field(gmsh, cfg: HousingConfig, bore_surfs: list[int]) -> None:
    rings = [b.boss_radius - b.bore_radius for b in cfg.bores]
    edges = None
    if cfg.edge_mesh_size is not None:
        edges = (junction_curves(gmsh), cfg.edge_mesh_size, cfg.edge_mesh_distance)
    size_field(gmsh, cfg.mesh_size, cfg.bore_mesh_size, bore_surfs, dist_min=0.25 * max(rings),
               dist_max=max(b.boss_radius for b in cfg.bores), edges=edges)


def junction_curves(gmsh, *, step: float = 1e-4) -> list[int]:
    """The re-entrant (concave) edges of the synchronized OCC solid: the curves where two faces
    meet with the solid on more than half of the space around them (wall/base, wall/wall inside
    the box, rib/wall, rib/base, boss/wall), where the elastic fields are singular (~ r^0.54).

    Per curve, at its parametric middle: outward normals n1, n2 of its two faces (OCC orients
    a solid's faces outwards) and the direction d1 from the curve into face 1 (perpendicular to
    the curve, checked on the trimmed face); concave where d1 . n2 > 0.  Seams and curves of one
    face are skipped."""
    m = gmsh.model
    out = []
    for _, c in m.getEntities(1):
        faces, _ = m.getAdjacencies(1, c)
        if len(faces) != 2:
            continue
        lo, hi = m.getParametrizationBounds(1, c)
        u = 0.5 * (lo[0] + hi[0])
        p = np.array(m.getValue(1, c, [u]))
        tan = np.array(m.getDerivative(1, c, [u]))
        if np.linalg.norm(tan) == 0:
            continue
        tan /= np.linalg.norm(tan)
        normals, d1 = [], None
        for i, f in enumerate(faces):
            n = np.array(m.getNormal(f, m.getParametrization(2, f, list(p))))
            normals.append(n / np.linalg.norm(n))
            if i == 0:
                d = np.cross(normals[0], tan)
                for sg in (1.0, -1.0):
                    q = p + step * sg * d
                    try:
                        uv = m.getParametrization(2, f, list(q))
                        on = m.isInside(2, f, uv) and np.linalg.norm(np.array(m.getValue(2, f, uv)) - q) < 1e-2 * step
                    except Exception:  # gmsh: inverse mapping did not converge (off the face)
                        on = False
                    if on:
                        d1 = sg * d
                        break
        if d1 is None or abs(normals[0] @ normals[1]) > 0.999:  # tangent faces: no corner
            continue
        if d1 @ normals[1] > 1e-3:
            out.append(c)
    return out


def size_field(gmsh, h: float, hb: float, bore_surfs: list[int], *, dist_min: float, dist_max: float,
               edges: tuple[list[int], float, float] | None = None) -> None:
    """The element-size rules of every meshed housing: size ``h``, ``hb`` within ``dist_min`` of the
    bore surfaces' edges, growing linearly to ``h`` at ``dist_max``.  ``edges = (curves, he, d)``:
    also size ``he`` on those curves (the junction edges), growing linearly to ``h`` at distance
    ``d``; the smaller size wins."""
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    smallest = min(hb, h) if edges is None or not edges[0] else min(hb, h, edges[1])
    gmsh.option.setNumber("Mesh.MeshSizeMin", smallest * 0.5)
    fields = []
    field = gmsh.model.mesh.field
    if bore_surfs:
        curves = gmsh.model.getBoundary([(2, s) for s in bore_surfs], combined=False, oriented=False)
        fd = field.add("Distance")  # gmsh 4.8 samples curves, not surfaces
        field.setNumbers(fd, "CurvesList", sorted({abs(c) for _, c in curves}))
        field.setNumber(fd, "NumPointsPerCurve", 80)
        fields.append(_threshold(field, fd, hb, h, dist_min, dist_max))
    if edges is not None and edges[0]:
        curves, he, de = edges
        longest = max(gmsh.model.occ.getMass(1, c) for c in curves)    # curve lengths
        fd = field.add("Distance")
        field.setNumbers(fd, "CurvesList", sorted(curves))
        # samples <= he / 2 apart on the longest curve: the distance is exact to he / 4 there
        field.setNumber(fd, "NumPointsPerCurve", int(min(2000, max(80, math.ceil(2 * longest / he) + 1))))
        fields.append(_threshold(field, fd, he, h, 0.0, de))
    if not fields:
        return
    if len(fields) > 1:
        fm = field.add("Min")
        field.setNumbers(fm, "FieldsList", fields)
        fields = [fm]
    field.setAsBackgroundMesh(fields[0])


def _threshold(field, fd: int, size_min: float, size_max: float, dist_min: float, dist_max: float) -> int:
    ft = field.add("Threshold")
    field.setNumber(ft, "InField", fd)
    field.setNumber(ft, "SizeMin", size_min)
    field.setNumber(ft, "SizeMax", size_max)
    field.setNumber(ft, "DistMin", dist_min)
    field.setNumber(ft, "DistMax", dist_max)
    return ft
