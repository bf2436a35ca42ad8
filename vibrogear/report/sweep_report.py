"""Files and figure of a sweep (any study): ``sweep.npz``, ``sweep.csv`` and the
bifurcation diagram ``bifurcation.png/.svg`` in the monitored quantity's display unit, with
the continuation branches overlaid when the scene ran ``continuation`` before."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .sweep_io import read_sweep_npz, write_sweep
from .sweep_plots import plot_bifurcation

__all__ = ["write", "display_arrays"]


def display_arrays(data: dict, scale: float, keys=("qmin", "qmax", "poincare")) -> dict:
    """A copy of ``data`` with the monitored-quantity arrays in display units."""
    out = dict(data)
    for k in keys:
        if k in out:
            out[k] = np.asarray(data[k], dtype=float) * scale
    return out


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    study = r.study
    mon = study.monitor
    paths = write_sweep(r.sweep, out)
    data = display_arrays(read_sweep_npz(paths["npz"]), mon.scale)
    lines = mon.lines
    if mon.zero_line and lines:      # the back-flank line only when the motion nears it
        near = np.nanmin(data["qmin"], initial=0.0) < 0.5 * min(lines)
        lines = lines if near else ()
    below = ": below 0 the mesh is interrupted" if mon.zero_line else ""
    plot_bifurcation(data, Path(out) / "bifurcation", param_label=study.param_label,
                     deformation_label=mon.axis_label(), zero_line=mon.zero_line,
                     bounds=lines, title=study.title + below)
    files = {k: str(v) for k, v in paths.items()}
    files["png"] = str(Path(out) / "bifurcation.png")
    branch = (previous or {}).get("continuation")
    if branch is not None:
        from .branch_report import plot_branch_figures
        plot_branch_figures(branch.result, out, sweep=r)
    return files
