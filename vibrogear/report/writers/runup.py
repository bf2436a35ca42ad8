"""Files and figures of a run-up / run-down (``vibrogear runup``).

* ``runup.npz``: per run ``<d>`` (the direction ``up``, ``down``; with ``[runup]
  inertia_torque = "both"`` also ``up_no_inertia``, ``down_no_inertia``: the same run
  without the inertia torque of the acceleration), per mesh period:
  ``<d>_time`` [s], ``<d>_rpm`` (mean speed over the period), ``<d>_env_min_<mesh>`` /
  ``<d>_env_max_<mesh>`` (deformation envelope, display unit), ``<d>_losses_<mesh>``
  (contact losses); per order-tracking window: ``<d>_track_rpm`` and
  ``<d>_order_<mesh>_<order>`` (amplitude of that order of the mesh's deformation, display
  unit); and ``orders`` / ``order_names`` (orders per driving-shaft revolution), ``meshes``,
  ``unit``, ``directions``, ``runs`` (the run names ``<d>``) and ``inertia_torque`` (per
  run: applied or not).
* ``runup.csv``: the per-period scalars, one row per run and mesh period (the run's
  direction and whether the inertia torque was applied).
* ``runup_envelope.png``, ``runup_orders.png``, ``runup_waterfall.png``
  (:mod:`vibrogear.report.plots.runup`); the envelope figure overlays the steady state:
  the sweep's extrema and the continuation branches, from the analyses run before in the
  same scene or from ``sweep.npz`` / ``branch.npz`` in the output folder.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from ...analyses.runup.runup import runup_arrays
from ...pipeline.files import atomic_write_bytes, atomic_write_npz
from ..figure import save_figure
from ..plots.runup import plot_envelopes, plot_orders, plot_waterfall
from ..sweep_files import read_sweep_npz, sweep_arrays

__all__ = ["write", "runup_arrays", "steady_state"]


def _csv(result) -> bytes:
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    cols = ["direction", "inertia_torque", "period", "time_s", "rpm"]
    for n in result.mesh_names:
        cols += [f"env_min_{n}", f"env_max_{n}", f"losses_{n}"]
    w.writerow(cols)
    for r in result.runs:
        for k in range(r.rpm.size):
            row = [r.direction, str(r.inertia_torque).lower(), k, repr(float(r.time_s[k])),
                   repr(float(r.rpm[k]))]
            for i in range(len(result.mesh_names)):
                row += [repr(float(r.env_min[i, k])), repr(float(r.env_max[i, k])),
                        int(r.losses[i, k])]
            w.writerow(row)
    return text.getvalue().encode()


def steady_state(previous, out, study) -> tuple[dict | None, dict | None]:
    """(sweep arrays, branch arrays) in display units, from the outcomes run before in this
    scene, else from ``sweep.npz`` / ``branch.npz`` in ``out`` (None where absent)."""
    scale = study.monitor.scale
    previous = previous or {}
    sweep = branch = None
    if previous.get("sweep") is not None:
        sweep = sweep_arrays(previous["sweep"].result.sweep)
    elif (Path(out) / "sweep.npz").is_file():
        sweep = read_sweep_npz(Path(out) / "sweep.npz")
    if previous.get("continuation") is not None:
        branch = previous["continuation"].result.arrays()
    elif (Path(out) / "branch.npz").is_file():
        with np.load(Path(out) / "branch.npz", allow_pickle=False) as z:
            branch = {k: z[k] for k in z.files}
    for data in (sweep, branch):
        if data is not None:
            for k in ("qmin", "qmax"):
                data[k] = np.asarray(data[k], float) * scale
    return sweep, branch


def write(scene, outcome, out, previous=None) -> dict:
    result = outcome.result
    out = Path(out)
    files = {"npz": str(atomic_write_npz(out / "runup.npz", runup_arrays(result))),
             "csv": str(atomic_write_bytes(out / "runup.csv", _csv(result)))}
    sweep, branch = steady_state(previous, out, result.study)
    png = ("png",)
    files["envelope_png"] = str(save_figure(plot_envelopes(result, sweep=sweep, branch=branch),
                                            out / "runup_envelope", formats=png)[0])
    files["orders_png"] = str(save_figure(plot_orders(result), out / "runup_orders",
                                          formats=png)[0])
    files["waterfall_png"] = str(save_figure(plot_waterfall(result), out / "runup_waterfall",
                                             formats=png)[0])
    files["overlaid"] = [k for k, v in (("sweep", sweep), ("continuation", branch))
                         if v is not None]
    return files
