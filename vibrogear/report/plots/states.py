"""The danger map of ``vibrogear states``: every attractor at every speed.

Two panels over the parameter (speed): the largest (top) and the smallest (bottom) value of
the monitored deformation on each attractor.  Colour = class (period-1, period-2, period-n,
quasi-periodic, chaotic, other), marker area = basin fraction (the share of random starts
that end there), a red ring = an attractor the sweep's path did not pass through.  Branches
continued from the attractors are drawn over it (stable solid, unstable dashed), and the
sweep's points as small grey dots where a sweep is at hand.
"""
from __future__ import annotations

import numpy as np

from .branch import stability_segments
from ..figure import new_figure

__all__ = ["plot_danger_map", "CATEGORIES", "category"]

#: (label, colour) of each class category
CATEGORIES = (("period-1", "tab:blue"), ("period-2", "tab:green"), ("period-n (n > 2)", "tab:olive"),
              ("quasi-periodic", "tab:orange"), ("chaotic", "tab:red"),
              ("not settled / other", "tab:gray"))


def category(motion_class: int, period_n: int) -> int:
    """Index into :data:`CATEGORIES` (motion codes of solvers/sequential/motion.py)."""
    if period_n > 0:
        return 0 if period_n == 1 else 1 if period_n == 2 else 2
    return {2: 3, 3: 4}.get(int(motion_class), 5)


def plot_danger_map(arrays: dict, *, param_label: str, q_label: str, scale: float,
                    title: str = ""):
    """The danger map from ``states.npz``'s arrays (``arrays``) as a Figure (the report
    writer saves it as PNG + SVG)."""
    fig = new_figure((9.0, 7.0))
    axes = fig.subplots(2, 1, sharex=True)
    p = np.asarray(arrays["attractor_param"], float)
    frac = np.asarray(arrays["basin_fraction"], float)
    cats = np.array([category(c, n) for c, n in zip(arrays["attractor_class"],
                                                   arrays["attractor_period_n"])], dtype=int)
    seen = np.asarray(arrays["attractor_seen_by_sweep"], int)
    size = 12.0 + 220.0 * np.clip(frac, 0.0, 1.0)
    for ax, key, word in ((axes[0], "attractor_qmax", "largest"),
                          (axes[1], "attractor_qmin", "smallest")):
        if "sweep_param" in arrays and np.size(arrays["sweep_param"]):
            ax.plot(arrays["sweep_param"], np.asarray(arrays[f"sweep_{key[10:]}"]) * scale,
                    ".", ms=2, color="0.65", zorder=1, label="sweep points")
        _branches(ax, arrays, key[10:], scale)
        y = np.asarray(arrays[key], float) * scale
        for c, (label, colour) in enumerate(CATEGORIES):
            sel = cats == c
            if np.any(sel):
                ax.scatter(p[sel], y[sel], s=size[sel], c=colour, alpha=0.75,
                           edgecolors="k", linewidths=0.4, zorder=3, label=label)
        miss = seen == 0
        if np.any(miss):
            ax.scatter(p[miss], y[miss], s=size[miss] + 60, facecolors="none",
                       edgecolors="red", linewidths=1.4, zorder=4,
                       label="not on the sweep's path")
        ax.set_ylabel(f"{word} {q_label}")
        ax.grid(alpha=0.3)
    axes[1].set_xlabel(param_label)
    grid = np.asarray(arrays.get("param", p), float)
    if grid.size:                   # the census's range (the sweep may span more)
        pad = 0.08 * (np.ptp(grid) or abs(float(grid[0])) * 0.05 or 1.0)
        axes[1].set_xlim(float(grid.min()) - pad, float(grid.max()) + pad)
    handles, labels = axes[0].get_legend_handles_labels()
    uniq = dict(zip(labels, handles))
    axes[0].legend(uniq.values(), uniq.keys(), loc="best", fontsize=7, markerscale=0.6)
    axes[0].set_title((title + "\n" if title else "") +
                      "attractors from random starts; marker area = basin fraction", fontsize=9)
    return fig


def _branches(ax, arrays, q: str, scale: float) -> None:
    start = np.asarray(arrays.get("branch_start", [0]), int)
    if start.size < 2:
        return
    x = np.asarray(arrays["branch_param"], float)
    y = np.asarray(arrays[f"branch_{q}"], float) * scale
    st = np.asarray(arrays["branch_stable"], bool)
    first = True
    for a, b in zip(start[:-1], start[1:]):
        for xs, ys, stable in stability_segments(x[a:b], y[a:b], st[a:b]):
            ax.plot(xs, ys, "-" if stable else "--", color="k", lw=0.9, zorder=2,
                    label=("branches (dashed: unstable)" if first else None))
            first = False
