"""The housing's modes for the housing verbs (``modes``, ``housing_convergence``): the FE
modal solve (:func:`~vibrogear.models.housing.run.housing_modes`) with a meshing or solver
failure turned into a :class:`~vibrogear.pipeline.outcome.NumericalFailure` (exit 1), in one
place that neither verb's module owns.
"""
from __future__ import annotations

from ...pipeline.outcome import NumericalFailure

__all__ = ["compute_modes"]


def compute_modes(cfg, *, cache: bool = True):
    """housing_modes with geometry/solver failures turned into NumericalFailure (exit 1)."""
    from ...geometry.housing import MeshingError
    from ...models.housing.fe import HousingSolveError
    from ...models.housing.run import housing_modes

    try:
        return housing_modes(cfg, cache=cache)
    except (MeshingError, HousingSolveError) as exc:
        raise NumericalFailure(f"housing: {exc}") from None
