"""Bifurcation diagram of a sweep (the paper's Fig. 2) as PNG and SVG.

Top panel: Poincare samples of the monitored deformation (small dots) and its minima and
maxima per point, up and down sweeps in two colours and markers, a zero line (gear-mesh
interruption below it) or the clearance lines +-b_r.  Below it, the motion class of every
point as a categorical colour band (one row per direction, and one per contact group and
direction where the group's own class differs: a loaded mesh can be period-1 while a free
gear rattles), with a legend.  Then one axis per mesh (two-sided contact): drive-flank
(filled) and back-flank (open) impacts per excitation period; where the sweep has the
stroboscopic spectral evidence (``strob_flatness``, ``base_f2_order``; sweep_io.py), the
flatness of every non-periodic point's Poincare spectrum and a quasi-periodic point's
second base frequency f2 / f1 (right axis); last, where any mesh
rattles, the impact energy per period of each mesh (log scale; see solvers/sequential/motion.py).

With ``branches`` (the arrays of a continuation's ``branch.npz``, same display unit) the
top panel also carries the continuation branches' maxima and minima: stable solid,
unstable dashed, LP / PD / NS marked (:mod:`.branch_plots`).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .figure import new_figure, save_figure

__all__ = ["plot_bifurcation", "class_categories"]

_STYLE = {"up": dict(color="tab:blue", marker="^", label="up"),
          "down": dict(color="tab:red", marker="v", label="down")}
#: categories of the band: (label, colour)
_CATS = (("period 1", "#2ca02c"), ("period 2", "#98df8a"), ("period 3+", "#bcbd22"),
         ("quasi-periodic", "#1f77b4"), ("chaotic", "#d62728"), ("not settled", "#8c8c8c"),
         ("not periodic (no exponent)", "#d9d9d9"), ("failed", "#000000"))
# motion class codes (solvers.motion): 0 failed, 1 periodic, 2 QP, 3 chaotic,
# 4 not settled, 5 no exponent
_BY_CODE = {0: 7, 2: 3, 3: 4, 4: 5, 5: 6}


def _get(data, name, default=None):
    if isinstance(data, dict):
        return np.asarray(data[name]) if name in data else default
    v = getattr(data, name, None)
    if v is None and hasattr(data, "metrics"):
        v = data.metrics.get(name)
    return default if v is None else np.asarray(v)


def class_categories(motion_class, period_n) -> np.ndarray:
    """Band category index (into the legend) per point."""
    mc = np.asarray(motion_class, dtype=int)
    n = np.asarray(period_n, dtype=int)
    out = np.array([_BY_CODE.get(int(c), 6) for c in mc])
    per = mc == 1
    out[per] = np.where(n[per] == 1, 0, np.where(n[per] == 2, 1, 2))
    return out


def _band(ax, param, rows):
    """rows: [(label, mask, categories)] drawn as coloured cells, top to bottom."""
    p = np.unique(param)
    w = np.min(np.diff(p)) if p.size > 1 else 1.0
    used = set()
    for r, (label, sel, cats) in enumerate(rows):
        y = len(rows) - 1 - r
        for x, c in zip(param[sel], cats[sel]):
            ax.add_patch(_rect(x - 0.5 * w, y + 0.08, w, 0.84, _CATS[c][1]))
            used.add(int(c))
    ax.set_ylim(0, len(rows))
    ax.set_yticks(np.arange(len(rows)) + 0.5)
    ax.set_yticklabels([lab for lab, _, _ in rows][::-1], fontsize=7)
    ax.tick_params(axis="y", length=0)
    from matplotlib.patches import Patch
    handles = [Patch(color=_CATS[c][1], label=_CATS[c][0]) for c in sorted(used)]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=7,
              frameon=False, borderaxespad=0.0)


def _spectral_panel(ax, data, param, direction, ok, mclass, dirs):
    """Spectral evidence of the stroboscopic samples: their flatness (chaos: broadband) for
    the points without a period, and a quasi-periodic point's f2 / f1 (right axis)."""
    flat = _get(data, "strob_flatness").astype(float)
    f2 = _get(data, "base_f2_order", np.zeros(param.size)).astype(float)
    right = ax.twinx()
    for d in dirs:
        sel = ok & (direction == d) & (mclass != 1)
        ax.plot(param[sel], flat[sel], _STYLE[d]["marker"], ms=3.5, color=_STYLE[d]["color"],
                lw=0, mfc="none", label=f"{d}: flatness")
        qp = ok & (direction == d) & (mclass == 2) & (f2 > 0)
        right.plot(param[qp], f2[qp], "*", ms=5, color=_CATS[3][1], lw=0,
                   label=f"{d}: quasi-periodic f2 / f1" if np.any(qp) else None)
    ax.set_ylabel("Poincare spectrum\nflatness", fontsize=8)
    ax.set_ylim(-0.02, 0.7)
    right.set_ylim(0.0, 0.52)
    right.set_ylabel("f2 / f1", fontsize=8)
    ax.grid(alpha=0.3)
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = right.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, loc="upper left", bbox_to_anchor=(1.06, 1.0), fontsize=7,
              frameon=False, borderaxespad=0.0)


