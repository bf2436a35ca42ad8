"""The figures a sweep and a continuation share: the bifurcation diagram of sweep arrays
(optionally with branches overlaid), the branch figures ``branch_max`` / ``branch_min``
(optionally with sweep points overlaid) and ``bifurcation_branches`` (both in one figure).
Both writers, :mod:`..writers.sweep` and :mod:`..writers.continuation`, draw through this
module, so whichever of the two runs second draws the combined figure without importing the
other."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .branch import plot_branches
from ..figure import plain_title, save_figure
from ..sweep_files import sweep_arrays
from .sweep import plot_bifurcation

__all__ = ["display_arrays", "draw_bifurcation", "plot_branch_figures", "plot_combined",
           "bifurcation_figure", "sweep_figure", "branch_figure"]


def display_arrays(data: dict, scale: float, keys=("qmin", "qmax", "poincare")) -> dict:
    """A copy of ``data`` with the monitored-quantity arrays in display units."""
    out = dict(data)
    for k in keys:
        if k in out:
            out[k] = np.asarray(data[k], dtype=float) * scale
    return out


def draw_bifurcation(data: dict, study, path, branches: dict | None = None, *,
                     per_contact_rows: bool = False) -> list[Path]:
    """The bifurcation diagram of sweep arrays ``data`` (display units) to ``path``, with
    continuation branch arrays (display units) overlaid when given; ``per_contact_rows``:
    the scene's ``[figures] motion_rows_per_contact``."""
    return save_figure(bifurcation_figure(data, study, branches,
                                          per_contact_rows=per_contact_rows), path)


def sweep_figure(result, branches=None, *, per_contact_rows: bool = False):
    """The bifurcation diagram of a sweep (:class:`~vibrogear.analyses.sweep.sweep.SweepStudyResult`)
    as a Figure, the report's ``bifurcation.png``; ``branches``: a continuation's result to
    overlay (``bifurcation_branches.png``)."""
    study = result.study
    data = display_arrays(sweep_arrays(result.sweep), study.monitor.scale)
    arrays = None if branches is None else display_arrays(
        branches.arrays(), study.monitor.scale, ("qmin", "qmax"))
    fig = bifurcation_figure(data, study, arrays, per_contact_rows=per_contact_rows)
    fig.tight_layout()
    return fig


def bifurcation_figure(data: dict, study, branches: dict | None = None, *,
                       per_contact_rows: bool = False):
    """The Figure :func:`draw_bifurcation` saves."""
    mon = study.monitor
    lines = mon.lines
    if mon.zero_line and lines:      # the back-flank line only when the motion nears it
        near = np.nanmin(data["qmin"], initial=0.0) < 0.5 * min(lines)
        lines = lines if near else ()
    below = " (below 0: the teeth lose contact)" if mon.zero_line else ""
    title = f"{plain_title(study.title)}: response against speed, sweep up and down{below}"
    if branches is not None:
        title += "\nwith the continuation branches"
    return plot_bifurcation(data, param_label=study.param_label,
                            deformation_label=mon.axis_label(), zero_line=mon.zero_line,
                            bounds=lines, title=title, branches=branches,
                            energy_unit=study.energy_unit, per_contact_rows=per_contact_rows)


def plot_branch_figures(result, out, sweep=None, sweep_data=None) -> list[Path]:
    """Both branch figures; ``sweep``: a sweep analysis' result to overlay (or
    ``sweep_data``: its arrays in display units)."""
    paths = []
    for q, lab in (("qmax", "max"), ("qmin", "min")):
        paths += save_figure(branch_figure(result, q, sweep, sweep_data),
                             Path(out) / f"branch_{lab}")
    return paths


def branch_figure(result, quantity: str = "qmax", sweep=None, sweep_data=None):
    """One branch figure (``quantity`` "qmax": ``branch_max.png``, "qmin": ``branch_min.png``)
    of a continuation (:class:`~vibrogear.analyses.continuation.ContinuationStudyResult`) as
    a Figure; ``sweep``: a sweep analysis' result to overlay (or ``sweep_data``: its arrays
    in display units)."""
    study = result.study
    mon = study.monitor
    arrays = display_arrays(result.arrays(),
                            mon.scale, ("qmin", "qmax"))
    sw = sweep_data if sweep is None else display_arrays(sweep_arrays(sweep.sweep), mon.scale)
    lines = tuple(mon.lines)
    if mon.zero_line:
        near = bool(lines) and np.nanmin(arrays["qmin"], initial=0.0) < 0.5 * min(lines)
        lines = (0.0,) + (lines if near else ())
    if quantity not in ("qmax", "qmin"):
        raise ValueError(f"quantity: expected 'qmax' or 'qmin', got {quantity!r}")
    lab = quantity[1:]
    return plot_branches(arrays, quantity=quantity, ylabel=mon.axis_label(lab),
                         xlabel=study.param_label,
                         title=f"{plain_title(study.title)}: periodic orbits traced "
                               f"by continuation, their {lab}ima", sweep=sw, bounds=lines)


def plot_combined(result, out, sweep_data: dict, *, per_contact_rows: bool = False) -> list[Path]:
    """``bifurcation_branches``: sweep arrays ``sweep_data`` (display units) with the
    branches of ``result`` overlaid."""
    study = result.study
    arrays = display_arrays(result.arrays(),
                            study.monitor.scale, ("qmin", "qmax"))
    return draw_bifurcation(sweep_data, study, Path(out) / "bifurcation_branches",
                            branches=arrays, per_contact_rows=per_contact_rows)
