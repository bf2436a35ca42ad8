"""Files and figure of a sweep (any study): ``sweep.npz``, ``sweep.csv`` and the
bifurcation diagram ``bifurcation.png/.svg`` in the monitored quantity's display unit; when
the scene ran ``continuation`` before, also the branch figures with the sweep points and
``bifurcation_branches.png/.svg`` (the bifurcation diagram with the branches overlaid)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .sweep_io import read_sweep_npz, write_sweep
from .sweep_plots import plot_bifurcation

__all__ = ["write", "display_arrays", "draw_bifurcation"]


def display_arrays(data: dict, scale: float, keys=("qmin", "qmax", "poincare")) -> dict:
    """A copy of ``data`` with the monitored-quantity arrays in display units."""
    out = dict(data)
    for k in keys:
        if k in out:
            out[k] = np.asarray(data[k], dtype=float) * scale
    return out


def draw_bifurcation(data: dict, study, path, branches: dict | None = None) -> list[Path]:
    """The bifurcation diagram of sweep arrays ``data`` (display units) to ``path``, with
    continuation branch arrays (display units) overlaid when given."""
    mon = study.monitor
    lines = mon.lines
    if mon.zero_line and lines:      # the back-flank line only when the motion nears it
        near = np.nanmin(data["qmin"], initial=0.0) < 0.5 * min(lines)
        lines = lines if near else ()
    below = ": below 0 the mesh is interrupted" if mon.zero_line else ""
    title = study.title + below
    if branches is not None:
        title += "\nsweep points with the continuation branches"
    return plot_bifurcation(data, path, param_label=study.param_label,
                            deformation_label=mon.axis_label(), zero_line=mon.zero_line,
                            bounds=lines, title=title, branches=branches,
                            energy_unit=study.energy_unit)


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    study = r.study
    paths = write_sweep(r.sweep, out)
    data = display_arrays(read_sweep_npz(paths["npz"]), study.monitor.scale)
    draw_bifurcation(data, study, Path(out) / "bifurcation")
    files = {k: str(v) for k, v in paths.items()}
    files["png"] = str(Path(out) / "bifurcation.png")
    branch = (previous or {}).get("continuation")
    if branch is not None:
        from .branch_report import plot_branch_figures, plot_combined
        plot_branch_figures(branch.result, out, sweep=r)
        files["branches_png"] = str(plot_combined(branch.result, out, data)[0])
    return files
