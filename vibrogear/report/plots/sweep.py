"""Bifurcation diagram of a sweep (the paper's Fig. 2) as PNG and SVG.

Top panel: Poincare samples of the monitored deformation (small dots, one per excitation
period) and its minima and maxima per point, up and down sweeps in two colours and markers,
a zero line (gear-mesh interruption below it) or the clearance lines +-b_r.  Below it, the
motion class of every point as a categorical colour band: one row per sweep direction, and
with ``per_contact_rows`` (``[figures] motion_rows_per_contact``) also one per contact group
and direction where the group's own class differs (a loaded mesh can be period-1 while a
free gear rattles).  Then one panel per gear mesh, every mesh (two-sided contact), also the
one that rattles: its drive-flank (filled) and back-flank (open) impacts per excitation
period (left axis) and the share of the time its teeth are out of contact (right axis,
line); last, where any mesh rattles, the impact energy per period of each mesh (log scale;
see solvers/sequential/motion.py).  With ``spectral`` and the stroboscopic spectral
evidence (``strob_flatness``, ``base_f2_order``; report/sweep_files.py) a panel of the flatness of
every non-periodic point's Poincare spectrum and a quasi-periodic point's f2 / f1.

With ``branches`` (the arrays of a continuation's ``branch.npz``, same display unit) the
top panel also carries the continuation branches' maxima and minima: stable solid,
unstable dashed, LP / PD / NS marked and named with their speeds, never overprinting
(:mod:`.branch`).
"""
from __future__ import annotations


import numpy as np

from ..figure import new_figure, plain_title

__all__ = ["plot_bifurcation", "class_categories", "motion_rows", "draw_band"]

_STYLE = {"up": dict(color="tab:blue", marker="^", label="up"),
          "down": dict(color="tab:red", marker="v", label="down")}
#: categories of the band: (label, colour)
CLASS_COLOURS = (("period 1", "#2ca02c"), ("period 2", "#98df8a"), ("period 3+", "#bcbd22"),
         ("quasi-periodic", "#1f77b4"), ("chaotic", "#d62728"), ("not settled", "#8c8c8c"),
         ("not periodic (no exponent)", "#d9d9d9"), ("failed", "#000000"),
         ("multi-frequency forced", "#17becf"))
# motion class codes (solvers.motion): 0 failed, 1 periodic, 2 QP, 3 chaotic,
# 4 not settled, 5 no exponent, 6 multi-frequency forced
_BY_CODE = {0: 7, 2: 3, 3: 4, 4: 5, 5: 6, 6: 8}
_LEGEND = dict(loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=7, frameon=False,
               borderaxespad=0.0)


def _get(data, name, default=None):
    if isinstance(data, dict):
        return np.asarray(data[name]) if name in data else default
    v = getattr(data, name, None)
    if v is None and hasattr(data, "metrics"):
        v = data.metrics.get(name)
    return default if v is None else np.asarray(v)


def _keys(data) -> list:
    return list(data) if isinstance(data, dict) else list(getattr(data, "metrics", {}))


def class_categories(motion_class, period_n) -> np.ndarray:
    """Band category index (into the legend) per point."""
    mc = np.asarray(motion_class, dtype=int)
    n = np.asarray(period_n, dtype=int)
    out = np.array([_BY_CODE.get(int(c), 6) for c in mc], dtype=int)
    per = mc == 1
    out[per] = np.where(n[per] == 1, 0, np.where(n[per] == 2, 1, 2))
    return out


def motion_rows(data, direction, cats, *, per_contact: bool = False) -> list:
    """The band's rows [(label, mask, categories)]: one per sweep direction; with
    ``per_contact`` also each contact group's (mesh, bearing) per direction where its own
    class differs from the whole motion's."""
    direction = np.asarray(direction).astype(str)
    dirs = [d for d in ("up", "down") if np.any(direction == d)]
    rows = [(d, direction == d, cats) for d in dirs]
    if not per_contact:
        return rows
    period_n = _get(data, "period_n")
    groups = sorted(k[len("motion_class_"):] for k in _keys(data)
                    if k.startswith("motion_class_") and k != "motion_class_legend")
    for g in groups:
        gc = class_categories(_get(data, f"motion_class_{g}"),
                              _get(data, f"period_n_{g}", period_n))
        if np.any(gc != cats):
            rows += [(f"{g} {d}", direction == d, gc) for d in dirs]
    return rows