def _rect(x, y, w, h, color):
    from matplotlib.patches import Rectangle
    return Rectangle((x, y), w, h, color=color, lw=0)


def plot_bifurcation(data, path, *, param_label: str | None = None,
                     deformation_label: str = "monitored deformation",
                     zero_line: bool = True, bounds=None, title: str | None = None,
                     branches: dict | None = None, formats=("png", "svg"),
                     dpi: int = 150, energy_unit: str = "model units") -> list[Path]:
    """Draw the bifurcation diagram of ``data`` (a SweepResult or the dict of a read
    ``sweep.npz``) to ``path`` with each suffix in ``formats``; returns the paths.

    ``bounds``: values drawn as dashed horizontal lines (e.g. (-b_r, b_r)).  Failed
    points (status != 0) are left out of the top panel and black in the class band.
    """
    param = _get(data, "param").astype(float)
    direction = _get(data, "direction").astype(str)
    qmin = _get(data, "qmin").astype(float)
    qmax = _get(data, "qmax").astype(float)
    poinc = _get(data, "poincare").astype(float)
    period_n = _get(data, "period_n").astype(int)
    status = _get(data, "status", np.zeros(param.size, int)).astype(int)
    ok = (status == 0) & np.isfinite(qmin) & np.isfinite(qmax)
    mclass = _get(data, "motion_class")
    if mclass is None:                       # a sweep from before the motion classes
        mclass = np.where(~ok, 0, np.where(period_n > 0, 1, 5))
    cats = class_categories(mclass, period_n)
    if param_label is None:
        name = data.get("param_name") if isinstance(data, dict) else getattr(
            data, "param_name", None)
        param_label = str(name) if name is not None else "parameter"
    keys = (list(data) if isinstance(data, dict) else list(getattr(data, "metrics", {})))
    meshes = sorted(k[len("impacts_drive_"):] for k in keys
                    if k.startswith("impacts_drive_") and not k.endswith("_err"))
    groups = sorted(k[len("motion_class_"):] for k in keys if k.startswith("motion_class_")
                    and k != "motion_class_legend")
    dirs = [d for d in ("up", "down") if np.any(direction == d)]
    rows = [(d, direction == d, cats) for d in dirs]
    for g in groups:
        gc = class_categories(_get(data, f"motion_class_{g}"),
                              _get(data, f"period_n_{g}", period_n))
        if np.any(gc != cats):
            rows += [(f"{g} {d}", direction == d, gc) for d in dirs]

    rattle = {g: _get(data, f"rattle_{g}").astype(float) for g in meshes
              if _get(data, f"rattle_{g}") is not None}
    rattle = {g: v for g, v in rattle.items() if np.any(v[ok] > 0)}
    flat = _get(data, "strob_flatness")
    spec = flat is not None and bool(np.any(ok & (mclass != 1)))
    fig = new_figure((9.0, 6.4 + 1.1 * (len(meshes) + bool(rattle) + spec)
                      + 0.15 * len(rows)))
    ratios = [3.0, 0.3 + 0.22 * len(rows)] + [1.0] * (len(meshes) + bool(rattle) + spec)
    axes = fig.subplots(len(ratios), 1, sharex=True, gridspec_kw={"height_ratios": ratios})
    ax, axc, axm = axes[0], axes[1], axes[2:2 + len(meshes)]
    if spec:
        _spectral_panel(axes[2 + len(meshes)], data, param, direction, ok, mclass, dirs)
    if rattle:
        axr = axes[-1]
        for i, (g, v) in enumerate(rattle.items()):
            for d in dirs:
                sel = ok & (direction == d) & (v > 0)
                axr.semilogy(param[sel], v[sel], _STYLE[d]["marker"], ms=3.5,
                             color=f"C{(2 * i + (d == 'down')) % 10}", lw=0,
                             label=f"{g} {d}")
        axr.set_ylabel(f"rattle energy per\nperiod [{energy_unit}]", fontsize=8)
        axr.grid(alpha=0.3, which="both")
        axr.legend(loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=7, frameon=False,
                   borderaxespad=0.0)
    for d in dirs:
        sel = ok & (direction == d)
        st = _STYLE[d]
        R = poinc.shape[1] if poinc.ndim == 2 else 0
        if R and np.any(sel):
            xs = np.repeat(param[sel], R)
            ys = poinc[sel].ravel()
            fin = np.isfinite(ys)
            ax.plot(xs[fin], ys[fin], ".", ms=1.2, color=st["color"], alpha=0.6,
                    rasterized=True)
        ax.plot(param[sel], qmax[sel], st["marker"], ms=3, color=st["color"],
                mfc="none", lw=0, label=f"{st['label']}: min / max")
        ax.plot(param[sel], qmin[sel], st["marker"], ms=3, color=st["color"], mfc="none",
                lw=0)
        for a, g in zip(axm, meshes):
            dr = _get(data, f"impacts_drive_{g}").astype(float)
            bk = _get(data, f"impacts_back_{g}").astype(float)
            a.plot(param[sel], dr[sel], st["marker"], ms=3.5, color=st["color"], lw=0,
                   label=f"{d}: drive flank")
            a.plot(param[sel], bk[sel], st["marker"], ms=3.5, color=st["color"],
                   mfc="none", lw=0, label=f"{d}: back flank")
    if branches is not None and np.size(branches["param"]):
        from .branch_plots import branch_legend, draw_branches
        for q in ("qmax", "qmin"):
            draw_branches(ax, branches, q, label_points=q == "qmax")
        ax.legend(handles=ax.get_legend_handles_labels()[0] + branch_legend(branches),
                  loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=7, frameon=False,
                  borderaxespad=0.0)
    else:
        ax.legend(loc="best", fontsize=8, markerscale=1.5)
    if zero_line:
        ax.axhline(0.0, color="k", lw=0.8)
    for b in (bounds or ()):
        ax.axhline(float(b), color="0.4", lw=0.8, ls="--")
    ax.set_ylabel(deformation_label)
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title, fontsize=10)
    _band(axc, param, rows)
    axc.set_ylabel("motion", fontsize=8)
    for a, g in zip(axm, meshes):
        a.set_ylabel(f"{g}: impacts\nper period", fontsize=8)
        top = max(1.0, a.get_ylim()[1])
        a.set_ylim(-0.05 * top, 1.05 * top)
        a.grid(alpha=0.3)
        a.legend(loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=7, frameon=False,
                 borderaxespad=0.0)
    axes[-1].set_xlabel(param_label)
    if param.size:
        pad = 0.5 * (np.min(np.diff(np.unique(param))) if np.unique(param).size > 1 else 1.0)
        ax.set_xlim(param.min() - pad, param.max() + pad)
    return save_figure(fig, path, formats, dpi)
