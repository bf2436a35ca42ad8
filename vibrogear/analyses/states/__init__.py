"""The ``states`` wing: every operating state at every speed (``vibrogear states``).

Its public names are those of :mod:`.states`, imported on first use (so that importing a
helper of the wing does not load the whole wing).  Its modules:

- ``states``: ``vibrogear states``: every operating state at every speed (section ``[states]``).
- ``branches``: Orbits and branches of the census's attractors, and what the sweep saw of them.
- ``cluster``: The settled motions of one parameter value grouped into attractors, with their
  basins (the rule, its reasons and the evidence behind it: docs/states.md).
- ``gaps``: A non-periodic group of census records split where its extrema fall into two clumps:
  distinct tori whose other statistics agree within their errors still differ in where their
  deformation turns (docs/states.md, "Grouping non-periodic motions").
- ``plan``: The census's work as one stream of units: starts, orbits and branches start as soon
  as what they need is there.
- ``starts``: The random starts of ``vibrogear states``: their scales and their reproducible
  draw.
- ``summary``: The ``states`` entry of ``summary.json``: what the census found, per grid value,
  in plain records the findings engine reads.
"""

from ...lazy import lazy_exports

__all__ = ["StatesResult", "run", "grid", "PARTIAL_NAME"]

__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(__all__, "states"))
