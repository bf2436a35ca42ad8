"""Files and figures of the rotor analyses (:mod:`vibrogear.analyses.rotor`).

* ``write_modes``: ``modes.csv`` (supported rotor at ``[rotor.modes].speed_rpm``;
  ``frequency_hz`` is the natural frequency |lambda| / 2 pi, as in the gearbox's modes.csv,
  ``damped_frequency_hz`` Im(lambda) / 2 pi, both at full precision), ``master_modes.csv`` +
  ``master_modes.npz`` (free, non-rotating shaft: what modal synthesis uses) and
  ``mode_shapes.png/.svg``.
* ``write_campbell``: ``campbell.csv``, ``critical_speeds.csv`` and ``campbell.png/.svg``.

Each returns the names of the files it wrote, as listed in ``summary.json``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ...pipeline.files import atomic_write_csv, atomic_write_npz

__all__ = ["write_modes", "write_campbell"]


def write_modes(scene, outcome, out, previous=None) -> list[str]:
    r = outcome.result
    res, master, model = r.modes, r.master, r.model
    out = Path(out)
    atomic_write_csv(out / "modes.csv",
                     ["index", "frequency_hz", "damped_frequency_hz", "damping_ratio", "whirl",
                      "whirl_ratio", "mode_type", "lateral_share", "axial_share",
                      "torsional_share", "residual"],
                     [[i + 1, repr(float(res.natural_frequencies_hz[i])),
                       repr(float(res.frequencies_hz[i])), f"{res.damping_ratios[i]:.6g}",
                       res.whirl[i], f"{res.whirl_ratio[i]:.4f}", res.mode_type[i],
                       *(f"{v:.4f}" for v in res.energy_share[i]), f"{res.residuals[i]:.2e}"]
                      for i in range(res.frequencies_hz.size)])
    atomic_write_csv(out / "master_modes.csv", ["index", "frequency_hz", "mode_type", "rigid_body"],
                     [[i + 1, f"{f:.8g}", r.master_types[i],
                       int(i < master.n_rigid)] for i, f in enumerate(master.frequencies_hz)])
    atomic_write_npz(out / "master_modes.npz", dict(
        frequencies_hz=master.frequencies_hz, vectors=master.vectors, node_z=model.node_z,
        free_gear_dofs=np.array(model.free_gear_dofs, int), n_rigid=master.n_rigid))
    plots = []
    if res.frequencies_hz.size:
        from ..figure import save_figure
        from ..plots.rotor import plot_mode_shapes
        plots = save_figure(plot_mode_shapes(model, res, title=r.title), out / "mode_shapes")
    return ["modes.csv", "master_modes.csv", "master_modes.npz", *(p.name for p in plots)]


def write_campbell(scene, outcome, out, previous=None) -> list[str]:
    r = outcome.result
    res = r.campbell
    out = Path(out)
    n_lines = res.frequencies_hz.shape[1]
    header = ["speed_rpm"] + [f"{k}_{j + 1}" for j in range(n_lines)
                              for k in ("frequency_hz", "whirl", "mode_type", "damping_ratio")]
    rows = []
    for i, s in enumerate(res.speeds_rpm):
        row = [f"{s:.6g}"]
        for j in range(n_lines):
            row += [f"{res.frequencies_hz[i, j]:.8g}", res.whirl[i, j], res.mode_type[i, j],
                    f"{res.damping_ratios[i, j]:.6g}"]
        rows.append(row)
    atomic_write_csv(out / "campbell.csv", header, rows)
    atomic_write_csv(out / "critical_speeds.csv",
                     ["order", "line", "speed_rpm", "frequency_hz", "whirl", "mode_type"],
                     [[f"{c.order:g}", c.line + 1, f"{c.speed_rpm:.6g}", f"{c.frequency_hz:.6g}",
                       c.whirl, c.mode_type] for c in res.critical_speeds])
    from ..figure import save_figure
    from ..plots.rotor import plot_campbell
    plots = save_figure(plot_campbell(res, title=r.title), out / "campbell")
    return ["campbell.csv", "critical_speeds.csv", *(p.name for p in plots)]
