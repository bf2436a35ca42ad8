"""Bifurcation diagram of a sweep (the paper's Fig. 2) as PNG and SVG.

Top panel: Poincare samples of the monitored deformation (small dots) and its minima and
maxima per point, up and down sweeps in two colours and markers, a zero line (gear-mesh
interruption below it) or the clearance lines +-b_r.  Bottom panel: motion class
(period-n, 0 = not periodic) and contact losses per excitation period.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_bifurcation"]

_STYLE = {"up": dict(color="tab:blue", marker="^", label="up"),
          "down": dict(color="tab:red", marker="v", label="down")}


def _get(data, name):
    return np.asarray(data[name] if isinstance(data, dict) else getattr(data, name))


def plot_bifurcation(data, path, *, param_label: str | None = None,
                     deformation_label: str = "monitored deformation",
                     zero_line: bool = True, bounds=None, title: str | None = None,
                     formats=("png", "svg"), dpi: int = 150) -> list[Path]:
    """Draw the bifurcation diagram of ``data`` (a SweepResult or the dict of a read
    ``sweep.npz``) to ``path`` with each suffix in ``formats``; returns the paths.

    ``bounds``: values drawn as dashed horizontal lines (e.g. (-b_r, b_r)).
    Failed points (status != 0) are left out of the top panel and marked with 'x' on
    the bottom one.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    param = _get(data, "param").astype(float)
    direction = _get(data, "direction").astype(str)
    qmin = _get(data, "qmin").astype(float)
    qmax = _get(data, "qmax").astype(float)
    poinc = _get(data, "poincare").astype(float)
    period_n = _get(data, "period_n").astype(int)
    impacts = _get(data, "impacts").astype(float)
    status = _get(data, "status").astype(int) if (
        (isinstance(data, dict) and "status" in data) or hasattr(data, "status")) \
        else np.zeros(param.size, int)
    if param_label is None:
        name = data.get("param_name") if isinstance(data, dict) else getattr(
            data, "param_name", None)
        param_label = str(name) if name is not None else "parameter"
    ok = (status == 0) & np.isfinite(qmin) & np.isfinite(qmax)

    fig = Figure(figsize=(8.0, 6.4))
    FigureCanvasAgg(fig)            # Agg canvas, no pyplot state
    ax, ax2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    for d in ("up", "down"):
        sel = ok & (direction == d)
        if not np.any(sel):
            continue
        st = _STYLE[d]
        R = poinc.shape[1] if poinc.ndim == 2 else 0
        if R:
            xs = np.repeat(param[sel], R)
            ys = poinc[sel].ravel()
            fin = np.isfinite(ys)
            ax.plot(xs[fin], ys[fin], ".", ms=1.2, color=st["color"], alpha=0.6,
                    rasterized=True)
        ax.plot(param[sel], qmax[sel], st["marker"], ms=3, color=st["color"],
                mfc="none", lw=0, label=f"{st['label']}: min / max")
        ax.plot(param[sel], qmin[sel], st["marker"], ms=3, color=st["color"], mfc="none",
                lw=0)
        off = 0.08 if d == "up" else -0.08
        ax2.plot(param[sel], period_n[sel] + off, st["marker"], ms=3, color=st["color"],
                 lw=0, label=f"{d}: period n")
        ax2.plot(param[sel], impacts[sel], "s", ms=2.5, color=st["color"], mfc="none",
                 lw=0, alpha=0.7, label=f"{d}: losses / period")
    bad = ~ok
    if np.any(bad):
        ax2.plot(param[bad], np.zeros(int(bad.sum())), "kx", ms=5, label="failed")
    if zero_line:
        ax.axhline(0.0, color="k", lw=0.8)
    for b in (bounds or ()):
        ax.axhline(float(b), color="0.4", lw=0.8, ls="--")
    ax.set_ylabel(deformation_label)
    ax.legend(loc="best", fontsize=8, markerscale=1.5)
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title)
    ax2.set_xlabel(param_label)
    ax2.set_ylabel("period n (0: not periodic)\nlosses / period", fontsize=8)
    ax2.grid(alpha=0.3)
    ax2.legend(loc="best", fontsize=7, ncol=2)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    out = []
    for fmt in formats:
        p = path.with_suffix(f".{fmt}")
        fig.savefig(p, dpi=dpi)
        out.append(p)
    return out
