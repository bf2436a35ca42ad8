"""Files and figures of a continuation (any study): ``branch.npz``, ``branch.csv`` and the
branch figures ``branch_max.png`` / ``branch_min.png`` (maxima and minima of the monitored
quantity along the branches, stable solid, unstable dashed, LP/PD/NS marked) in its display
unit, with the sweep points overlaid when the scene ran ``sweep`` before; with a sweep (run
before in the same scene, or its ``sweep.npz`` already in the output folder) also
``bifurcation_branches.png/.svg``: the sweep's bifurcation diagram (points up and down,
motion-class band, impacts per period of each mesh, rattle intensity) with the branches
overlaid (stable solid, unstable dashed, LP / PD / NS marked), and ``fig2.png/.svg``: the
seed's Fig. 2 (sweep minima / maxima, zero line, branches, motion-class band; :mod:`.fig2`)."""
from __future__ import annotations

from pathlib import Path

from ..plots.bifurcation import display_arrays, plot_branch_figures, plot_combined
from ..branch_files import write_branches
from .fig2 import write_fig2
from ..sweep_files import read_sweep_npz, sweep_arrays

__all__ = ["write", "plot_branch_figures", "plot_combined"]


def _sweep_of(previous, out, study):
    """Display arrays of the sweep run before in this scene, else of a ``sweep.npz`` in
    ``out`` over the same parameter, else None."""
    sweep = (previous or {}).get("sweep")
    if sweep is not None:
        return display_arrays(sweep_arrays(sweep.result.sweep), study.monitor.scale)
    path = Path(out) / "sweep.npz"
    if path.is_file():
        data = read_sweep_npz(path)
        if str(data.get("param_name", study.model.param_name)) == study.model.param_name:
            return display_arrays(data, study.monitor.scale)
    return None


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    paths = write_branches(r, out)
    data = _sweep_of(previous, out, r.study)
    plot_branch_figures(r, out, sweep_data=data)
    files = {k: str(v) for k, v in paths.items()}
    files["png"] = [str(Path(out) / "branch_max.png"), str(Path(out) / "branch_min.png")]
    if data is not None:
        rows = scene.figures.motion_rows_per_contact
        files["branches_png"] = str(plot_combined(r, out, data, per_contact_rows=rows)[0])
        files["fig2_png"] = str(write_fig2(r, out, data, per_contact_rows=rows)[0])
    return files
