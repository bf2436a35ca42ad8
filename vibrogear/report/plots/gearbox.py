"""Gearbox figures: resonance map, time response with contact forces."""
from __future__ import annotations

import numpy as np

from ..figure import new_figure, plain_title

__all__ = ["plot_resonance_map", "resonance_map_figure", "plot_gearbox_time_response"]


def _grey(s: float):
    return (0.8 - 0.8 * min(1.0, 4 * s),) * 3


def plot_resonance_map(f_hz, mesh, teeth: int, rpm_lo: float, rpm_hi: float, *,
                       title: str = "", f_max: float | None = None, orders=None,
                       crossings=()):
    """Natural frequencies (horizontal lines, darker = more mesh strain energy, with its
    scale) against the orders 1x and 2x of every mesh's frequency over the speed range; the
    crossings with modes of mesh strain-energy share > 5 % are the resonance speeds, marked
    and written on the speed axis.  ``orders``: [(mesh name, Hz per rpm)] (default: one
    mesh of ``teeth`` teeth on the driving shaft); ``crossings``: the resonance speeds of
    the modes analysis (dicts with rpm, frequency_hz, mesh, mesh_order).  Returns the Figure
    (the report writer saves it)."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import LinearSegmentedColormap, Normalize

    if not rpm_hi > rpm_lo:               # a single speed: a span around it
        rpm_lo, rpm_hi = 0.5 * rpm_lo, max(1.5 * rpm_lo, 1.0)
    orders = list(orders) if orders else [("mesh", teeth / 60.0)]
    fig = new_figure((8.5, 5.4))
    ax = fig.add_subplot(111)
    rpm = np.linspace(rpm_lo, rpm_hi, 2)
    top = 2.2 * max(p for _, p in orders) * rpm_hi if f_max is None else f_max
    share = mesh.max(axis=0) if mesh.size else np.zeros_like(f_hz)
    for f, s in zip(f_hz, share):
        if f <= top:
            ax.axhline(f, color=_grey(s), lw=0.6 + 2.0 * min(1.0, 4 * s), zorder=1)
    for j, (name, per_rpm) in enumerate(orders):
        for h, style in ((1, "-"), (2, "--")):
            ax.plot(rpm, h * per_rpm * rpm, style, color=f"C{(3 + j) % 10}", lw=1.5, zorder=2,
                    label=f"{name} {h}x mesh frequency")
    cross = list(crossings)
    last = -np.inf
    lane = 0
    for c in cross:
        ax.plot(c["rpm"], c["frequency_hz"], "o", ms=6, mfc="none", mec="k", mew=1.2, zorder=4)
        ax.axvline(c["rpm"], color="k", lw=0.6, ls=":", zorder=1)
        close = c["rpm"] - last < 0.07 * (rpm_hi - rpm_lo)
        lane = (lane + 1) % 3 if close else 0
        last = c["rpm"]
        right = c["rpm"] > rpm_lo + 0.85 * (rpm_hi - rpm_lo)     # keep it inside the axes
        ax.annotate(f"{c['rpm']:.0f} rpm\n{c['mesh']} {c['mesh_order']}x", (c["rpm"], 0.0),
                    xytext=(-2 if right else 2, 3 + 20 * lane), textcoords="offset points",
                    ha="right" if right else "left", fontsize=7,
                    zorder=5, bbox=dict(boxstyle="square,pad=0.1", fc="white", ec="none",
                                        alpha=0.8))
    ax.set_xlim(rpm_lo, rpm_hi)
    ax.set_ylim(0.0, top)
    ax.set_xlabel("driving speed [rpm]")
    ax.set_ylabel("frequency [Hz]")
    if cross:
        from matplotlib.lines import Line2D
        handles = ax.get_legend_handles_labels()[0] + [Line2D(
            [], [], marker="o", mfc="none", mec="k", lw=0, label="resonance (share > 5 %)")]
    else:
        handles = ax.get_legend_handles_labels()[0]
    ax.legend(handles=handles, loc="upper left", fontsize=7, framealpha=0.85)
    greys = LinearSegmentedColormap.from_list("share", [_grey(0.0), _grey(0.25)])
    bar = fig.colorbar(ScalarMappable(Normalize(0.0, 25.0), greys), ax=ax, pad=0.02,
                       extend="max")
    bar.set_label("mode's mesh strain-energy share [%]", fontsize=8)
    head = plain_title(title)
    ax.set_title((head + "\n" if head else "") + "natural frequencies against the mesh "
                 "orders: crossings are resonance speeds", fontsize=9)
    return fig


def plot_gearbox_time_response(t_s, delta, ddot, force, mesh_names, bearing_forces, *,
                               mesh_period_s: float, backlash=(), title: str = ""):
    """Mesh deformations (zero line: mesh interruption below), phase trajectories of the
    last half, mesh forces and the total radial load of each bearing's elements, as a
    Figure (the report writer saves it)."""
    fig = new_figure((11.0, 8.0))
    axes = fig.subplots(3, 2, gridspec_kw={"width_ratios": [2.2, 1]})
    tp = t_s / mesh_period_s
    half = t_s >= 0.5 * t_s[-1]
    for j, name in enumerate(mesh_names[:2]):
        ax, ph = axes[j]
        ax.plot(tp, delta[j] * 1e6, lw=0.6)
        ax.axhline(0.0, color="k", lw=0.7)
        # the back flank (-backlash) only when the motion comes near it
        if j < len(backlash) and np.isfinite(backlash[j]) and \
                np.min(delta[j]) < 0.5 * backlash[j]:
            ax.axhline(backlash[j] * 1e6, color="0.5", ls=":", lw=0.8, label="back flank")
        ax.set_ylabel(f"{name} deformation [um]")
        ph.plot(delta[j, half] * 1e6, ddot[j, half] * 1e3, lw=0.5)
        ph.axvline(0.0, color="k", lw=0.7)
        ph.set_xlabel(f"{name} deformation [um]")
        ph.set_ylabel("rate [mm/s]")
        ph.set_title("phase trajectory (second half)", fontsize=8)
    ax, fx = axes[2]
    for j, name in enumerate(mesh_names):
        ax.plot(tp, force[j], lw=0.6, label=f"mesh {name}")
    ax.set_ylabel("mesh force [N]")
    ax.set_xlabel("time / mesh period")
    ax.legend(fontsize=7, loc="upper right")
    for name, f in bearing_forces.items():
        fx.plot(tp, f, lw=0.6, label=name)
    fx.set_xlabel("time / mesh period")
    fx.set_ylabel("sum of element forces [N]")
    if bearing_forces:
        fx.legend(fontsize=6)
    else:
        fx.text(0.5, 0.5, "no rolling-element bearings", ha="center", transform=fx.transAxes)
    if len(mesh_names) < 2:
        axes[1, 0].set_visible(False)
        axes[1, 1].set_visible(False)
    fig.suptitle(plain_title(title), fontsize=9)
    return fig


def resonance_map_figure(r):
    """The resonance map of a gearbox's modes
    (:class:`~vibrogear.analyses.gearbox_modes.GearboxModesResult`) as a Figure, the
    report's ``resonance_map.png``."""
    return plot_resonance_map(r.f_hz, r.mesh, r.mesh_teeth, r.rpm_lo, r.rpm_hi, title=r.title,
                              orders=r.orders, crossings=r.resonances)
