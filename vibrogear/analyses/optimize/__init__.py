"""The ``optimize`` wing: design optimisation over any ``--set`` key.

Its public names are those of :mod:`.optimize`, imported on first use (so that importing a
helper of the wing does not load the whole wing).  Its modules:

- ``optimize``: ``vibrogear optimize SCENE``: design optimisation over the scene's ``--set``
  keys ([optimize], :mod:`vibrogear.config.sections.optimize`).
- ``evaluate``: One evaluation of ``vibrogear optimize``: the scene with the variables set, its
  analyses run as the runner runs them (from the verb registry, :mod:`vibrogear.config.verbs`),
  and the objective and constraint metrics read from the returned outcomes.
- ``methods``: The search methods of ``vibrogear optimize``, all on the unit cube u in [0, 1]^n
  (each variable's range, or log range, mapped to [0, 1]; :class:`Space`).
"""

from ...lazy import lazy_exports

__all__ = ["OptimizeResult", "run", "PARTIAL_NAME", "penalised", "violation"]

__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(__all__, "optimize"))
