"""The ``map`` wing: the speed x load operating map and its fold / period-doubling curves.

Its public names are those of :mod:`.map`, imported on first use (so that importing a
helper of the wing does not load the whole wing).  Its modules:

- ``map``: Speed x load operating map of a gearbox (``vibrogear map SCENE``, section [map]).
- ``curves``: Fold (LP) and period-doubling (PD) curves of the period-1 branch in the (speed,
  load) plane.
- ``load_scaling``: The static load of a gearbox as one number: the transmitted input torque.
"""

from ...lazy import lazy_exports

__all__ = ["OperatingMap", "run", "compute_map", "PARTIAL_NAME", "grid_array", "map_arrays",
           "METRICS_PER_MESH"]

__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(__all__, "map"))
