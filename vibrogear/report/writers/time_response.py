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
from ..plots.time_response import contact_names, primary_contacts, time_response_figure

__all__ = ["write"]

_STATES_CSV = 8


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    study, model = r.study, r.study.model
    out = Path(out)
    names = contact_names(r)
    files = {"npz": str(atomic_write_npz(out / "time_response.npz", r.arrays()))}

    lu = f"_{study.length_unit}" if study.length_unit else ""
    fu = "_N" if study.length_unit else ""
    cols, data = ["t_s" if study.length_unit else "t"], [r.t_s]
    if model.n_states <= _STATES_CSV:
        cols += list(model.state_names) or [f"u{i}" for i in range(model.n_states)]
        data += list(r.u.T)
    for j in primary_contacts(r):
        cols += [f"delta_{names[j]}{lu}", f"force_{names[j]}{fu}"]
        data += [r.delta[j], r.force[j]]
    txt = io.StringIO()
    np.savetxt(txt, np.column_stack(data), delimiter=",", header=",".join(cols), comments="",
               fmt="%.10g")
    files["csv"] = str(atomic_write_bytes(out / "time_response.csv", txt.getvalue().encode()))

    save_figure(time_response_figure(r), out / "time_response")
    files["png"] = str(out / "time_response.png")
    return files
