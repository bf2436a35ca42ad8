"""The ``runup`` wing: run-up / run-down transients and their order tracking.

Its public names are those of :mod:`.runup`, imported on first use (so that importing a
helper of the wing does not load the whole wing).  Its modules:

- ``runup``: Run-up and run-down transients (``vibrogear runup``, section [runup]).
- ``order_tracking``: Computed order tracking and the waterfall of a signal under a varying
  speed.
"""

from ...lazy import lazy_exports

__all__ = ["RunupResult", "RunupRun", "run", "shaft_orders", "period_table", "jump_speed",
           "run_key", "inertia_effect", "MAX_RUNUP_BYTES", "runup_arrays"]

__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(__all__, "runup"))
