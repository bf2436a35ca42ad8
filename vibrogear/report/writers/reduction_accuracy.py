"""Files and figures of the ``reduction_accuracy`` analysis
(:mod:`vibrogear.analyses.reduction_accuracy`).

* ``reduction_levels.csv`` / ``reduction_levels.json``: a row per reduction level;
* ``reduction_modes.csv`` (and ``reduction_modes_frequency.csv`` with ``frequency_level``):
  full vs reduced frequency and MAC per mode;
* ``reduction_accuracy.png/.svg``: error against run time per level.
"""
from __future__ import annotations

from pathlib import Path

from ..figure import save_figure
from ..plots.reduction_accuracy import plot_reduction_study, write_reduction_tables

__all__ = ["write"]


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    out = Path(out)
    rows, extra = list(r.rows), list(r.extra)
    paths = write_reduction_tables(out, rows, extra)
    save_figure(plot_reduction_study(rows + extra, title=r.title), out / "reduction_accuracy")
    files = {k: str(v) for k, v in paths.items()}
    files["png"] = str(out / "reduction_accuracy.png")
    return files
