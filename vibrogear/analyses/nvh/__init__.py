"""The ``nvh`` wing: spectra of the steady response, their line sources, the housing's
radiated power.

Its public names are those of :mod:`.nvh`, imported on first use (so that importing a
helper of the wing does not load the whole wing).  Its modules:

- ``nvh``: ``nvh``: spectra of the steady response over speed and the housing's radiated power.
- ``housing_surface``: The housing's outer-surface normal velocity from the reduced model's
  housing coordinates, and its equivalent radiated power (ERP).
- ``line_sources``: The sources of a gearbox's spectral lines, and each nvh steady point's lines
  and evidence.
"""

from ...lazy import lazy_exports

__all__ = ["NvhResult", "BranchSpectra", "run", "steady_points", "order_lines", "branch_spectra",
           "operating_shape"]

__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(__all__, "nvh"))
