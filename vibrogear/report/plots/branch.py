"""Amplitude-frequency plots of continuation branches (paper Figs 4-8).

Stable segments solid, unstable dashed, special points marked and labelled (LP
triangles, PD squares, NS diamonds); sweep points (up/down) can be overlaid.
"""
from __future__ import annotations


import numpy as np

from ..figure import new_figure, plain_title

__all__ = ["plot_branches", "draw_branches", "branch_legend", "stability_segments",
           "label_special_points"]

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
    stable solid, unstable dashed, special points marked (and named: ``label_points``,
    :func:`label_special_points`)."""
    _draw(ax, arrays, quantity, lw_scale)
    if label_points:
        label_special_points(ax, arrays, quantity)


def _group_text(group) -> str:
    """"LP 1856, 1862 / PD 1859": each kind with its parameter values (more than three:
    their count and range)."""
    kinds = []
    for _, _, lab in group:
        if lab not in kinds:
            kinds.append(lab)
    parts = []
    for k in kinds:
        xs = sorted({f"{x:.4g}": x for x, _, lab in group if lab == k}.items(),
                    key=lambda kv: kv[1])            # one name per distinct value
        parts.append(f"{k} " + (", ".join(t for t, _ in xs) if len(xs) <= 3
                                else f"{len(xs)}x {xs[0][0]}-{xs[-1][0]}"))
    return " / ".join(parts)


def label_special_points(ax, arrays, quantity, *, fontsize: float = 7.0,
                         lanes: int = 6, avoid=()) -> list:
    """Name the special points (LP / PD / NS / BP) of ``arrays`` with their parameter value
    so that no two names overprint.  Points within 36 pt of a group's first point are named
    together ("LP 1856 / PD 1859"); each name is placed above its point, moved up one line
    at a time (at most ``lanes``) until its box, measured by the figure's renderer, meets no
    name placed before; one that would leave the axes on the right is right-aligned; a name
    that finds no free line is left out (its markers and the legend stay).  ``avoid``:
    axes (an inset) whose area no name may cover and whose points are named there, not
    here.  Call it once the axes have their final size.  Returns the Text artists."""
    label = np.asarray(arrays["label"]).astype(str)
    x = np.asarray(arrays["param"], float)
    y = np.asarray(arrays[quantity], float)
    pts = sorted((float(x[i]), float(y[i]), str(label[i])) for i in range(label.size)
                 if label[i] in _MARK and np.isfinite(x[i]) and np.isfinite(y[i]))
    if not pts:
        return []
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    per_pt = (x1 - x0) / max(frame.width * 72.0 / fig.dpi, 1.0)   # data x per point
    blocked = [a.get_tightbbox(renderer) for a in avoid]
    pts = [p for p in pts if x0 <= p[0] <= x1 and min(y0, y1) <= p[1] <= max(y0, y1)
           and not any(b.contains(*ax.transData.transform((p[0], p[1]))) for b in blocked)]
    if not pts:
        return []
    groups: list[list] = []
    for p in pts:
        if groups and p[0] - groups[-1][0][0] < 36.0 * per_pt:
            groups[-1].append(p)
        else:
            groups.append([p])
    texts, placed = [], list(blocked)
    step = fontsize + 4.0
    for g in groups:
        kinds = {lab for _, _, lab in g}
        col = _MARK[g[0][2]][1] if len(kinds) == 1 else "black"
        xa, ya = g[0][0], max(v for _, v, _ in g)
        t = ax.annotate(_group_text(g), (xa, ya), textcoords="offset points", xytext=(4, 4),
                        fontsize=fontsize, color=col, zorder=8, annotation_clip=False,
                        bbox=dict(boxstyle="square,pad=0.05", fc="white", ec="none",
                                  alpha=0.75))
        t.set_in_layout(False)
        for lane in range(lanes):
            t.set_horizontalalignment("left")
            t.xyann = (4, 4 + lane * step)
            box = t.get_window_extent(renderer)
            if box.x1 > frame.x1:
                t.set_horizontalalignment("right")
                t.xyann = (-4, 4 + lane * step)
                box = t.get_window_extent(renderer)
            if not any(box.overlaps(b) for b in placed):
                placed.append(box)
                texts.append(t)
                break
        else:
            t.remove()
    return texts


def branch_legend(arrays) -> list:
    """Legend handles: each period's stable / unstable line style, the special points."""
    from matplotlib.lines import Line2D
    nper = np.asarray(arrays["n_periods"])
    stable = np.asarray(arrays["stable"], dtype=bool)
    label = np.asarray(arrays["label"]).astype(str)
    handles = []
    plain = label == ""                     # the points the lines are drawn through
    for n in np.unique(nper):
        col = _COLOR.get(int(n), "tab:gray")
        for s, ls, word in ((True, "-", "stable"), (False, "--", "unstable")):
            if np.sum(plain & (nper == n) & (stable == s)) >= 1 and \
                    np.sum(plain & (nper == n)) >= 2:
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
    return ins


def plot_branches(arrays: dict, *, quantity: str = "qmax", ylabel: str = "max q",
                  xlabel: str = "Omega", title: str = "", sweep: dict | None = None,
                  bounds=()):
    """``arrays[quantity]`` (e.g. qmax or qmin) of every branch against param, as a Figure
    (the report writer saves it)."""
    from matplotlib.lines import Line2D

    fig = new_figure((9.0, 5.0))
    ax = fig.add_subplot(111)
    _draw(ax, arrays, quantity)
    drawn = []
    if sweep is not None:
        ok = np.asarray(sweep["status"]) == 0 if "status" in sweep else slice(None)
        for d, mk, col in (("up", "^", "tab:cyan"), ("down", "v", "tab:red")):
            sel = (np.asarray(sweep["direction"]).astype(str) == d) & ok
            if np.any(sel):
                ax.plot(np.asarray(sweep["param"])[sel], np.asarray(sweep[quantity])[sel],
                        mk, color=col, ms=3, alpha=0.7, ls="none")
                drawn.append(Line2D([], [], marker=mk, color=col, ls="none", ms=4,
                                    label=f"sweep {d}"))
    for b in bounds:
        ax.axhline(b, color="0.6", lw=0.8, ls=":")
    handles = branch_legend(arrays)                     # only what is drawn
    handles += drawn
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              frameon=False, borderaxespad=0.0)            # beside the axes, off the data
    nper = np.asarray(arrays["n_periods"])
    ins = _inset_period_doubling(ax, arrays, quantity) if np.any(nper == 2) else None
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(plain_title(title), fontsize=9)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    if ins is not None:           # the inset's points named in the inset, not under it
        label_special_points(ins, arrays, quantity, fontsize=6)
    label_special_points(ax, arrays, quantity, avoid=() if ins is None else (ins,))
    return fig
