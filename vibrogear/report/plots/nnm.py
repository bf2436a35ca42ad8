"""Figures of ``nnm``: the frequency-energy plot and the backbone over the forced response."""
from __future__ import annotations

from fractions import Fraction

import numpy as np

from .branch import stability_segments
from ..figure import new_figure, plain_title

__all__ = ["plot_fep", "plot_backbone"]

_COLORS = ("tab:red", "tab:blue", "tab:green", "tab:purple")


def _draw(ax, x, y, stable, color, name):
    first = True
    for xs, ys, st in stability_segments(x, y, stable):
        ax.plot(xs, ys, "-" if st else "--", color=color, lw=1.6,
                label=name if first else None)
        first = False


def _labels(ax, x, y, labels):
    for xv, yv, lab in zip(x, y, labels):
        if lab:
            ax.plot([xv], [yv], "o", ms=4, color="black")
            ax.annotate(lab, (xv, yv), textcoords="offset points", xytext=(4, 4), fontsize=7)


def plot_fep(r, arrays):
    """Frequency against log energy, one line per backbone; the other modes' linear
    frequencies divided by small integers (where they fall in the plotted band) dotted; a
    Figure (the report writer saves it)."""
    fig = new_figure((8.0, 5.0))
    ax = fig.add_subplot(111)
    f, e = arrays[r.freq_key], arrays["energy"]
    for b in np.unique(arrays["branch"]):
        sel = arrays["branch"] == b
        _draw(ax, e[sel], f[sel], arrays["stable"][sel], _COLORS[int(b) % 4],
              f"NNM of mode {int(arrays['mode'][sel][0])}")
        _labels(ax, e[sel], f[sel], arrays["label"][sel])
    lo, hi = float(f.min()), float(f.max())
    pad = max(0.05 * (hi - lo), 1e-3 * hi)
    for fl in arrays["linear_frequencies"]:
        for q in range(1, 6):
            for p in range(1, 6):
                v = float(fl * Fraction(p, q))
                if Fraction(p, q).denominator == q and lo - pad <= v <= hi + pad:
                    ax.axhline(v, ls=":", lw=0.7, color="gray")
    on = np.asarray(arrays["onset_energy"], float)
    for v in on[np.isfinite(on)]:
        ax.axvline(v, ls="-.", lw=0.8, color="tab:orange", label="contact-switch energy")
    ax.set_xscale("log")
    ax.set_ylim(lo - pad, hi + pad)
    ax.set_xlabel(f"energy above the static state [{r.energy_unit}]")
    ax.set_ylabel(r.freq_label)
    ax.set_title(f"{plain_title(r.study.title)}\nfrequency-energy plot (stable solid, "
                 "unstable dashed)", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def plot_backbone(r, arrays, forced=None, sweep=None, to_freq: float = 1.0):
    """The backbone(s) in (frequency, amplitude) over the forced branches and sweep points
    (amplitude: max |delta| over the orbit, display unit); a Figure."""
    mon = r.study.monitor
    fig = new_figure((8.0, 5.0))
    ax = fig.add_subplot(111)
    if sweep is not None and np.size(sweep.get("param", [])):
        amp = np.maximum(np.abs(sweep["qmin"]), np.abs(sweep["qmax"])) * mon.scale
        ax.plot(np.asarray(sweep["param"]) * to_freq, amp, ".", ms=3, color="0.6",
                label="sweep points")
    if forced is not None and np.size(forced.get("param", [])):
        amp = np.maximum(np.abs(forced["qmin"]), np.abs(forced["qmax"])) * mon.scale
        x = np.asarray(forced["param"]) * to_freq
        for b in np.unique(forced["branch"]):
            sel = forced["branch"] == b
            _draw(ax, x[sel], amp[sel], forced["stable"][sel], "tab:gray",
                  "forced branches" if b == 0 else None)
    f, a = arrays[r.freq_key], arrays["amplitude"]
    for b in np.unique(arrays["branch"]):
        sel = arrays["branch"] == b
        _draw(ax, f[sel], a[sel], arrays["stable"][sel], _COLORS[int(b) % 4],
              f"backbone (NNM of mode {int(arrays['mode'][sel][0])})")
        _labels(ax, f[sel], a[sel], arrays["label"][sel])
    if forced is not None or sweep is not None:
        fa = f if forced is None else np.asarray(forced["param"]) * to_freq
        lo, hi = min(fa.min(), f.min()), max(fa.max(), f.max())
        ax.set_xlim(lo - 0.02 * (hi - lo), hi + 0.02 * (hi - lo))
    ax.set_xlabel(f"{r.freq_label} (forced: excitation frequency)")
    ax.set_ylabel(mon.axis_label("amplitude (largest |value|) of the"))
    ax.set_title(f"{plain_title(r.study.title)}\nbackbone over the forced response", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return fig
