"""The ``sweep`` wing: sequential continuation and the branches started from it.

Its public names are those of :mod:`.sweep`, imported on first use (so that importing a
helper of the wing does not load the whole wing).  Its modules:

- ``sweep``: Sequential continuation over the study's parameter (paper Fig. 2), resumable.
- ``branches``: Period-n branches started from a sweep (``[continuation] from_sweep = true``).
"""

from ...lazy import lazy_exports

__all__ = ["SweepStudyResult", "run", "resumable_sweep", "jumps", "PARTIAL_NAME", "motion_summary"]

__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(__all__, "sweep"))
