"""Files and figure of a sweep (any study): ``sweep.npz``, ``sweep.csv`` and the
bifurcation diagram ``bifurcation.png/.svg`` in the monitored quantity's display unit; when
the scene ran ``continuation`` before, also the branch figures with the sweep points and
``bifurcation_branches.png/.svg`` (the bifurcation diagram with the branches overlaid)."""
from __future__ import annotations

from pathlib import Path

from ..plots.bifurcation import (display_arrays, draw_bifurcation, plot_branch_figures,
    plot_combined)
from ..sweep_files import read_sweep_npz, write_sweep

__all__ = ["write", "display_arrays", "draw_bifurcation"]


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    study = r.study
    paths = write_sweep(r.sweep, out, param_unit=study.param_unit,
                        length_unit=study.length_unit, time_unit_s=study.model.time_unit_s)
    data = display_arrays(read_sweep_npz(paths["npz"]), study.monitor.scale)
    rows = scene.figures.motion_rows_per_contact
    draw_bifurcation(data, study, Path(out) / "bifurcation", per_contact_rows=rows)
    files = {k: str(v) for k, v in paths.items()}
    files["png"] = str(Path(out) / "bifurcation.png")
    branch = (previous or {}).get("continuation")
    if branch is not None:
        plot_branch_figures(branch.result, out, sweep=r)
        files["branches_png"] = str(plot_combined(branch.result, out, data,
                                                  per_contact_rows=rows)[0])
    return files
