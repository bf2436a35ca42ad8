"""Figures of ``nvh``: speed-frequency waterfalls with order lines, ERP against speed.

Levels are in dB re a physical reference (:data:`REFERENCES`: 1 um, 1 N, 1 pW), so that two
figures or two runs compare; the colour range is the ``span_db`` below the largest level.
Of the named spectral lines only the identified ones are marked (by kind); the unidentified
ones are counted in the title with their share of the lines' power.
"""
from __future__ import annotations

import numpy as np

from ..figure import new_figure, plain_title

__all__ = ["plot_waterfall", "plot_erp", "db_reference", "levels_db", "unidentified_note",
           "REFERENCES"]

_LINE_STYLES = ("-", "--", ":", "-.")

#: physical dB references by unit: (reference value, its label)
REFERENCES = {"m": (1e-6, "1 \u00b5m"), "N": (1.0, "1 N"), "W": (1e-12, "1 pW"),
              "m/s": (1e-9, "1 nm/s"), "Pa": (2e-5, "20 \u00b5Pa")}


def db_reference(unit: str) -> tuple[float, str]:
    """The dB reference of a quantity in ``unit`` (REFERENCES; another unit: 1 of it)."""
    return REFERENCES.get(unit, (1.0, f"1 {unit}"))


def levels_db(amp, unit: str, *, power: bool = False) -> tuple[np.ndarray, str]:
    """``amp`` [unit] in dB re :func:`db_reference` (20 log10 of an amplitude, 10 log10 of
    a power) and the reference's label; zeros at -600 dB."""
    ref, ref_label = db_reference(unit)
    factor = 10.0 if power else 20.0
    return factor * np.log10(np.maximum(np.asarray(amp, float), ref * 1e-30) / ref), ref_label


def _edges(x: np.ndarray) -> np.ndarray:
    """Cell edges around the centres ``x`` (midpoints, the ends mirrored)."""
    mid = 0.5 * (x[1:] + x[:-1])
    return np.concatenate([[2 * x[0] - mid[0]], mid, [2 * x[-1] - mid[-1]]])


def plot_waterfall(rpm, freq_hz, amp, *, label: str, unit: str, max_hz: float,
                   mesh_hz, shaft_hz, max_order: float, shaft_names=(), title: str = "",
                   power: bool = False, lines=None, unstable=None, span_db: float = 80.0,
                   mesh_names=()):
    """Colour map of ``amp`` (P, K) [unit] over frequency (P, K) [Hz] and speed (P,) [rpm]
    in dB re :func:`db_reference` (module docstring), with mesh order lines h x f_mesh
    (h = 1 .. max_order, each mesh) and 1x shaft order lines.  Each bin is drawn as the
    cell of its order (frequency proportional to speed), so lines at a fixed order stay on
    their bins.  One speed: the spectrum as a line.  ``power``: ``amp`` is a power
    (10 log10 instead of 20 log10).  ``lines``: (frequency, rpm, kind[, amplitude]) of the
    named spectral lines: the identified ones are marked by kind; the unidentified ones are
    not, and with the amplitudes their share of the lines' power is stated in the title.
    ``unstable``: (P,) bool, speeds whose orbit is unstable (not observed in operation),
    hatched in a strip at the left edge."""
    rpm, freq_hz, amp = np.asarray(rpm), np.asarray(freq_hz), np.asarray(amp)
    level, ref_label = levels_db(amp, unit, power=power)
    body = level[:, 1:] if level.shape[1] > 1 else level          # bin 0: the mean
    top = float(np.ceil(np.max(body) / 10.0) * 10.0) if body.size else 0.0
    vmin = top - span_db
    bar_label = f"{label} [dB re {ref_label}]"
    fig = new_figure((8.0, 6.0))
    ax = fig.add_subplot(111)
    note = ""
    if rpm.size >= 2:
        hz_per_rpm = freq_hz[0] / rpm[0]                  # (K,): bin k at order k / R
        r_edges = _edges(rpm)
        k_edges = _edges(hz_per_rpm)
        X = np.outer(r_edges, k_edges)
        Y = np.repeat(r_edges[:, None], k_edges.size, axis=1)
        mesh = ax.pcolormesh(X, Y, level, shading="flat", cmap="viridis", vmin=vmin, vmax=top)
        fig.colorbar(mesh, ax=ax, label=bar_label)
        speeds = np.array([r_edges[0], r_edges[-1]])
        scale = speeds / rpm.min()
        for i, f0 in enumerate(np.atleast_1d(np.asarray(mesh_hz)[0])):
            for h in range(1, int(np.floor(max_order)) + 1):
                ax.plot(h * f0 * scale, speeds, color="w", lw=0.8,
                        ls=_LINE_STYLES[i % len(_LINE_STYLES)],
                        label=(f"{mesh_names[i] if i < len(mesh_names) else f'mesh {i + 1}'}"
                               f" orders 1..{int(max_order)}") if h == 1 else None)
        for i, f0 in enumerate(np.atleast_1d(np.asarray(shaft_hz)[0])):
            name = shaft_names[i] if i < len(shaft_names) else f"shaft {i}"
            ax.plot(f0 * scale, speeds, color="r", lw=0.8,
                    ls=_LINE_STYLES[i % len(_LINE_STYLES)], label=f"{name} 1x")
        note = _mark_lines(ax, lines, max_hz)
        if unstable is not None and np.any(unstable):
            _mark_unstable(ax, r_edges, np.asarray(unstable, bool), max_hz)
        ax.set_ylabel("driving speed [rpm]")
        # below the map, on a dark ground like the map's, so the white order lines show
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=3, fontsize=7,
                  frameon=True, facecolor="0.25", edgecolor="none", framealpha=1.0,
                  labelcolor="white")
    else:
        ax.plot(freq_hz[0], level[0], lw=1.0)
        ax.set_ylabel(bar_label)
        ax.set_ylim(vmin, top + 5.0)
        for f0 in np.atleast_1d(np.asarray(mesh_hz)[0]):
            for h in range(1, int(np.floor(max_order)) + 1):
                ax.axvline(h * f0, color="0.6", lw=0.6, ls="--")
    ax.set_xlim(0.0, max_hz)
    ax.set_xlabel("frequency [Hz]")
    head = plain_title(title)
    ax.set_title(head + (f"\n{note}" if note else ""), fontsize=9)
    return fig


