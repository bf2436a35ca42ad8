"""Work-precision views of the ``report`` analysis (CSV tables and log-log plots).

``plot_work_precision``: integrator error against wall time and against rtol, each point
annotated with its tolerance, the fitted slopes in the legend.
``plot_shooting_precision``: shooting residual, u0 error and Floquet-multiplier error
against wall time and against the shooting tolerance.
``plot_accuracy_rule``: a gearbox's mesh-deformation error against steps per mesh period and
against rtol, per calibration point, with the fitted rule and the rtol it picks for the
accuracy asked for (vibrogear.analyses.study.tolerances_for).
Matplotlib ``Figure`` objects with the Agg canvas: no pyplot state.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ...pipeline.files import atomic_write_csv
from ..figure import new_figure, plain_title

__all__ = ["write_table", "plot_work_precision", "plot_shooting_precision",
           "plot_accuracy_rule"]


def write_table(path, table: dict, columns) -> Path:
    """Write the named columns of ``table`` (equal-length arrays) as CSV (atomically)."""
    cols = [np.asarray(table[c]) for c in columns]
    return atomic_write_csv(Path(path), columns, [[_fmt(v) for v in row] for row in zip(*cols)])


def _fmt(v) -> str:
    v = v.item() if hasattr(v, "item") else v
    if isinstance(v, bool):
        return str(int(v))
    if isinstance(v, float):
        return f"{v:.6e}"
    return str(v)


def _figure(ncols: int):
    fig = new_figure((5.0 * ncols, 4.6))
    return fig, [fig.add_subplot(1, ncols, k + 1) for k in range(ncols)]


def _finish(fig, axes, title):
    """Grid and legend on every axis, and the title: the Figure."""
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, loc="best")
    if title:
        fig.suptitle(plain_title(title), fontsize=9)
    return fig


def _annotate(ax, xs, ys, labels, color="0.25") -> None:
    for x, y, lab in zip(xs, ys, labels):
        if np.isfinite(x) and np.isfinite(y) and x > 0 and y > 0:
            ax.annotate(lab, (x, y), textcoords="offset points", xytext=(5, 3), fontsize=7,
                        color=color)


def _guide(ax, x, y, slope: float, label: str, **kw) -> None:
    """A line of the given log-log slope through the geometric centre of (x, y)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = (x > 0) & (y > 0)
    if np.count_nonzero(ok) < 2 or not np.isfinite(slope):
        return
    lx, ly = np.log(x[ok]), np.log(y[ok])
    xs = np.array([lx.min(), lx.max()])
    ax.plot(np.exp(xs), np.exp(ly.mean() + slope * (xs - lx.mean())), label=label, **kw)


def plot_work_precision(table: dict, slopes: dict, *, title: str = ""):
    """Left: error vs wall time; right: error vs rtol (with the fitted slope); a Figure."""
    fig, (a1, a2) = _figure(2)
    rtol = np.asarray(table["rtol"], float)
    err = np.asarray(table["error"], float)
    wall = np.asarray(table["wall_s"], float)
    steps = np.asarray(table["steps"])
    tags = [f"rtol {r:.0e}" for r in rtol]

    a1.loglog(wall * 1e3, err, "o-", color="tab:blue", label="DOPRI5 + event location")
    _annotate(a1, wall * 1e3, err, [f"{t}, {s} steps" for t, s in zip(tags, steps)])
    a1.set_xlabel("wall time [ms] (best of repeats)")
    a1.set_ylabel("max |q - q_exact| on the sample grid")
    a1.set_title(f"error vs work: order {slopes.get('order', np.nan):.2f} (vs steps)", fontsize=9)

    a2.loglog(rtol, err, "s-", color="tab:red", label="measured")
    _guide(a2, rtol, err, slopes.get("error_vs_rtol", np.nan),
           f"fit: slope {slopes.get('error_vs_rtol', np.nan):.2f}", color="0.3", ls="--", lw=1)
    a2.loglog(rtol, rtol, ":", color="0.6", lw=1, label="error = rtol")
    _annotate(a2, rtol, err, [f"{e:.1e}" for e in err])
    a2.set_xlabel("rtol (atol = rtol * 1e-2)")
    a2.set_ylabel("max |q - q_exact|")
    a2.set_title("tolerance proportionality", fontsize=9)
    return _finish(fig, (a1, a2), title)


