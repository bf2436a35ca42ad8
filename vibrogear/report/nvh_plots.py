"""Figures of ``nvh``: speed-frequency waterfalls with order lines, ERP against speed."""
from __future__ import annotations

import numpy as np

from .figure import new_figure, save_figure

__all__ = ["plot_waterfall", "plot_erp"]

_LINE_STYLES = ("-", "--", ":", "-.")


def _edges(x: np.ndarray) -> np.ndarray:
    """Cell edges around the centres ``x`` (midpoints, the ends mirrored)."""
    mid = 0.5 * (x[1:] + x[:-1])
    return np.concatenate([[2 * x[0] - mid[0]], mid, [2 * x[-1] - mid[-1]]])


def plot_waterfall(path, rpm, freq_hz, amp, *, label: str, unit: str, max_hz: float,
                   mesh_hz, shaft_hz, max_order: float, shaft_names=(), title: str = "",
                   power: bool = False, lines=None):
    """Colour map of ``amp`` (P, K) [unit] over frequency (P, K) [Hz] and speed (P,) [rpm],
    in dB re the largest amplitude, with mesh order lines h x f_mesh (h = 1 .. max_order,
    each mesh) and 1x shaft order lines.  Each bin is drawn as the cell of its order
    (frequency proportional to speed), so lines at a fixed order stay on their bins.  One
    speed: the spectrum as a line.  ``power``: ``amp`` is a power (10 log10 instead of
    20 log10).  ``lines``: (frequency, rpm, kind) of the named spectral lines, marked by
    kind (unidentified: a white x)."""
    rpm, freq_hz, amp = np.asarray(rpm), np.asarray(freq_hz), np.asarray(amp)
    ref = float(np.max(amp[:, 1:])) if amp.shape[1] > 1 and np.max(amp[:, 1:]) > 0 else 1.0
    floor = 1e-12 if power else 1e-6                      # -120 dB / -120 dB
    level = (10.0 if power else 20.0) * np.log10(np.maximum(amp, ref * floor) / ref)
    fig = new_figure((8.0, 5.5))
    ax = fig.add_subplot(111)
    if rpm.size >= 2:
        hz_per_rpm = freq_hz[0] / rpm[0]                  # (K,): bin k at order k / R
        r_edges = _edges(rpm)
        k_edges = _edges(hz_per_rpm)
        X = np.outer(r_edges, k_edges)
        Y = np.repeat(r_edges[:, None], k_edges.size, axis=1)
        mesh = ax.pcolormesh(X, Y, level, shading="flat", cmap="viridis", vmin=-80.0, vmax=0.0)
        fig.colorbar(mesh, ax=ax, label=f"{label}, dB re {ref:.3g} {unit}")
        speeds = np.array([r_edges[0], r_edges[-1]])
        scale = speeds / rpm.min()
        for i, f0 in enumerate(np.atleast_1d(np.asarray(mesh_hz)[0])):
            for h in range(1, int(np.floor(max_order)) + 1):
                ax.plot(h * f0 * scale, speeds, color="w", lw=0.8,
                        ls=_LINE_STYLES[i % len(_LINE_STYLES)],
                        label=f"mesh {i + 1} orders 1..{int(max_order)}" if h == 1 else None)
        for i, f0 in enumerate(np.atleast_1d(np.asarray(shaft_hz)[0])):
            name = shaft_names[i] if i < len(shaft_names) else f"shaft {i}"
            ax.plot(f0 * scale, speeds, color="r", lw=0.8,
                    ls=_LINE_STYLES[i % len(_LINE_STYLES)], label=f"{name} 1x")
        _mark_lines(ax, lines, max_hz)
        ax.set_ylabel("driving speed [rpm]")
        ax.legend(loc="lower right", fontsize=7, framealpha=0.6)
    else:
        ax.plot(freq_hz[0], level[0], lw=1.0)
        ax.set_ylabel(f"{label}, dB re {ref:.3g} {unit}")
        ax.set_ylim(-80.0, 5.0)
        for f0 in np.atleast_1d(np.asarray(mesh_hz)[0]):
            for h in range(1, int(np.floor(max_order)) + 1):
                ax.axvline(h * f0, color="0.6", lw=0.6, ls="--")
    ax.set_xlim(0.0, max_hz)
    ax.set_xlabel("frequency [Hz]")
    ax.set_title(title, fontsize=9)
    return save_figure(fig, path, formats=("png",))


_KIND_STYLE = {"mesh": ("o", "w"), "shaft": ("s", "tab:red"), "free gear": ("D", "tab:orange"),
               "bearing": ("^", "tab:pink"), "mode": ("v", "tab:cyan"),
               "base": ("*", "yellow"), "combination": ("P", "tab:olive"),
               "unidentified": ("x", "w")}


def _mark_lines(ax, lines, max_hz: float):
    """The named lines as markers by kind (drawn below ``max_hz``)."""
    if lines is None:
        return
    f, rpm, kind = (np.asarray(a) for a in lines)
    keep = f <= max_hz
    for k, (marker, colour) in _KIND_STYLE.items():
        sel = keep & (kind == k)
        if np.any(sel):
            ax.plot(f[sel], rpm[sel], marker, ms=3.0, mfc="none" if k != "base" else colour,
                    mec=colour, lw=0, mew=0.7, label=f"line: {k}")


def plot_erp(path, rpm, erp_w, *, title: str = ""):
    """ERP against speed in W (log scale) and in dB re 1e-12 W (right axis)."""
    rpm, erp_w = np.asarray(rpm), np.asarray(erp_w)
    fig = new_figure((8.0, 4.5))
    ax = fig.add_subplot(111)
    ok = erp_w > 0
    ax.semilogy(rpm[ok], erp_w[ok], "o-", ms=3, lw=1.0)
    ax.set_xlabel("driving speed [rpm]")
    ax.set_ylabel("ERP [W]")
    ax.grid(True, which="both", alpha=0.3)
    lo, hi = ax.get_ylim()
    right = ax.twinx()
    right.set_ylim(10 * np.log10(lo / 1e-12), 10 * np.log10(hi / 1e-12))
    right.set_ylabel("ERP [dB re 1e-12 W]")
    ax.set_title(title, fontsize=9)
    return save_figure(fig, path, formats=("png",))
