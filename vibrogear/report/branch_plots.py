"""Amplitude-frequency plots of continuation branches (paper Figs 4-8).

Stable segments solid, unstable dashed, special points marked and labelled (LP
triangles, PD squares, NS diamonds); sweep points (up/down) can be overlaid.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_branches"]

_MARK = {"LP": ("^", "black"), "PD": ("s", "tab:purple"), "NS": ("D", "tab:orange"),
         "BP": ("o", "tab:brown")}
_COLOR = {1: "tab:blue", 2: "tab:green"}


def _segments(x, y, stable):
    """Split a polyline where stability changes, sharing the boundary point."""
    start = 0
    for k in range(1, len(x) + 1):
        if k == len(x) or stable[k] != stable[start]:
            lo = max(start - 1, 0) if start > 0 else 0
            yield x[lo:k], y[lo:k], bool(stable[start])
            start = k


def plot_branches(arrays: dict, path, *, quantity: str = "qmax", ylabel: str = "max q",
                  xlabel: str = "Omega", title: str = "", sweep: dict | None = None,
                  bounds=(), formats=("png", "svg"), dpi: int = 150) -> list[Path]:
    """Plot ``arrays[quantity]`` (e.g. qmax or qmin) of every branch against param."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    fig = Figure(figsize=(8.0, 5.0))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(111)
    label = np.asarray(arrays["label"]).astype(str)
    branch = np.asarray(arrays["branch"])
    for b in np.unique(branch):
        sel = (branch == b) & (label == "")
        nper = int(np.asarray(arrays["n_periods"])[branch == b][0])
        x = np.asarray(arrays["param"])[sel]
        y = np.asarray(arrays[quantity])[sel]
        st = np.asarray(arrays["stable"])[sel]
        for xs, ys, s in _segments(x, y, st):
            ax.plot(xs, ys, "-" if s else "--", color=_COLOR.get(nper, "tab:gray"),
                    lw=1.6 if s else 1.1)
    for lab, (mk, col) in _MARK.items():
        sel = label == lab
        if np.any(sel):
            xs = np.asarray(arrays["param"])[sel]
            ys = np.asarray(arrays[quantity])[sel]
            ax.plot(xs, ys, mk, color=col, ms=6, mfc="none", mew=1.5, zorder=5)
            for xv, yv in zip(xs, ys):
                ax.annotate(lab, (xv, yv), textcoords="offset points", xytext=(4, 4),
                            fontsize=7, color=col)
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
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    out = []
    for fmt in formats:
        p = Path(path).with_suffix("." + fmt)
        fig.savefig(p, dpi=dpi)
        out.append(p)
    return out
