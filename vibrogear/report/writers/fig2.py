"""``fig2.png/.svg``: the seed paper's Fig. 2 with the continuation on top of it.

One figure from a sweep and a continuation of the same scene (written by the continuation's
report writer, :mod:`.continuation`, when the sweep's arrays are at hand):

* top panel: the minima and maxima of the monitored deformation (a gearbox: the G1 mesh
  deformation) at every settled sweep point as dots (up and down sweeps in two colours),
  the zero line (below it the mesh is interrupted), and over them the continuation
  branches' maxima and minima: stable solid, unstable dashed, LP / PD / NS marked and named
  (:func:`..plots.branch.draw_branches`);
* bottom panel: the motion class of every sweep point as a colour band, one row per sweep
  direction (with ``per_contact_rows``, ``[figures] motion_rows_per_contact``, also one per
  contact group whose own class differs; the band of :mod:`..plots.sweep`).

Unlike ``bifurcation_branches.png`` it leaves out the Poincare samples and the impact and
rattle panels, so that it reads as the seed's diagram.  Both arrays come in display units
(:func:`..plots.bifurcation.display_arrays`).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plots.bifurcation import display_arrays
from ..plots.branch import branch_legend, draw_branches, label_special_points
from ..figure import new_figure, plain_title, save_figure
from ..plots.sweep import class_categories, draw_band, motion_rows

__all__ = ["plot_fig2", "write_fig2"]

_DOTS = {"up": dict(color="tab:blue", marker="^", label="sweep up: min / max"),
         "down": dict(color="tab:red", marker="v", label="sweep down: min / max")}


def plot_fig2(sweep: dict, branches: dict | None, *, param_label: str = "parameter",
              ylabel: str = "deformation", title: str = "", zero_line: bool = True,
              per_contact_rows: bool = False):
    """The figure of the module docstring from sweep arrays ``sweep`` and branch arrays
    ``branches`` (branch.npz's; None or empty: the sweep alone), as a Figure."""
    param = np.asarray(sweep["param"], float)
    direction = np.asarray(sweep["direction"]).astype(str)
    qmin = np.asarray(sweep["qmin"], float)
    qmax = np.asarray(sweep["qmax"], float)
    status = np.asarray(sweep.get("status", np.zeros(param.size, int)))
    ok = (status == 0) & np.isfinite(qmin) & np.isfinite(qmax)
    cats = class_categories(sweep["motion_class"], sweep["period_n"]) \
        if "motion_class" in sweep else np.where(np.asarray(sweep["period_n"]) > 0, 0, 6)
    rows = motion_rows(sweep, direction, cats, per_contact=per_contact_rows)
    fig = new_figure((9.0, 6.0 + 0.15 * len(rows)))
    ax, axc = fig.subplots(2, 1, sharex=True,
                           gridspec_kw={"height_ratios": [4.0, 0.4 + 0.22 * len(rows)]})
    for d, st in _DOTS.items():
        sel = ok & (direction == d)
        if not np.any(sel):
            continue
        for q, lab in ((qmax, st["label"]), (qmin, None)):
            ax.plot(param[sel], q[sel], st["marker"], ms=2.6, color=st["color"], lw=0,
                    alpha=0.75, label=lab)
    handles = ax.get_legend_handles_labels()[0]
    drawn_branches = branches is not None and np.size(branches["param"])
    if drawn_branches:
        for q in ("qmax", "qmin"):
            draw_branches(ax, branches, q)
        handles += branch_legend(branches)
    if zero_line:
        ax.axhline(0.0, color="k", lw=0.9)
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=7,
              frameon=False, borderaxespad=0.0)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(plain_title(title), fontsize=10)
    draw_band(axc, param, rows)
    axc.set_ylabel("motion", fontsize=8)
    axc.set_xlabel(param_label)
    if param.size:
        u = np.unique(param)
        pad = 0.5 * (np.min(np.diff(u)) if u.size > 1 else 1.0)
        ax.set_xlim(param.min() - pad, param.max() + pad)
    fig.tight_layout()
    if drawn_branches:                  # named once the axes have their final size
        label_special_points(ax, branches, "qmax")
    return fig


def write_fig2(result, out, sweep_data: dict, *, per_contact_rows: bool = False) -> list[Path]:
    """``fig2.png/.svg`` in ``out`` from a continuation ``result`` and the sweep arrays
    ``sweep_data`` (display units) of the same study."""
    study = result.study
    mon = study.monitor
    arrays = display_arrays(result.arrays(),
                            mon.scale, ("qmin", "qmax"))
    below = " (below 0: the teeth lose contact)" if mon.zero_line else ""
    title = (f"{plain_title(study.title)}: response against speed{below}\nsweep minima / "
             "maxima, continuation branches (stable solid, unstable dashed), motion classes")
    return save_figure(plot_fig2(sweep_data, arrays, param_label=study.param_label,
                                 ylabel=mon.axis_label(), title=title, zero_line=mon.zero_line,
                                 per_contact_rows=per_contact_rows), Path(out) / "fig2")
