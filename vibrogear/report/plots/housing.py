"""Plots of housing results: mode previews, geometry sweeps, error against run time.

Takes result objects and plain tables and returns matplotlib Figures (on their own Agg
canvas, no pyplot state); the report writer saves them (:mod:`..writers.housing`, at 110 dpi).
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from ..figure import new_figure

__all__ = ["plot_mode_previews", "plot_sweep", "plot_error_vs_time", "DPI"]

#: resolution the housing figures are saved at
DPI = 110


def plot_mode_previews(res, *, n: int = 6, title: str = ""):
    """First ``n`` mode shapes on the outer surface (deformed, coloured by |u|), a Figure."""
    import mpl_toolkits.mplot3d  # noqa: F401  (the "3d" projection)

    pts, vals = res.preview_points, res.preview_values
    n = min(n, vals.shape[-1] if vals.ndim == 3 else 0, res.n_modes)
    cols = 3
    rows = max(1, -(-n // cols))
    fig = new_figure((4.2 * cols, 3.8 * rows))
    span = float(np.ptp(pts, axis=0).max()) if len(pts) else 1.0
    for i in range(n):
        ax = fig.add_subplot(rows, cols, i + 1, projection="3d")
        u = vals[:, :, i]
        mag = np.linalg.norm(u, axis=1)
        scale = 0.08 * span / max(mag.max(), 1e-300)
        d = pts + scale * u
        ax.scatter(d[:, 0], d[:, 1], d[:, 2], c=mag, s=1.5, cmap="viridis", linewidths=0)
        ax.set_title(f"mode {i + 1}: {res.freqs_hz[i]:.1f} Hz", fontsize=9)
        ax.set_box_aspect(np.ptp(pts, axis=0) + 1e-9)
        ax.set_axis_off()
    fig.suptitle(title or f"housing master modes (P{res.degree}, {res.n_dofs} DOF)")
    fig.tight_layout()
    return fig


def plot_sweep(param: str, values: Sequence[float], freqs: np.ndarray):
    """First N frequencies (columns of ``freqs``) against the swept parameter, a Figure."""
    fig = new_figure((6.5, 4.5))
    ax = fig.subplots()
    freqs = np.asarray(freqs, dtype=float)
    for j in range(freqs.shape[1]):
        ax.plot(values, freqs[:, j], "o-", ms=3, label=f"f{j + 1}")
    ax.set_xlabel(param)
    ax.set_ylabel("frequency, Hz")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig


def plot_error_vs_time(rows: Sequence[dict], *, target: float = 0.01):
    """Max relative error of the first frequencies against DOF and against wall time, a
    Figure."""
    fig = new_figure((10, 4.2))
    axes = fig.subplots(1, 2)
    for degree, marker in ((1, "s--"), (2, "o-")):
        sel = sorted((r for r in rows if r["degree"] == degree), key=lambda r: r["n_dofs"])
        if not sel:
            continue
        err = [r["max_rel_error"] for r in sel]
        axes[0].loglog([r["n_dofs"] for r in sel], err, marker, label=f"P{degree}")
        axes[1].loglog([r["fe_seconds"] for r in sel], err, marker, label=f"P{degree}")
    for ax, xl in zip(axes, ("DOF", "wall time (mesh + assembly + solve), s")):
        ax.axhline(target, color="k", lw=0.8, ls=":")
        ax.set_xlabel(xl)
        ax.set_ylabel("max relative frequency error")
        ax.grid(alpha=0.3, which="both")
        ax.legend()
    fig.tight_layout()
    return fig
