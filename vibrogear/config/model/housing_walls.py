"""The walls of the parametric housing that carry bores, and the bores' numbering.

The box has a *front* wall (y = 0 .. t) and a *back* wall (y = width - t .. width), t the
wall thickness.  ``[housing] inner_walls = [y1, y2, ...]`` adds inner walls parallel to them:
wall k occupies y = y_k - t/2 .. y_k + t/2 (y_k its middle plane, metres, ascending) and
spans the whole cavity (x = t .. length - t, z = t .. height - t), like the intermediate wall
of a coaxial gearbox that carries the bearings between the front and the back.

Every shaft axis (``[[housing.bores]]`` entry) is bored through every wall: the bore's
coupling points are grouped **per shaft, then per wall from front to back**:

    bore index = i * (n + 2) + j,   i = the entry in ``housing.bores``,
    j = 0 (front), 1 .. n (inner wall 1 .. n, ascending y), n + 1 (back),

with n = ``len(inner_walls)``; names ``<bore>/front``, ``<bore>/inner1`` .. ``<bore>/innerN``,
``<bore>/back``.  Without inner walls this is the numbering the housing always had (bore
2 i front, 2 i + 1 back).  A front or back bore runs through its boss (``boss_length``
outside the wall); an inner wall has no boss (a boss would reach into the gears' room): its
bore is the wall's thickness long, and its coupling points lie in the wall's middle plane.
"""
from __future__ import annotations

import math

from ..base import ConfigError

__all__ = ["bore_walls", "check_inner_walls", "check_wall_counts", "MIN_GAP_WALLS"]

#: neighbouring walls must leave a cavity at least this many wall thicknesses wide
MIN_GAP_WALLS = 1.0


def bore_walls(housing, bore) -> list[tuple[str, tuple[float, float], float, int]]:
    """(side, housing-frame y span of the bore, outward axis sign along y, coupling points) of
    each wall of ``bore``, front to back: ``front``, ``inner1`` .. ``innerN``, ``back``.
    Inner bores get the axis sign +1 (towards the back: an inner wall has no outside).  The
    points: ``bore.wall_rolling_elements`` (one per wall) where given, else
    ``bore.rolling_elements``."""
    t, W = housing.wall_thickness, housing.width
    spans = [("front", (-bore.boss_length, t), -1.0)]
    for k, y in enumerate(housing.inner_walls):
        spans.append((f"inner{k + 1}", (y - 0.5 * t, y + 0.5 * t), 1.0))
    spans.append(("back", (W - t, W + bore.boss_length), 1.0))
    counts = bore.wall_rolling_elements or (bore.rolling_elements,) * len(spans)
    return [(*s, n) for s, n in zip(spans, counts)]


def check_wall_counts(housing, path: str) -> None:
    """``bores[i].wall_rolling_elements``: empty or one count per wall (front, inner, back)."""
    n = len(housing.inner_walls) + 2
    for i, b in enumerate(housing.bores):
        if b.wall_rolling_elements and len(b.wall_rolling_elements) != n:
            raise ConfigError(f"{path}.bores[{i}].wall_rolling_elements", f"needs one count per wall "
                              f"(front, {len(housing.inner_walls)} inner, back): {n} entries, got "
                              f"{len(b.wall_rolling_elements)}")


def check_inner_walls(housing, path: str) -> None:
    """``inner_walls``: parametric tetrahedral housings only; finite, ascending, each wall
    wholly inside the cavity with at least :data:`MIN_GAP_WALLS` wall thicknesses of cavity on
    each side (to the front wall, to the back wall and between neighbours)."""
    if not housing.inner_walls:
        return
    if housing.source != "parametric":
        raise ConfigError(f"{path}.inner_walls", f"only for the parametric housing; a "
                          f"{housing.source!r} housing's walls are in its file")
    if housing.mesh.element == "hex":
        raise ConfigError(f"{path}.inner_walls", "not with mesh.element = 'hex': the structured hex "
                          "grid is built for a front and a back wall only; mesh a housing with inner "
                          "walls with element = 'tet'")
    t, W = housing.wall_thickness, housing.width
    gap = MIN_GAP_WALLS * t
    lo_face = t                                   # the inner face of the previous wall
    prev = "the front wall's inner face"
    for k, y in enumerate(housing.inner_walls):
        p = f"{path}.inner_walls[{k}]"
        if not math.isfinite(y):
            raise ConfigError(p, f"must be a finite number (the wall's middle plane y, m), got {y!r}")
        if not 0.0 < y < W:
            raise ConfigError(p, f"inner wall outside the housing: y must lie in (0, width) = "
                              f"(0, {W:g}) m, got {y:g}")
        if y - 0.5 * t - lo_face < gap:
            raise ConfigError(p, f"inner wall too close to {prev} (y = {lo_face:g} m): the cavity "
                              f"between must be >= {MIN_GAP_WALLS:g} x wall_thickness = {gap:g} m wide, "
                              f"so y >= {lo_face + gap + 0.5 * t:g}, got {y:g} (inner walls are "
                              "listed in ascending y and may not overlap)")
        lo_face, prev = y + 0.5 * t, f"inner_walls[{k}] (its back face)"
    if housing.inner_walls and W - t - lo_face < gap:
        k = len(housing.inner_walls) - 1
        raise ConfigError(f"{path}.inner_walls[{k}]", f"inner wall too close to the back wall (inner "
                          f"face y = {W - t:g} m): the cavity between must be >= {gap:g} m wide, so "
                          f"y <= {W - t - gap - 0.5 * t:g}, got {housing.inner_walls[k]:g}")
