"""Figures of ``vibrogear optimize``: convergence and the objective landscape.

* ``optimize_convergence.png/.svg``: the objective of every evaluation (feasible filled,
  infeasible open, failed as crosses on the axis) and the best feasible so far;
* ``optimize_landscape.png/.svg`` (one or two variables): the objective against the variable,
  or over the two variables (coloured points, a triangulated contour from six evaluations).

Matplotlib ``Figure`` with the Agg canvas: no pyplot state.
"""
from __future__ import annotations

import numpy as np

from ..figure import new_figure, plain_title

__all__ = ["plot_convergence", "plot_landscape"]


def _split(history):
    ok = [h for h in history if h["status"] == "ok"]
    return ([h for h in ok if h["feasible"]], [h for h in ok if not h["feasible"]],
            [h for h in history if h["status"] != "ok"])


def plot_convergence(history, best_so_far, *, label: str, title: str = ""):
    """The objective of every evaluation and the best feasible one so far, a Figure (the
    report writer saves it)."""
    fig = new_figure((7.5, 4.5))
    ax = fig.add_subplot(111)
    feas, infeas, failed = _split(history)
    if feas:
        ax.plot([h["evaluation"] for h in feas], [h["objective"] for h in feas], "o",
                color="tab:blue", ms=4, label="feasible")
    if infeas:
        ax.plot([h["evaluation"] for h in infeas], [h["objective"] for h in infeas], "o",
                mfc="none", color="tab:red", ms=4, label="violates a constraint")
    n = np.arange(1, len(best_so_far) + 1)
    b = np.array(best_so_far, dtype=float)
    if np.any(np.isfinite(b)):
        ax.step(n, b, where="post", color="k", lw=1.2, label="best feasible so far")
    if failed:
        y0 = ax.get_ylim()[0] if (feas or infeas) else 0.0
        ax.plot([h["evaluation"] for h in failed], [y0] * len(failed), "x", color="0.3",
                clip_on=False, ls="none", label="failed")
    ax.set_xlabel("evaluation")
    ax.set_ylabel(label)
    ax.set_title(plain_title(title), fontsize=9)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)
    return fig


def _constraints_panel(ax, ok, key, constraints):
    """Each constraint's value against the one variable, with its bounds."""
    for i, c in enumerate(constraints):
        pts = sorted((h["values"][key], h["constraints"][i]) for h in ok)
        if pts:
            x, y = np.array(pts).T
            line, = ax.plot(x, y, ".-", lw=0.8, ms=5, label=f"{c.reduce} {c.metric}")
            for b in (c.min, c.max):
                if b is not None:
                    ax.axhline(b, color=line.get_color(), ls=":", lw=1)
    ax.set_xlabel(key)
    ax.set_ylabel("constraint value")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)


def plot_landscape(history, variables, best, *, label: str, title: str = "",
                   constraints=()):
    """One or two variables: the objective of the successful evaluations over them (one
    variable with constraints: their values in a second panel), a Figure."""
    ok = [h for h in history if h["status"] == "ok"]
    keys = [v.key for v in variables]
    two = len(keys) == 1 and len(constraints) > 0
    fig = new_figure((7.0, 7.0 if two else 5.0))
    ax = fig.add_subplot(211 if two else 111)
    if two:
        _constraints_panel(fig.add_subplot(212, sharex=ax), ok, keys[0], constraints)
    if len(keys) == 1:
        for group, style in ((True, dict(color="tab:blue", mfc="tab:blue")),
                             (False, dict(color="tab:red", mfc="none"))):
            pts = sorted((h["values"][keys[0]], h["objective"]) for h in ok
                         if h["feasible"] == group)
            if pts:
                x, y = np.array(pts).T
                ax.plot(x, y, "o", ms=5, label="feasible" if group else
                        "violates a constraint", **style)
        if best is not None:
            ax.axvline(best["values"][keys[0]], color="k", ls="--", lw=1,
                       label=f"best {keys[0]} = {best['values'][keys[0]]:.6g}")
        ax.set_xlabel(keys[0])
        ax.set_ylabel(label)
        if variables[0].log:
            ax.set_xscale("log")
    else:
        x = np.array([h["values"][keys[0]] for h in ok], float)
        y = np.array([h["values"][keys[1]] for h in ok], float)
        z = np.array([h["objective"] for h in ok], float)
        if x.size >= 6 and np.ptp(x) > 0 and np.ptp(y) > 0:
            try:
                cs = ax.tricontourf(x, y, z, levels=14, cmap="viridis", alpha=0.6)
                fig.colorbar(cs, ax=ax, label=label)
            except (ValueError, RuntimeError):
                pass            # degenerate triangulation: the points alone
        feas = np.array([h["feasible"] for h in ok], bool)
        sc = ax.scatter(x[feas], y[feas], c=z[feas], cmap="viridis", edgecolors="k", s=28,
                        label="feasible")
        if np.any(~feas):
            ax.scatter(x[~feas], y[~feas], facecolors="none", edgecolors="tab:red", s=28,
                       label="violates a constraint")
        if x.size < 6 and np.any(feas):
            fig.colorbar(sc, ax=ax, label=label)
        if best is not None:
            ax.plot(best["values"][keys[0]], best["values"][keys[1]], "*", color="tab:orange",
                    ms=16, mec="k", label="best")
        ax.set_xlabel(keys[0])
        ax.set_ylabel(keys[1])
        for v, setter in zip(variables, (ax.set_xscale, ax.set_yscale)):
            if v.log:
                setter("log")
    ax.set_title(plain_title(title), fontsize=9)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)
    return fig
