"""Shafts meshed for you: sections split so that a node lies at every feature.

A shaft is given by its sections (length, outer and inner diameter) and the positions of its
features (gears, bearings, couplings, discs).  :func:`mesh_sections` returns the sections
split at every feature position, each piece cut into the fewest elements no longer than
``max_element`` (default :data:`MAX_ELEMENT_LENGTH`): so a node lies at every section change
and every feature, and no Timoshenko element is longer than the limit.  Positions closer
than :data:`MERGE_TOL` to an existing node are taken as that node.  A shaft whose sections
give element counts keeps them; :func:`with_nodes_at` only splits a section where a feature
falls between its nodes.
"""
from __future__ import annotations

import dataclasses
import math

from .rotor import POSITION_TOL, node_positions

__all__ = ["mesh_sections", "with_nodes_at", "MAX_ELEMENT_LENGTH", "MERGE_TOL"]

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


def with_nodes_at(sections, features) -> tuple:
    """Sections with element counts given, split where a feature lies between nodes: each
    piece keeps its share of the section's elements (at least 1), so a scene whose
    features all sit on nodes is unchanged."""
    nodes = node_positions(sections)
    length = nodes[-1]
    off = sorted({x for x in features if x is not None and 0.0 < x < length
                  and min(abs(n - x) for n in nodes) > POSITION_TOL * length})
    if not off:
        return tuple(sections)
    out, start = [], 0.0
    for sec in sections:
        end = start + sec.length
        cuts = [start, *(x for x in off if start < x < end), end]
        for a, b in zip(cuts[:-1], cuts[1:]):
            n = max(1, round(sec.elements * (b - a) / sec.length))
            out.append(dataclasses.replace(sec, length=b - a, elements=n))
        start = end
    return tuple(out)
