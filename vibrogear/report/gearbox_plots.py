"""Gearbox figures and tables: modes, resonance map, time response with contact forces."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .figure import new_figure, save_figure
from ..pipeline.files import atomic_write_bytes

__all__ = ["write_modes_csv", "plot_resonance_map", "plot_gearbox_time_response"]


def write_modes_csv(path, f_hz, fd_hz, zeta, names, shares, mesh, mesh_names) -> Path:
    """modes.csv: index, frequency_hz (natural frequency |lambda| / 2 pi, as in the rotor's
    modes.csv), damped_frequency_hz, damping_ratio, dominant subsystem, its energy share,
    and the strain-energy share of each gear mesh; frequencies at full precision."""
    cols = ["index", "frequency_hz", "damped_frequency_hz", "damping_ratio", "dominant",
            "share"] + [f"mesh_energy_{n}" for n in mesh_names]
    lines = [",".join(cols)]
    for i in range(len(f_hz)):
        k = int(np.argmax(shares[:, i]))
        row = [str(i), repr(float(f_hz[i])), repr(float(fd_hz[i])), f"{zeta[i]:.6g}", names[k],
               f"{shares[k, i]:.3f}"]
        row += [f"{mesh[j, i]:.4g}" for j in range(mesh.shape[0])]
        lines.append(",".join(row))
    return atomic_write_bytes(Path(path), ("\n".join(lines) + "\n").encode())


def plot_resonance_map(path, f_hz, mesh, teeth: int, rpm_lo: float, rpm_hi: float, *,
                       title: str = "", f_max: float | None = None,
                       formats=("png", "svg"), dpi: int = 150) -> list[Path]:
    """Natural frequencies (horizontal lines, darker = more mesh strain energy) against the
    mesh-frequency orders 1x and 2x over the speed range: crossings are resonance speeds."""
    if not rpm_hi > rpm_lo:               # a single speed: a span around it
        rpm_lo, rpm_hi = 0.5 * rpm_lo, max(1.5 * rpm_lo, 1.0)
    fig = new_figure((8.0, 5.0))
    ax = fig.add_subplot(111)
    rpm = np.linspace(rpm_lo, rpm_hi, 2)
    top = 2.2 * teeth * rpm_hi / 60.0 if f_max is None else f_max
    share = mesh.max(axis=0) if mesh.size else np.zeros_like(f_hz)
    for f, s in zip(f_hz, share):
        if f <= top:
            ax.axhline(f, color=(0.8 - 0.8 * min(1.0, 4 * s),) * 3, lw=0.6 + 2.0 * min(1.0, 4 * s))
    for order, style in ((1, "-"), (2, "--")):
        ax.plot(rpm, order * teeth * rpm / 60.0, "r" + style, lw=1.5, label=f"{order}x mesh frequency")
    ax.set_xlim(rpm_lo, rpm_hi)
    ax.set_ylim(0.0, top)
    ax.set_xlabel("driving speed [rpm]")
    ax.set_ylabel("frequency [Hz]")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(title + "\nnatural frequencies (dark: large gear-mesh strain energy)", fontsize=9)
    return save_figure(fig, path, formats, dpi)


def plot_gearbox_time_response(path, t_s, delta, ddot, force, mesh_names, bearing_forces, *,
                               mesh_period_s: float, backlash=(), title: str = "",
                               formats=("png", "svg"), dpi: int = 150) -> list[Path]:
    """Mesh deformations (zero line: mesh interruption below), phase trajectories of the
    last half, mesh forces and the total radial load of each bearing's elements."""
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
    fig.suptitle(title, fontsize=9)
    return save_figure(fig, path, formats, dpi)
