"""The ``sweep`` wing: sequential continuation and the branches started from it.

Its public names are those of :mod:`.sweep`, imported on first use (so that importing a
helper of the wing does not load the whole wing).  Its modules:

- ``sweep``: Sequential continuation over the study's parameter (paper Fig. 2), resumable.
- ``branches``: Period-n branches started from a sweep (``[continuation] from_sweep = true``).
"""

__all__ = ["SweepStudyResult", "run", "resumable_sweep", "jumps", "PARTIAL_NAME", "motion_summary"]


def __getattr__(name: str):
    if name in __all__:
        from . import sweep
        return getattr(sweep, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
