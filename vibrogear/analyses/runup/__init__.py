"""The ``runup`` wing: run-up / run-down transients and their order tracking.

Its public names are those of :mod:`.runup`, imported on first use (so that importing a
helper of the wing does not load the whole wing).  Its modules:

- ``runup``: Run-up and run-down transients (``vibrogear runup``, section [runup]).
- ``order_tracking``: Computed order tracking and the waterfall of a signal under a varying
  speed.
"""

__all__ = ["RunupResult", "RunupRun", "run", "shaft_orders", "period_table", "jump_speed",
           "run_key", "inertia_effect", "MAX_RUNUP_BYTES", "runup_arrays"]


def __getattr__(name: str):
    if name in __all__:
        from . import runup
        return getattr(runup, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
