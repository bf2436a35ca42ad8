"""Reduction-level study: tables and the error-against-run-time figure."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..figure import new_figure, plain_title
from ...pipeline.files import atomic_write_bytes

__all__ = ["write_reduction_tables", "plot_reduction_study"]

_COLS = ("level", "shaft_modes", "housing_modes", "m", "modes_compared", "max_freq_error", "min_mac",
         "period_n", "judged_by", "response_error", "extrema_error", "statistics_error",
         "statistics_error_bar", "f_top_hz", "build_s", "sim_wall_s", "steps", "status")


def _cell(v) -> str:
    """A CSV cell: floats to 6 digits, missing or non-finite values empty."""
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return ""
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def write_reduction_tables(out_dir, rows, extra=()) -> dict:
    """reduction_levels.csv (a row per level: ``rows``, the count levels, then ``extra``,
    the frequency-criterion levels; empty cells where a value does not apply, e.g. the
    pointwise errors of non-periodic motion) and reduction_modes.csv (full vs reduced frequency and
    MAC per mode at the largest count level; reduction_modes_frequency.csv: at the first
    extra level)."""
    out = Path(out_dir)
    lines = [",".join(_COLS)]
    for r in list(rows) + list(extra):
        lines.append(",".join(_cell(r.get(c)) for c in _COLS))
    p1 = atomic_write_bytes(out / "reduction_levels.csv", ("\n".join(lines) + "\n").encode())
    pairs = rows[-1].get("pairs", [])
    lines = ["index,f_full_hz,f_reduced_hz,rel_error,mac"]
    lines += [f"{i},{p['f_full_hz']:.6g},{p['f_reduced_hz']:.6g},{p['rel_error']:.4g},"
              f"{p['mac']:.5f}" for i, p in enumerate(pairs)]
    p2 = atomic_write_bytes(out / "reduction_modes.csv", ("\n".join(lines) + "\n").encode())
    p3 = atomic_write_bytes(out / "reduction_levels.json",
                            json.dumps(list(rows) + list(extra), indent=1,
                                       default=float).encode())
    paths = {"levels": p1, "modes": p2, "json": p3}
    if extra and extra[0].get("pairs"):
        lines = ["index,f_full_hz,f_reduced_hz,rel_error,mac"]
        lines += [f"{i},{p['f_full_hz']:.6g},{p['f_reduced_hz']:.6g},{p['rel_error']:.4g},"
                  f"{p['mac']:.5f}" for i, p in enumerate(extra[0]["pairs"])]
        paths["modes_frequency"] = atomic_write_bytes(out / "reduction_modes_frequency.csv",
                                                      ("\n".join(lines) + "\n").encode())
    return paths


def plot_reduction_study(rows, *, title: str = ""):
    """Left: frequency error against the full model; middle: the nonlinear response's
    error against the largest level over the simulation's wall time, pointwise where the
    motion is periodic, the converging statistics' error with its batch-means error bar
    (lower end clipped at the axis) where it is not; right: MAC of the largest level.  A
    Figure (the report writer saves it)."""
    fig = new_figure((13.0, 4.6))
    a1, a2, a3 = fig.subplots(1, 3)
    m = np.array([r["m"] for r in rows], float)
    wall = np.array([r["sim_wall_s"] for r in rows], float)
    ferr = np.array([r.get("max_freq_error", np.nan) for r in rows], float)
    cnt = np.array([r.get("level", "count") == "count" for r in rows])
    if np.any(np.isfinite(ferr)):
        a1.semilogy(m[cnt], np.abs(ferr[cnt]), "o-", label="master counts")
        for r, mm, fe in zip(rows, m, ferr):
            if r.get("level", "count") != "count" and np.isfinite(fe):
                a1.semilogy([mm], [abs(fe)], "*", ms=9, label=r["level"])
        a1.legend(fontsize=7)
    a1.set_xlabel("master modes m")
    a1.set_ylabel("max rel. frequency error\nvs full model")
    a1.set_title("linearised: reduced vs full", fontsize=8)
    _error_panel(a2, rows, wall, m, cnt)
    last = [r for r in rows if r.get("level", "count") == "count"][-1]
    pairs = last.get("pairs", [])
    if pairs:
        f = [p["f_full_hz"] for p in pairs]
        a3.plot(f, [p["mac"] for p in pairs], "o", ms=3)
        a3.set_ylim(0.0, 1.05)
        a3.set_xlabel("full-model frequency [Hz]")
        a3.set_ylabel("MAC (shaft DOF + bore points)")
        a3.set_title(f"largest level, m = {last['m']}", fontsize=8)
    for a in (a1, a2, a3):
        a.tick_params(labelsize=8)
    fig.suptitle(plain_title(title), fontsize=9)
    return fig


def _error_panel(ax, rows, wall, m, cnt):
    """Error against run time of the levels below the largest (its own error is 0)."""
    judged = rows[0].get("judged_by", "pointwise") if rows else "pointwise"
    rerr = np.array([r.get("response_error", np.nan) for r in rows], float)
    serr = np.array([r.get("statistics_error", np.nan) for r in rows], float)
    sbar = np.array([r.get("statistics_error_bar", np.nan) for r in rows], float)
    ok = np.isfinite(rerr) & (rerr > 0)
    if np.any(ok):
        ax.loglog(wall[ok & cnt], rerr[ok & cnt], "s-", color="C0",
                  label="pointwise (periodic motion)")
        ax.loglog(wall[ok & ~cnt], rerr[ok & ~cnt], "*", ms=9, color="C0")
    st = np.isfinite(serr) & (serr > 0)
    if np.any(st):
        bar = np.where(np.isfinite(sbar), sbar, 0.0)
        lower = np.minimum(bar, 0.9 * serr)          # log axis: keep the bar above 0
        for sel, mk in ((st & cnt, "o"), (st & ~cnt, "*")):
            if np.any(sel):
                ax.errorbar(wall[sel], serr[sel], yerr=[lower[sel], bar[sel]], fmt=mk,
                            ls="-" if mk == "o" else "none", color="C3", capsize=3,
                            ms=5 if mk == "o" else 9,
                            label="statistics, batch-means bars" if mk == "o" else None)
        ax.set_xscale("log")
        ax.set_yscale("log")
    for x, y, mm in zip(wall, np.where(ok, rerr, serr), m):
        if np.isfinite(y) and y > 0:
            ax.annotate(f"m={mm:.0f}", (x, y), fontsize=7, xytext=(3, 3),
                        textcoords="offset points")
    _plain_log_ticks(ax)
    ax.set_xlabel("simulation wall time [s]")
    ax.set_ylabel("mesh-deformation error\nvs largest level")
    ax.set_title(f"nonlinear response, judged {judged}", fontsize=8)
    if np.any(ok) or np.any(st):
        ax.legend(fontsize=7, loc="best")


def _plain_log_ticks(ax):
    """Log axes over less than a decade: ticks at 1, 2, 5 x 10^k in plain numbers, no
    minor labels (matplotlib's default labels every minor tick there, overprinting)."""
    from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter
    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() == "log":
            axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
            axis.set_major_formatter(FormatStrFormatter("%g"))
            axis.set_minor_formatter(NullFormatter())