def draw_band(ax, param, rows):
    """rows: [(label, mask, categories)] drawn as coloured cells, top to bottom; the legend
    lists the classes drawn."""
    param = np.asarray(param, float)
    p = np.unique(param)
    w = np.min(np.diff(p)) if p.size > 1 else 1.0
    used = set()
    for r, (label, sel, cats) in enumerate(rows):
        y = len(rows) - 1 - r
        for x, c in zip(param[sel], cats[sel]):
            ax.add_patch(_rect(x - 0.5 * w, y + 0.08, w, 0.84, CLASS_COLOURS[c][1]))
            used.add(int(c))
    ax.set_ylim(0, len(rows))
    ax.set_yticks(np.arange(len(rows)) + 0.5)
    ax.set_yticklabels([lab for lab, _, _ in rows][::-1], fontsize=7)
    ax.tick_params(axis="y", length=0)
    from matplotlib.patches import Patch
    handles = [Patch(color=CLASS_COLOURS[c][1], label=CLASS_COLOURS[c][0]) for c in sorted(used)]
    ax.legend(handles=handles, **_LEGEND)


def _mesh_panel(ax, data, g, param, direction, ok, dirs):
    """Mesh ``g``: impacts per period on each flank (left), time out of contact (right)."""
    from matplotlib.lines import Line2D

    dr = _get(data, f"impacts_drive_{g}").astype(float)
    bk = _get(data, f"impacts_back_{g}").astype(float)
    frac = _get(data, f"contact_fraction_{g}")
    right = ax.twinx() if frac is not None else None
    for d in dirs:
        sel = ok & (direction == d)
        st = _STYLE[d]
        ax.plot(param[sel], dr[sel], st["marker"], ms=3.5, color=st["color"], lw=0)
        ax.plot(param[sel], bk[sel], st["marker"], ms=3.5, color=st["color"], mfc="none", lw=0)
        if right is not None:
            order = np.argsort(param[sel], kind="stable")
            right.plot(param[sel][order], 100.0 * (1.0 - frac.astype(float)[sel][order]),
                       "-", lw=0.9, color=st["color"], alpha=0.6)
    ax.set_ylabel(f"{g}: impacts\nper period", fontsize=8)
    top = max(1.0, ax.get_ylim()[1])
    ax.set_ylim(-0.05 * top, 1.05 * top)
    ax.grid(alpha=0.3)
    handles = [Line2D([], [], marker="o", color="0.3", lw=0, ms=4, label="drive-flank impacts"),
               Line2D([], [], marker="o", color="0.3", mfc="none", lw=0, ms=4,
                      label="back-flank impacts\n(rattle)")]
    if right is not None:
        right.set_ylim(-5.0, 105.0)
        right.set_ylabel("out of contact\n[% of time]", fontsize=8)
        right.tick_params(labelsize=7)
        handles.append(Line2D([], [], color="0.3", lw=0.9, label="time out of contact"))
    ax.legend(handles=handles, **{**_LEGEND, "bbox_to_anchor": (1.09, 1.0)})


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
        right.plot(param[qp], f2[qp], "*", ms=5, color=CLASS_COLOURS[3][1], lw=0,
                   label=f"{d}: quasi-periodic f2 / f1" if np.any(qp) else None)
    ax.set_ylabel("Poincare spectrum\nflatness", fontsize=8)
    ax.set_ylim(-0.02, 0.7)
    right.set_ylim(0.0, 0.52)
    right.set_ylabel("f2 / f1", fontsize=8)
    ax.grid(alpha=0.3)
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = right.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, **{**_LEGEND, "bbox_to_anchor": (1.06, 1.0)})


def _rect(x, y, w, h, color):
    from matplotlib.patches import Rectangle
    return Rectangle((x, y), w, h, color=color, lw=0)


