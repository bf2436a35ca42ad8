"""Files of an operating map (``vibrogear map``): ``map.npz``, ``map.csv``, the colour maps
and, with ``[map] curves = true``, ``map_curves.csv``.

``map.npz`` (grids are (directions, loads, speeds); no NaN: missing values are 0 with
``status`` < 0 or ``ok`` False):

* ``rpm`` (speeds,), ``torque`` (loads,) [N m, transmitted input torque], ``twist``
  (loads,) [rad, the motor coupling's], ``load_scale`` (loads,) (factor on the scene's
  twists), ``direction`` (directions,), ``load_given_as`` ("torque" / "twist");
* per point: ``motion_class`` (codes of ``motion_class_legend``), ``period_n``, ``qmin``,
  ``qmax`` [m, monitored mesh deformation], ``status``, ``ok``, ``wall_time`` [s];
* per mesh ``<m>``: ``impacts_<m>`` (drive + back flank onsets per mesh period),
  ``impacts_drive_<m>``, ``impacts_back_<m>``, ``rattle_<m>`` (impact energy per period,
  J), ``contact_fraction_<m>``, ``max_force_<m>`` [N, largest |mesh force|];
  per bearing: ``unloaded_<bearing>`` (rolling elements out of contact, mean);
* curves: ``curve_label`` (curves,), ``curve_start`` (curves + 1,) offsets into
  ``curve_rpm`` / ``curve_torque`` / ``curve_twist`` (points of all curves, concatenated).

``map.csv``: one row per point (direction, torque, twist, rpm, class, period, metrics).
"""
from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from ...analyses.map.map import METRICS_PER_MESH, map_arrays
from ...pipeline.files import atomic_write_bytes, atomic_write_npz
from ..plots.map import write_map_figures

__all__ = ["write", "map_arrays", "METRICS_PER_MESH"]



def _cell(x) -> str:
    if isinstance(x, (float, np.floating)):
        return repr(float(x)) if math.isfinite(x) else ""
    return str(x)


def _csv(res, arrays) -> bytes:
    keys = [f"{k}_{m}" for m in res.meshes for k in ("impacts",) + METRICS_PER_MESH] + \
        [f"unloaded_{b}" for b in res.bearings]
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow(["direction", "torque_N_m", "twist_rad", "rpm", "motion_class", "period_n",
                "qmin_m", "qmax_m", "status", "wall_time_s"] + keys)
    for j, d in enumerate(res.directions):
        for k in range(res.scale.size):
            for i in range(res.rpm.size):
                st = int(arrays["status"][j, k, i])
                c = int(arrays["motion_class"][j, k, i])
                row = [d, float(res.torque[k]), float(res.twist[k]), float(res.rpm[i]),
                       res.legend[c] if c >= 0 else "", int(arrays["period_n"][j, k, i]),
                       float(arrays["qmin"][j, k, i]), float(arrays["qmax"][j, k, i]), st,
                       float(arrays["wall_time"][j, k, i])]
                row += [float(arrays[n][j, k, i]) if st == 0 else math.nan for n in keys]
                w.writerow([_cell(v) for v in row])
    return text.getvalue().encode()


def _curves_csv(curves) -> bytes:
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow(["curve", "label", "torque_N_m", "twist_rad", "rpm"])
    for n, c in enumerate(curves.curves):
        for t, tw, p in zip(c.torque, c.twist, c.rpm):
            w.writerow([n, c.label, repr(float(t)), repr(float(tw)), repr(float(p))])
    return text.getvalue().encode()


def write(scene, outcome, out, previous=None) -> dict:
    res = outcome.result
    out = Path(out)
    arrays = map_arrays(res)
    files = {"npz": str(atomic_write_npz(out / "map.npz", arrays)),
             "csv": str(atomic_write_bytes(out / "map.csv", _csv(res, arrays)))}
    if res.curves is not None:
        files["curves_csv"] = str(atomic_write_bytes(out / "map_curves.csv",
                                                     _curves_csv(res.curves)))
    title = res.study.title if res.study is not None else scene.scene.name
    unit = res.study.energy_unit if res.study is not None else "model units"
    for name, path in write_map_figures(arrays, res.meshes, out, title=title,
                                        energy_unit=unit).items():
        files[name] = str(path)
    return files
