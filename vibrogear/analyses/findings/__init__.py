"""The findings wing: the run's speed bands and verdict, and two runs' findings compared.

Its public names are those of :mod:`.findings`, imported on first use (so that importing a
helper of the wing does not load the whole wing).  Its modules:

- ``findings``: Findings: where the gearbox loses contact, rattles, jumps or goes chaotic, and
  which speeds to avoid, derived from the files a run wrote.
- ``bands``: Speed bands of a sweep: contact loss, rattle, double-sided impacts, bearing
  unloading, motion classes, hysteresis (:mod:`vibrogear.analyses.findings.findings` explains
  the band).
- ``compare``: Two runs' findings side by side (``vibrogear compare RUN_A RUN_B``): the
  engineer's next step after a design change.
- ``events``: Findings from the continuation (special points), the modes (resonance speeds), the
  ERP (peak and the bands above a level) and the census of coexisting states.
- ``iso_resonance``: The resonance speed of each gear pair by ISO 6336-1:2006 (6.5, method B)
  and its main resonance range, as the standard computes them from the gear data.
- ``text``: The verdict of the findings in one sentence, and the speed ranges of a set of bands
  in plain words.
"""

from ...lazy import lazy_exports

__all__ = ["derive_findings", "run_findings", "read_sources", "SOURCE_FILES", "Band", "mesh_roles",
           "windows", "mesh_summary"]

__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(__all__, "findings"))