def plot_bifurcation(data, *, param_label: str | None = None,
                     deformation_label: str = "monitored deformation",
                     zero_line: bool = True, bounds=None, title: str | None = None,
                     branches: dict | None = None, energy_unit: str = "model units",
                     per_contact_rows: bool = False, spectral: bool = False):
    """The bifurcation diagram of ``data`` (a SweepResult or the dict of a read
    ``sweep.npz``) as a Figure (the report writer saves it, :func:`.figure.save_figure`).

    ``bounds``: values drawn as dashed horizontal lines (e.g. (-b_r, b_r)).  Failed
    points (status != 0) are left out of the top panel and black in the class band.
    """
    from matplotlib.lines import Line2D

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
    meshes = sorted(k[len("impacts_drive_"):] for k in _keys(data)
                    if k.startswith("impacts_drive_") and not k.endswith("_err"))
    dirs = [d for d in ("up", "down") if np.any(direction == d)]
    rows = motion_rows(data, direction, cats, per_contact=per_contact_rows)

    rattle = {g: _get(data, f"rattle_{g}").astype(float) for g in meshes
              if _get(data, f"rattle_{g}") is not None}
    rattle = {g: v for g, v in rattle.items() if np.any(v[ok] > 0)}
    spec = spectral and _get(data, "strob_flatness") is not None \
        and bool(np.any(ok & (mclass != 1)))
    extra = len(meshes) + bool(rattle) + spec
    fig = new_figure((9.5, 5.6 + 1.3 * extra + 0.15 * len(rows)))
    ratios = [3.0, 0.3 + 0.22 * len(rows)] + [1.1] * extra
    axes = fig.subplots(len(ratios), 1, sharex=True, gridspec_kw={"height_ratios": ratios})
    ax, axc, axm = axes[0], axes[1], axes[2:2 + len(meshes)]
    for a, g in zip(axm, meshes):
        _mesh_panel(a, data, g, param, direction, ok, dirs)
    if spec:
        _spectral_panel(axes[2 + len(meshes)], data, param, direction, ok, mclass, dirs)
    if rattle:                       # colour: direction (as above); marker: mesh
        axr = axes[-1]
        marks = ("o", "s", "D", "P", "X", "*")
        for i, (g, v) in enumerate(rattle.items()):
            for d in dirs:
                sel = ok & (direction == d) & (v > 0)
                axr.semilogy(param[sel], v[sel], marks[i % len(marks)], ms=3.2,
                             color=_STYLE[d]["color"], lw=0, alpha=0.8)
        axr.set_ylabel(f"impact energy per\nperiod [{energy_unit}]", fontsize=8)
        axr.grid(alpha=0.3, which="both")
        axr.legend(handles=[Line2D([], [], marker=marks[i % len(marks)], color="0.3", lw=0,
                                   ms=4, label=f"{g}") for i, g in enumerate(rattle)],
                   **_LEGEND)
    handles = []
    R = poinc.shape[1] if poinc.ndim == 2 else 0
    for d in dirs:
        sel = ok & (direction == d)
        st = _STYLE[d]
        if R and np.any(sel):
            xs = np.repeat(param[sel], R)
            ys = poinc[sel].ravel()
            fin = np.isfinite(ys)
            ax.plot(xs[fin], ys[fin], ".", ms=1.2, color=st["color"], alpha=0.6,
                    rasterized=True)
        ax.plot(param[sel], qmax[sel], st["marker"], ms=3, color=st["color"], mfc="none", lw=0)
        ax.plot(param[sel], qmin[sel], st["marker"], ms=3, color=st["color"], mfc="none", lw=0)
        if np.any(sel):
            handles.append(Line2D([], [], marker=st["marker"], color=st["color"], mfc="none",
                                  lw=0, label=f"sweep {d}: min / max"))
    if R and np.any(ok):
        handles.append(Line2D([], [], marker=".", color="0.4", lw=0, ms=4,
                              label="once per period\n(Poincare samples)"))
    drawn_branches = branches is not None and np.size(branches["param"])
    if drawn_branches:
        from .branch import branch_legend, draw_branches
        for q in ("qmax", "qmin"):
            draw_branches(ax, branches, q)
        handles += branch_legend(branches)
    ax.legend(handles=handles, **_LEGEND)
    if zero_line:
        ax.axhline(0.0, color="k", lw=0.8)
    for b in (bounds or ()):
        ax.axhline(float(b), color="0.4", lw=0.8, ls="--")
    ax.set_ylabel(deformation_label)
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(plain_title(title), fontsize=10)
    draw_band(axc, param, rows)
    axc.set_ylabel("motion", fontsize=8)
    axes[-1].set_xlabel(param_label)
    if param.size:
        pad = 0.5 * (np.min(np.diff(np.unique(param))) if np.unique(param).size > 1 else 1.0)
        ax.set_xlim(param.min() - pad, param.max() + pad)
    fig.tight_layout()
    if drawn_branches:
        from .branch import label_special_points
        label_special_points(ax, branches, "qmax")
    return fig
