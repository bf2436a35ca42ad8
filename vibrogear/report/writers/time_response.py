"""Files and figures of a time response (any study).

* ``time_response.npz``: ``t`` (model time), ``t_s`` (s), per contact ``delta``,
  ``delta_dot``, ``force`` (rows in ``names`` order; m, m/s, N for a gearbox), and the
  states ``u`` with ``state_names`` when the model has at most 64 states.
* ``time_response.csv``: time, the states of a small model (at most 8), and the
  deformation and force of the primary contacts (the gear meshes, or the impact pair's
  clearance).
* ``time_response.png/.svg``: the monitored deformation against time and its phase
  trajectory (gearboxes: every mesh, the mesh forces and the bearing loads).
"""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ...pipeline.files import atomic_write_bytes, atomic_write_npz
from ..figure import save_figure
from ..plots.gearbox import plot_gearbox_time_response
from ..plots.time_response import plot_time_response

__all__ = ["write", "figure"]

_STATES_CSV = 8


def _names(result) -> list[str]:
    ct = result.study.model.contacts
    return list(ct.names) or [f"c{j}" for j in range(ct.count)]


def _primary(result) -> np.ndarray:
    g = result.study.contact_groups
    return np.asarray(g.get("mesh", g.get("clearance", [])), dtype=int)


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    study, model = r.study, r.study.model
    out = Path(out)
    names = _names(r)
    files = {"npz": str(atomic_write_npz(out / "time_response.npz", r.arrays()))}

    lu = f"_{study.length_unit}" if study.length_unit else ""
    fu = "_N" if study.length_unit else ""
    cols, data = ["t_s" if study.length_unit else "t"], [r.t_s]
    if model.n_states <= _STATES_CSV:
        cols += list(model.state_names) or [f"u{i}" for i in range(model.n_states)]
        data += list(r.u.T)
    for j in _primary(r):
        cols += [f"delta_{names[j]}{lu}", f"force_{names[j]}{fu}"]
        data += [r.delta[j], r.force[j]]
    txt = io.StringIO()
    np.savetxt(txt, np.column_stack(data), delimiter=",", header=",".join(cols), comments="",
               fmt="%.10g")
    files["csv"] = str(atomic_write_bytes(out / "time_response.csv", txt.getvalue().encode()))

    save_figure(figure(r), out / "time_response")
    files["png"] = str(out / "time_response.png")
    return files


def figure(r):
    """The figure of a time response
    (:class:`~vibrogear.analyses.time_response.TimeResponseResult`): a gearbox's mesh
    deformations, phase trajectories, mesh and bearing forces; the impact pair's monitored
    deformation and its phase trajectory."""
    study, model = r.study, r.study.model
    names = _names(r)
    title = f"{study.title}, {study.param_name} = {r.param:g}"
    if "mesh" in study.contact_groups:
        mesh = _primary(r)
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
