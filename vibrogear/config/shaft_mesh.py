"""Shafts meshed for you: sections split so that a node lies at every feature.

A shaft is given by its sections (length, outer and inner diameter) and the positions of its
features (gears, bearings, couplings, discs).  :func:`mesh_sections` returns the sections
split at every feature position, each piece cut into the fewest elements no longer than
``max_element`` (default :data:`MAX_ELEMENT_LENGTH`): so a node lies at every section change
and every feature, and no Timoshenko element is longer than the limit.  Positions closer
than :data:`MERGE_TOL` to an existing node are taken as that node.
"""
from __future__ import annotations

import math

__all__ = ["mesh_sections", "MAX_ELEMENT_LENGTH", "MERGE_TOL"]

#: longest element a meshed shaft gets [m]
MAX_ELEMENT_LENGTH = 0.02
#: feature positions closer than this to a node are that node [m]
MERGE_TOL = 1e-6


def mesh_sections(sections: list[dict], features, *, max_element: float = MAX_ELEMENT_LENGTH,
                  path: str = "sections") -> list[dict]:
    """``sections``: dicts with ``length``, ``outer_diameter``, ``inner_diameter`` (and any
    other keys, kept); ``features``: positions [m] from the shaft's start.  Returns the split
    sections with ``elements``.  A feature off the shaft is left to the check that places
    it (it names the feature's own field)."""
    total = sum(s["length"] for s in sections)
    cuts = sorted({0.0, total, *(float(x) for x in features if x is not None)})
    out: list[dict] = []
    start = 0.0
    for s in sections:
        end = start + s["length"]
        inner = [x for x in cuts if start + MERGE_TOL < x < end - MERGE_TOL]
        edges = [start, *inner, end]
        for a, b in zip(edges[:-1], edges[1:]):
            piece = dict(s)
            piece["length"] = round(b - a, 12)
            piece["elements"] = max(1, math.ceil(piece["length"] / max_element - 1e-9))
            out.append(piece)
        start = end
    return out