_KIND_STYLE = {"mesh": ("o", "w"), "shaft": ("s", "tab:red"), "free gear": ("D", "tab:orange"),
               "bearing": ("^", "tab:pink"), "mode": ("v", "tab:cyan"),
               "base": ("*", "yellow"), "combination": ("P", "tab:olive")}


def _mark_lines(ax, lines, max_hz: float) -> str:
    """The identified lines as markers by kind (drawn below ``max_hz``); returns the
    sentence on the unidentified ones ("" when there are none)."""
    if lines is None:
        return ""
    f, rpm, kind = (np.asarray(a) for a in lines[:3])
    keep = f <= max_hz
    for k, (marker, colour) in _KIND_STYLE.items():
        sel = keep & (kind == k)
        if np.any(sel):
            ax.plot(f[sel], rpm[sel], marker, ms=3.0, mfc="none" if k != "base" else colour,
                    mec=colour, lw=0, mew=0.7, label=f"line: {k}")
    return unidentified_note(lines)


def unidentified_note(lines) -> str:
    """The sentence on the unidentified lines of ``lines`` (frequency, rpm, kind[,
    amplitude[, alternatives]]): their share of the lines' power (sum of squared
    amplitudes), their count and the share of them that had candidates."""
    kind = np.asarray(lines[2])
    unknown = kind == "unidentified"
    if not np.any(unknown):
        return ""
    if len(lines) < 4:
        return f"{int(np.sum(unknown))} of {kind.size} lines unidentified (not marked)"
    p = np.asarray(lines[3], float) ** 2
    share = float(np.sum(p[unknown]) / np.sum(p)) if np.sum(p) > 0 else 0.0
    text = (f"unidentified lines (not marked): {100.0 * share:.0f} % of the lines' power "
            f"({int(np.sum(unknown))} of {kind.size} lines)")
    sep = "\n"
    if len(lines) >= 5 and np.sum(p[unknown]) > 0:
        # lines left unidentified because several sources lie within the resolution
        amb = unknown & (np.char.str_len(np.asarray(lines[4]).astype(str)) > 0)
        text += (f"{sep}{100.0 * np.sum(p[amb]) / np.sum(p[unknown]):.0f} % of that with "
                 "candidate sources too close together to tell apart")
    return text


def _mark_unstable(ax, r_edges, unstable, max_hz: float) -> None:
    """A hatched strip at the left edge over the speeds whose orbit is unstable."""
    from matplotlib.patches import Rectangle

    w = 0.03 * max_hz
    for k in np.flatnonzero(unstable):
        ax.add_patch(Rectangle((0.0, r_edges[k]), w, r_edges[k + 1] - r_edges[k], fc="white",
                               ec="tab:red", hatch="////", lw=0.0, zorder=6))
    ax.add_patch(Rectangle((0.0, r_edges[0]), 0.0, 0.0, fc="white", ec="tab:red",
                           hatch="////", label="orbit unstable at this speed (not observed)"))


def plot_erp(rpm, erp_w, *, title: str = ""):
    """ERP against speed in W (log scale) and in dB re 1 pW (right axis), a Figure."""
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
    right.set_ylabel("ERP [dB re 1 pW]")
    ax.set_title(plain_title(title), fontsize=9)
    return fig
