"""Colour maps of an operating map over (driving speed, input torque), PNG.

* ``map_class.png``: the motion class of every point (period 1 / 2 / 3+, quasi-periodic,
  chaotic, not settled, ...) as categorical colours with a legend, one panel per sweep
  direction (the colours of the sweep's class band, :mod:`.sweep`);
* ``map_impacts_<mesh>.png``: contact onsets (both flanks) per mesh period;
* ``map_rattle_<mesh>.png``: impact energy per period (log colour scale);
* ``map_max_force_<mesh>.png``: the largest mesh force [N].

Where the map has bifurcation curves (``curve_*`` arrays) they are drawn over every panel:
LP (fold: the jump region's boundaries) solid black, PD (period-doubling) dashed magenta.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..figure import new_figure, plain_title, save_figure
from .sweep import CLASS_COLOURS, class_categories

__all__ = ["write_map_figures", "plot_class_map", "plot_value_map"]

_CURVE_STYLE = {"LP": dict(color="black", ls="-", marker="o"),
                "PD": dict(color="magenta", ls="--", marker="s")}


def _curves(arrays):
    start = np.asarray(arrays.get("curve_start", [0]), dtype=int)
    labels = [str(x) for x in arrays.get("curve_label", [])]
    for n, label in enumerate(labels):
        sl = slice(start[n], start[n + 1])
        yield label, np.asarray(arrays["curve_rpm"])[sl], np.asarray(arrays["curve_torque"])[sl]


def _draw_curves(ax, arrays) -> None:
    seen = set()
    for label, rpm, torque in _curves(arrays):
        st = _CURVE_STYLE.get(label, dict(color="grey", ls=":", marker="x"))
        ax.plot(rpm, torque, lw=1.6, ms=3.5, label=None if label in seen else label, **st)
        seen.add(label)
    if seen:
        ax.legend(loc="lower right", fontsize=7, framealpha=0.8)


def _edges(c: np.ndarray) -> np.ndarray:
    """Cell edges around centres ``c`` (one centre: +-0.5 around it, or +-5 % of it)."""
    c = np.asarray(c, dtype=float)
    if c.size == 1:
        h = 0.05 * abs(c[0]) or 0.5
        return np.array([c[0] - h, c[0] + h])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[2 * c[0] - mid[0]], mid, [2 * c[-1] - mid[-1]]])


def _panels(arrays, figsize_per=(6.2, 4.0)):
    dirs = [str(d) for d in arrays["direction"]]
    fig = new_figure((figsize_per[0] * len(dirs) + 1.5, figsize_per[1]))
    axes = [fig.add_subplot(1, len(dirs), j + 1) for j in range(len(dirs))]
    for j, ax in enumerate(axes):
        ax.set_xlabel("driving speed [rpm]")
        if j == 0:
            ax.set_ylabel("input torque [N m]")
        ax.set_title(f"sweep {dirs[j]}", fontsize=9)
    return fig, axes, dirs


def plot_class_map(arrays, *, title: str = ""):
    """The motion class of every point as categorical colours (module docstring), a Figure
    laid out (the writer saves it with ``tight=False``)."""
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    fig, axes, _ = _panels(arrays)
    cmap = ListedColormap([c for _, c in CLASS_COLOURS])
    norm = BoundaryNorm(np.arange(len(CLASS_COLOURS) + 1) - 0.5, len(CLASS_COLOURS))
    xe, ye = _edges(arrays["rpm"]), _edges(arrays["torque"])
    used = set()
    for j, ax in enumerate(axes):
        mc, pn = arrays["motion_class"][j], arrays["period_n"][j]
        cats = class_categories(np.where(mc < 0, 0, mc).ravel(), pn.ravel()).reshape(mc.shape)
        cats = np.ma.masked_where(mc < 0, cats)
        used |= set(int(c) for c in np.unique(cats.compressed()))
        ax.pcolormesh(xe, ye, cats, cmap=cmap, norm=norm, shading="flat")
        _draw_curves(ax, arrays)
    handles = [Patch(color=CLASS_COLOURS[c][1], label=CLASS_COLOURS[c][0]) for c in sorted(used)]
    fig.legend(handles=handles, loc="center right", fontsize=8, frameon=False,
               title="motion class", title_fontsize=8)
    fig.suptitle(plain_title(title), fontsize=10)
    fig.tight_layout(rect=(0, 0, 1 - 1.4 / fig.get_figwidth(), 1))
    return fig


def plot_value_map(arrays, key, *, label: str, title: str = "", log: bool = False):
    """A colour map of ``arrays[key]`` (directions x loads x speeds); failed points blank; a
    Figure (the writer saves it with ``tight=False``)."""
    from matplotlib.colors import LogNorm

    fig, axes, _ = _panels(arrays)
    v = np.ma.masked_where(~np.asarray(arrays["ok"], bool), np.asarray(arrays[key], float))
    norm = None
    if log:
        pos = v.compressed()[v.compressed() > 0]
        if pos.size:
            norm = LogNorm(vmin=pos.min(), vmax=pos.max())
            v = np.ma.masked_where(v <= 0, v)
    vmin = None if norm is not None else float(v.min()) if v.count() else None
    vmax = None if norm is not None else float(v.max()) if v.count() else None
    xe, ye = _edges(arrays["rpm"]), _edges(arrays["torque"])
    for j, ax in enumerate(axes):
        mesh = ax.pcolormesh(xe, ye, v[j], cmap="viridis", shading="flat", norm=norm,
                             vmin=vmin, vmax=vmax)
        _draw_curves(ax, arrays)
    fig.colorbar(mesh, ax=axes, label=label, fraction=0.04, pad=0.02)
    fig.suptitle(plain_title(title), fontsize=10)
    return fig


def write_map_figures(arrays, meshes, out, *, title: str = "",
                      energy_unit: str = "model units") -> dict:
    """Every figure of a map saved into ``out`` (PNG); returns {name: path}."""
    out = Path(out)

    def save(fig, stem):
        return save_figure(fig, out / stem, formats=("png",), tight=False)[0]

    files = {"class_png": save(plot_class_map(arrays, title=title), "map_class")}
    for m in meshes:
        files[f"impacts_{m}_png"] = save(plot_value_map(
            arrays, f"impacts_{m}",
            label=f"{m}: contact onsets per mesh period (both flanks)", title=title),
            f"map_impacts_{m}")
        files[f"rattle_{m}_png"] = save(plot_value_map(
            arrays, f"rattle_{m}", log=True,
            label=f"{m}: impact energy per period [{energy_unit}]", title=title),
            f"map_rattle_{m}")
        files[f"max_force_{m}_png"] = save(plot_value_map(
            arrays, f"max_force_{m}", label=f"{m}: largest mesh force [N]", title=title),
            f"map_max_force_{m}")
    return files
