"""Time response: table and plots (time trace, phase trajectory)."""
from __future__ import annotations

import numpy as np

from ..figure import new_figure, plain_title
from .gearbox import plot_gearbox_time_response

__all__ = ["plot_time_response", "time_response_figure", "contact_names", "primary_contacts"]


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


def contact_names(result) -> list[str]:
    """The contacts' names of a time response's model (c0, c1, ... where unnamed)."""
    ct = result.study.model.contacts
    return list(ct.names) or [f"c{j}" for j in range(ct.count)]


def primary_contacts(result) -> np.ndarray:
    """The primary contacts' rows: the gear meshes, or the impact pair's clearance."""
    g = result.study.contact_groups
    return np.asarray(g.get("mesh", g.get("clearance", [])), dtype=int)


def time_response_figure(r):
    """The figure of a time response
    (:class:`~vibrogear.analyses.time_response.TimeResponseResult`): a gearbox's mesh
    deformations, phase trajectories, mesh and bearing forces; the impact pair's monitored
    deformation and its phase trajectory."""
    study, model = r.study, r.study.model
    names = contact_names(r)
    title = f"{study.title}, {study.param_name} = {r.param:g}"
    if "mesh" in study.contact_groups:
        mesh = primary_contacts(r)
        bearings = {k.split(":", 1)[1]: r.force[idx].sum(axis=0)
                    for k, idx in study.contact_groups.items() if k.startswith("bearing:")}
        return plot_gearbox_time_response(r.t_s, r.delta[mesh], r.delta_dot[mesh],
                                          r.force[mesh], [names[j] for j in mesh], bearings,
                                          mesh_period_s=r.period * study.time_unit_s,
                                          backlash=[model.contacts.gap_lo[j] for j in mesh],
                                          title=title)
    j = study.monitor.contact
    return plot_time_response(r.t, r.delta[j], r.delta_dot[j], period=r.period,
                              bounds=study.monitor.lines, title=title)
