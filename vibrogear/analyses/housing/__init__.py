"""The housing wing: the verbs of a housing scene and what they share.

- ``modes``: ``modes`` of a housing scene (master modes and coupling values).
- ``convergence``: ``housing_convergence``: frequency error against DOF and run time, P1 and
  P2.
- ``sweep``: ``housing_sweep``: first frequencies against one housing parameter.
- ``compute``: the housing's modal solve with meshing and solver failures as
  ``NumericalFailure``, shared by ``modes`` and ``convergence``.

The verb registry names each verb's module (``housing.modes:run_modes``, ...); their public
functions are also names of the wing, imported on first use.
"""

from ...lazy import lazy_exports

#: public name -> the module of the wing that defines it
_NAMES = {"run_modes": "modes", "modes_summary": "modes", "run_convergence": "convergence",
          "run_sweep": "sweep", "HousingSweepResult": "sweep", "compute_modes": "compute"}
__all__ = list(_NAMES)

__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