def plot_shooting_precision(table: dict, *, title: str = ""):
    """Left: residual / errors vs wall time; right: the same vs the shooting tolerance; a
    Figure."""
    fig, (a1, a2) = _figure(2)
    tol = np.asarray(table["tol"], float)
    wall = np.asarray(table["wall_s"], float) * 1e3
    its = np.asarray(table["iterations"])
    curves = (("residual", "o-", "tab:blue", "periodicity residual"),
              ("u0_error", "s-", "tab:red", "|u0 - u0_exact|"),
              ("floquet_error", "^-", "tab:green", "|mu - mu_exact|"))
    for key, mk, col, lab in curves:
        y = np.asarray(table[key], float)
        a1.loglog(wall, y, mk, color=col, label=lab)
        a2.loglog(tol, y, mk, color=col, label=lab)
    _annotate(a1, wall, np.asarray(table["u0_error"], float),
              [f"tol {t:.0e}, {i} it" for t, i in zip(tol, its)])
    a2.loglog(tol, tol, ":", color="0.6", lw=1, label="= tol")
    a1.set_xlabel("wall time [ms] (best of repeats)")
    a1.set_ylabel("residual / error")
    a1.set_title("shooting: accuracy vs work", fontsize=9)
    a2.set_xlabel("shooting tol (integrator rtol = tol)")
    a2.set_title("shooting: accuracy vs tolerance", fontsize=9)
    return _finish(fig, (a1, a2), title)


def plot_accuracy_rule(points, rule: dict, accuracy: float, chosen_rtol: float, *,
                       title: str = ""):
    """``points``: dicts with ``label``, ``rtols``, ``errors``, ``steps_per_period``; ``rule``:
    coefficient, exponent, safety (err = c rtol^p; the rtol picked meets accuracy / safety).
    Left: error vs steps per mesh period (work); right: error vs rtol with the fit.  A
    Figure."""
    fig, (a1, a2) = _figure(2)
    for k, pt in enumerate(points):
        col = f"C{k % 10}"
        r, e = np.asarray(pt["rtols"], float), np.asarray(pt["errors"], float)
        a1.loglog(np.asarray(pt["steps_per_period"], float), e, "o-", ms=3, color=col,
                  label=pt["label"])
        a2.loglog(r, e, "o", ms=3, color=col)
        j = int(np.argmin(np.abs(np.log(r / chosen_rtol))))
        a1.plot(pt["steps_per_period"][j], e[j], "*", ms=9, color=col)
    xs = np.logspace(-10, -3, 50)
    c, p, sf = rule["coefficient"], rule["exponent"], rule["safety"]
    a2.loglog(xs, c * xs ** p, "--", color="0.3", lw=1, label=f"fit: {c:.3g} rtol^{p:.3f}")
    a2.loglog(xs, sf * c * xs ** p, ":", color="0.3", lw=1, label=f"fit x safety {sf:g}")
    for ax in (a1, a2):
        ax.axhline(accuracy, color="tab:red", lw=1, label=f"accuracy asked {accuracy:g}")
    a2.axvline(chosen_rtol, color="tab:green", lw=1, label=f"rtol chosen {chosen_rtol:.2g}")
    a1.set_xlabel("steps per mesh period (star: the rtol chosen)")
    a1.set_ylabel("max |delta - delta_ref| / range(delta_ref)")
    a1.set_title("mesh-deformation error vs work", fontsize=9)
    a2.set_xlabel("rtol (atol = 1e-6 rtol)")
    a2.set_title("error vs tolerance: the rule", fontsize=9)
    return _finish(fig, (a1, a2), title)
