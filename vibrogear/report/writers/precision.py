"""Files and figures of the impact pair's ``report`` analysis (work-precision against the
exact solution, :mod:`vibrogear.analyses.precision`).

* ``work_precision.csv``, ``work_precision.png/.svg``: integrator error against rtol and
  work;
* ``shooting_precision.csv``, ``shooting_precision.png/.svg``: shooting error against its
  tolerance and work.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..figure import save_figure
from ..plots.precision import plot_shooting_precision, plot_work_precision, write_table

__all__ = ["write"]


def _columns(table: dict) -> tuple[str, ...]:
    """The table's columns: its array entries, in their order (scalars are not columns)."""
    return tuple(k for k, v in table.items() if np.ndim(v) == 1)


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    out = Path(out)
    files = {"work_precision_csv": str(write_table(out / "work_precision.csv", r.wp, _columns(r.wp))),
             "shooting_precision_csv": str(write_table(out / "shooting_precision.csv", r.sh,
                                                       _columns(r.sh)))}
    save_figure(plot_work_precision(r.wp, r.slopes, title=r.wp_title), out / "work_precision")
    save_figure(plot_shooting_precision(r.sh, title=r.sh_title), out / "shooting_precision")
    files["work_precision_png"] = str(out / "work_precision.png")
    files["shooting_precision_png"] = str(out / "shooting_precision.png")
    return files
