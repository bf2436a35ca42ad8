"""Files and figures of a continuation (any study): ``branch.npz``, ``branch.csv`` and the
branch figures ``branch_max.png`` / ``branch_min.png`` (maxima and minima of the monitored
quantity along the branches, stable solid, unstable dashed, LP/PD/NS marked) in its display
unit, with the sweep points overlaid when the scene ran ``sweep`` before."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .branch_io import branch_arrays, write_branches
from .branch_plots import plot_branches
from .sweep_io import sweep_arrays
from .sweep_report import display_arrays

__all__ = ["write", "plot_branch_figures"]


def plot_branch_figures(result, out, sweep=None) -> list[Path]:
    """Both branch figures; ``sweep``: a sweep analysis' result to overlay."""
    study = result.study
    mon = study.monitor
    arrays = display_arrays(branch_arrays(result.branches, study.model.omega_per_param),
                            mon.scale, ("qmin", "qmax"))
    sw = None if sweep is None else display_arrays(sweep_arrays(sweep.sweep), mon.scale)
    lines = tuple(mon.lines)
    if mon.zero_line:
        near = bool(lines) and np.nanmin(arrays["qmin"], initial=0.0) < 0.5 * min(lines)
        lines = (0.0,) + (lines if near else ())
    paths = []
    for q, lab in (("qmax", "max"), ("qmin", "min")):
        paths += plot_branches(arrays, Path(out) / f"branch_{lab}", quantity=q,
                               ylabel=mon.axis_label(lab), xlabel=study.param_label,
                               title=study.title, sweep=sw, bounds=lines)
    return paths


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    paths = write_branches(r.branches, r.study.model.omega_per_param, out)
    sweep = (previous or {}).get("sweep")
    plot_branch_figures(r, out, sweep=None if sweep is None else sweep.result)
    files = {k: str(v) for k, v in paths.items()}
    files["png"] = [str(Path(out) / "branch_max.png"), str(Path(out) / "branch_min.png")]
    return files
