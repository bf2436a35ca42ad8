"""Independent exact references used to verify the solvers (and the ``report`` analysis).

Nothing here imports :mod:`vibrogear.solvers`: a reference that shared code with what it
checks would not be a check.
"""
from .impact_exact import FlowResult, ImpactParams, exact_dense, exact_flow, exact_monodromy
from .impact_orbits import PeriodicOrbit, periodic_orbit

__all__ = ["ImpactParams", "FlowResult", "PeriodicOrbit", "exact_flow", "exact_dense",
           "exact_monodromy", "periodic_orbit"]
