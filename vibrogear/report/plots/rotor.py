"""Rotor plots: Campbell diagram and mode shapes, as Figures (the report writer saves them
as PNG + SVG).  Takes result objects only."""
from __future__ import annotations

import numpy as np

from ..figure import new_figure

__all__ = ["plot_campbell", "plot_mode_shapes"]

_WHIRL_STYLE = {"forward": ("tab:blue", "-"), "backward": ("tab:red", "--"),
                "mixed": ("tab:purple", "-."), "-": ("0.4", ":")}


def plot_campbell(result, *, title: str = ""):
    """Frequency lines coloured by whirl at each speed, order lines, critical speeds; a
    Figure."""
    fig = new_figure((7.0, 4.8))
    ax = fig.subplots()
    s = result.speeds_rpm
    for line in range(result.frequencies_hz.shape[1]):
        f = result.frequencies_hz[:, line]
        w = result.whirl[:, line]
        for i in range(len(s) - 1):
            key = w[i] if w[i] in _WHIRL_STYLE else "-"
            color, ls = _WHIRL_STYLE[key]
            ax.plot(s[i:i + 2], f[i:i + 2], color=color, ls=ls, lw=1.6)
    fmax = np.nanmax(result.frequencies_hz) * 1.05
    for order in result.orders:
        ax.plot(s, order * s / 60.0, color="k", lw=0.9)
        x_end = min(s[-1], fmax * 60.0 / order)
        ax.annotate(f"{order:g}x", (x_end, order * x_end / 60.0), fontsize=8,
                    xytext=(2, 2), textcoords="offset points")
    for c in result.critical_speeds:
        ax.plot(c.speed_rpm, c.frequency_hz, "o", mfc="none", mec="k", ms=6)
    for key, (color, ls) in _WHIRL_STYLE.items():
        ax.plot([], [], color=color, ls=ls, label={"-": "axial / torsional"}.get(key, key))
    ax.plot([], [], "o", mfc="none", mec="k", label="critical speed")
    ax.set(xlim=(s[0], s[-1]), ylim=(0, fmax), xlabel="spin speed [rpm]",
           ylabel="frequency [Hz]", title=title or "Campbell diagram")
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    return fig


def plot_mode_shapes(model, modes, *, n: int = 6, title: str = ""):
    """Deflection of the first ``n`` modes along the shaft (|u|, |v| for lateral modes, the
    axial or torsional component otherwise), normalised to 1; a Figure."""
    k = min(n, modes.shapes.shape[1])
    fig = new_figure((7.0, 1.2 + 1.1 * k))
    axes = fig.subplots(k, 1, sharex=True, squeeze=False)
    z = model.node_z
    idx = 6 * np.arange(model.n_nodes)
    for j in range(k):
        ax = axes[j, 0]
        x = modes.shapes[:, j]
        if modes.mode_type[j] == "lateral":
            curves = {"u": np.real(x[idx]), "v": np.real(x[idx + 1])}
        elif modes.mode_type[j] == "axial":
            curves = {"w": np.real(x[idx + 2])}
        else:
            curves = {"psi": np.real(x[idx + 5])}
        scale = max(np.abs(np.concatenate(list(curves.values()))).max(), 1e-300)
        for name, c in curves.items():
            ax.plot(z, c / scale, marker=".", label=name)
        for nd in model.bearing_nodes:
            ax.axvline(z[nd], color="0.6", lw=0.8)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_ylabel(f"{j + 1}")
        ax.text(0.99, 0.9, f"{modes.frequencies_hz[j]:.2f} Hz  {modes.mode_type[j]}"
                f"{'' if modes.whirl[j] == '-' else ' ' + modes.whirl[j]}",
                transform=ax.transAxes, ha="right", va="top", fontsize=8)
        ax.legend(fontsize=7, loc="lower left")
    axes[-1, 0].set_xlabel("z [m]")
    axes[0, 0].set_title(title or f"mode shapes at {modes.speed_rpm:g} rpm (real part)")
    return fig
