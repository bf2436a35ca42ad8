"""Time response: table and plots (time trace, phase trajectory)."""
from __future__ import annotations

from ..figure import new_figure, plain_title

__all__ = ["plot_time_response"]


def plot_time_response(t, q, dq, *, period: float, bounds=(), title: str = ""):
    """The deformation ``q`` against time ``t`` / ``period`` and its phase trajectory
    (second half) as a matplotlib Figure (saved by the report writer)."""
    fig = new_figure((10.0, 4.2))
    ax1, ax2 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [2, 1]})
    ax1.plot(t / period, q, lw=0.8)
    ax1.set_xlabel("time / excitation period")
    ax1.set_ylabel("q")
    half = t >= 0.5 * t[-1]
    ax2.plot(q[half], dq[half], lw=0.6)
    ax2.set_xlabel("q")
    ax2.set_ylabel("dq/dt")
    ax2.set_title("phase trajectory (second half)", fontsize=8)
    for b in bounds:
        ax1.axhline(b, color="0.6", ls=":", lw=0.8)
        ax2.axvline(b, color="0.6", ls=":", lw=0.8)
    fig.suptitle(plain_title(title), fontsize=9)
    return fig
