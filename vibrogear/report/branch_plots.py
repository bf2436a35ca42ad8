"""Amplitude-frequency plots of continuation branches (paper Figs 4-8).

Stable segments solid, unstable dashed, special points marked and labelled (LP
triangles, PD squares, NS diamonds); sweep points (up/down) can be overlaid.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .figure import new_figure, save_figure

__all__ = ["plot_branches", "draw_branches", "branch_legend", "stability_segments"]

_MARK = {"LP": ("^", "black"), "PD": ("s", "tab:purple"), "NS": ("D", "tab:orange"),
         "BP": ("o", "tab:brown")}
_COLOR = {1: "tab:blue", 2: "tab:green", 3: "tab:olive", 4: "tab:pink", 5: "tab:cyan",
          6: "tab:brown", 8: "tab:gray"}


def stability_segments(x, y, stable):
    """Split a polyline where stability changes, sharing the boundary point."""
    start = 0
    for k in range(1, len(x) + 1):
        if k == len(x) or stable[k] != stable[start]:
            lo = max(start - 1, 0)
            yield x[lo:k], y[lo:k], bool(stable[start])
            start = k


def draw_branches(ax, arrays, quantity, *, label_points: bool = False, lw_scale=1.0):
    """Every branch of ``arrays`` (branch.npz's) on ``ax``: ``quantity`` against param,
    stable solid, unstable dashed, special points marked (and named: ``label_points``)."""
    _draw(ax, arrays, quantity, lw_scale)
    if label_points:
        # names only where they do not overprint: one per 3 % x 6 % of the branch's span
        label = np.asarray(arrays["label"]).astype(str)
        x, y = np.asarray(arrays["param"], float), np.asarray(arrays[quantity], float)
        wx, wy = 0.03 * (np.ptp(x) or 1.0), 0.06 * (np.ptp(y) or 1.0)
        done = []
        for lab, (_, col) in _MARK.items():
            for xv, yv in zip(x[label == lab], y[label == lab]):
                if any(abs(xv - a) < wx and abs(yv - b) < wy for a, b in done):
                    continue
                done.append((xv, yv))
                ax.annotate(lab, (xv, yv), textcoords="offset points", xytext=(4, 4),
                            fontsize=7, color=col)


def branch_legend(arrays) -> list:
    """Legend handles: each period's stable / unstable line style, the special points."""
    from matplotlib.lines import Line2D
    nper = np.asarray(arrays["n_periods"])
    stable = np.asarray(arrays["stable"], dtype=bool)
    label = np.asarray(arrays["label"]).astype(str)
    handles = []
    for n in np.unique(nper):
        col = _COLOR.get(int(n), "tab:gray")
        for s, ls, word in ((True, "-", "stable"), (False, "--", "unstable")):
            if np.any((nper == n) & (stable == s)):
                handles.append(Line2D([], [], color=col, ls=ls,
                                      label=f"period-{int(n)} branch {word}"))
    handles += [Line2D([], [], marker=mk, color=col, ls="none", mfc="none", label=lab)
                for lab, (mk, col) in _MARK.items() if np.any(label == lab)]
    return handles


def _draw(ax, arrays, quantity, lw_scale=1.0):
    label = np.asarray(arrays["label"]).astype(str)
    branch = np.asarray(arrays["branch"])
    for b in np.unique(branch):
        sel = (branch == b) & (label == "")
        nper = int(np.asarray(arrays["n_periods"])[branch == b][0])
        x = np.asarray(arrays["param"])[sel]
        y = np.asarray(arrays[quantity])[sel]
        st = np.asarray(arrays["stable"])[sel]
        for xs, ys, s in stability_segments(x, y, st):
            ax.plot(xs, ys, "-" if s else "--", color=_COLOR.get(nper, "tab:gray"),
                    lw=(1.6 if s else 1.1) * lw_scale)
    for lab, (mk, col) in _MARK.items():
        sel = label == lab
        if np.any(sel):
            ax.plot(np.asarray(arrays["param"])[sel], np.asarray(arrays[quantity])[sel], mk,
                    color=col, ms=5 * lw_scale, mfc="none", mew=1.2, zorder=5)


def _inset_period_doubling(ax, arrays, quantity):
    """Zoom on the period-2 branch (usually small against the whole range)."""
    p = np.asarray(arrays["param"])
    q = np.asarray(arrays[quantity])
    sel2 = np.asarray(arrays["n_periods"]) == 2
    x0, x1 = p[sel2].min(), p[sel2].max()
    pad = 0.15 * (x1 - x0) + 1e-9
    near = (p > x0 - pad) & (p < x1 + pad)
    y0, y1 = q[near].min(), q[near].max()
    ypad = 0.1 * (y1 - y0) + 1e-9
    ins = ax.inset_axes([0.55, 0.45, 0.4, 0.35])
    _draw(ins, arrays, quantity, lw_scale=0.8)
    ins.set_xlim(x0 - pad, x1 + pad)
    ins.set_ylim(y0 - ypad, y1 + ypad)
    ins.tick_params(labelsize=6)
    ins.set_title("period-doubling region", fontsize=7)
    ax.indicate_inset_zoom(ins, edgecolor="0.5")


def plot_branches(arrays: dict, path, *, quantity: str = "qmax", ylabel: str = "max q",
                  xlabel: str = "Omega", title: str = "", sweep: dict | None = None,
                  bounds=(), formats=("png", "svg"), dpi: int = 150) -> list[Path]:
    """Plot ``arrays[quantity]`` (e.g. qmax or qmin) of every branch against param."""
    from matplotlib.lines import Line2D

    fig = new_figure((8.0, 5.0))
    ax = fig.add_subplot(111)
    label = np.asarray(arrays["label"]).astype(str)
    _draw(ax, arrays, quantity)
    for lab, (_, col) in _MARK.items():
        for xv, yv in zip(np.asarray(arrays["param"])[label == lab],
                          np.asarray(arrays[quantity])[label == lab]):
            ax.annotate(lab, (xv, yv), textcoords="offset points", xytext=(4, 4), fontsize=7,
                        color=col)
    if sweep is not None:
        ok = np.asarray(sweep["status"]) == 0 if "status" in sweep else slice(None)
        for d, mk, col in (("up", "^", "tab:cyan"), ("down", "v", "tab:red")):
            sel = (np.asarray(sweep["direction"]).astype(str) == d) & ok
            if np.any(sel):
                ax.plot(np.asarray(sweep["param"])[sel], np.asarray(sweep[quantity])[sel],
                        mk, color=col, ms=3, alpha=0.7, ls="none")
    for b in bounds:
        ax.axhline(b, color="0.6", lw=0.8, ls=":")
    handles = [Line2D([], [], color=_COLOR[1], ls="-", label="period-1 stable"),
               Line2D([], [], color=_COLOR[1], ls="--", label="period-1 unstable")]
    if np.any(np.asarray(arrays["n_periods"]) == 2):
        handles += [Line2D([], [], color=_COLOR[2], ls="-", label="period-2 stable"),
                    Line2D([], [], color=_COLOR[2], ls="--", label="period-2 unstable")]
    handles += [Line2D([], [], marker=mk, color=col, ls="none", mfc="none", label=lab)
                for lab, (mk, col) in _MARK.items() if np.any(label == lab)]
    if sweep is not None:
        handles += [Line2D([], [], marker="^", color="tab:cyan", ls="none", ms=4, label="sweep up"),
                    Line2D([], [], marker="v", color="tab:red", ls="none", ms=4, label="sweep down")]
    ax.legend(handles=handles, fontsize=7, loc="best")
    nper = np.asarray(arrays["n_periods"])
    if np.any(nper == 2):
        _inset_period_doubling(ax, arrays, quantity)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    return save_figure(fig, path, formats, dpi)
