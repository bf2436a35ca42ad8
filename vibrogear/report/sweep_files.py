"""Files of a sweep: ``sweep.npz``, ``sweep.csv`` and the append-as-you-go partial file.

* ``sweep.npz``: ``param``, ``direction`` ("up"/"down"), ``qmin``, ``qmax``,
  ``poincare`` (points x samples), ``period_n`` (0 = not periodic), ``impacts`` (contact
  losses per excitation period), plus ``index``, ``status``, ``ok``, ``defect``,
  ``clusters``, ``u_end`` and the scalar error estimates; the motion class with its
  evidence: ``motion_class`` (int code) and ``motion_class_legend`` (its names, see
  :mod:`vibrogear.solvers.sequential.motion`), ``lyapunov`` (largest exponent, in 1 / the model's
  time unit; 0 with ``lyapunov_ok = False`` where not computed), ``lyapunov_ci`` (points x 2,
  its 95 % interval), the same in physical terms: ``lyapunov_per_s`` and
  ``lyapunov_lo_per_s`` [1/s], ``lyapunov_per_period``, ``lyapunov_lo_per_period`` and
  ``lyapunov_floor_per_period`` (per excitation period; the floor: the change of the
  exponent at rtol / 10, computed where the lower bound is above 0); the class's
  resolution evidence: ``resolution_period_n`` (the period at which every mesh
  deformation and force repeats within its resolution, 0: none), ``resolution_defect``
  (their largest difference in resolutions), ``qmax_res`` (the monitored deformation's
  resolution) and ``qmax_err`` (batch-means error of qmax); ``hysteresis_<mesh>``
  (|qmax up - qmax down| at each point's speed beyond the two points' ``qmax_err``, the
  monitored mesh's; 0 where within them or where either failed); ``transient_used`` (periods), ``settled_by``; per contact group
  ``period_n_<g>`` / ``motion_class_<g>`` and the rattle / contact metrics
  (``impacts_drive_<mesh>``, ``impacts_back_<mesh>``, ``impact_velocity_rms_<mesh>``,
  ``impact_velocity_max_<mesh>``, ``contact_fraction_<mesh>``, ``rattle_<mesh>``,
  ``unloaded_<bearing>``), each with an ``_err`` companion (batch means over blocks of the
  record) and, with ``[sweep] second_tolerance``, a ``_tol_err`` companion (the change when
  the record window is integrated again at rtol / 10 from the same state; also
  ``qmin_tol_err`` / ``qmax_tol_err``; not on chaotic points, where ``tol_err_measured`` is 0
  and the ``_tol_err`` values are written as 0: read them with that flag).  The spectral evidence of the class, from the
  record's stroboscopic samples ``poincare`` (one per excitation period;
  :func:`~vibrogear.solvers.sequential.spectral_lines.stroboscopic_evidence`):
  ``base_f2_order``, a quasi-periodic point's two base frequencies being the excitation
  (order 1) and this one, the rotation number nu in (0, 1/2] (f2 is known up to f2 -> +-f2 +
  k f1; ``nvh`` names the representative seen in the dense spectrum, in Hz); 0 elsewhere;
  ``strob_flatness``, the spectral flatness of the samples (a torus or a period: lines,
  ~0; chaos: broadband, towards 0.56), and ``strob_peak_fraction``, the share of their power
  at nu, 2 nu, 3 nu (folded).  No NaN/inf is ever written:
  failed points carry 0 placeholders and ``ok = False`` / ``status < 0``.
* ``sweep.csv`` repeats the per-point scalars; missing values are empty cells.  Its header
  names the parameter (``rpm`` for a gearbox, ``Omega`` for the impact pair; the npz key
  stays ``param``) and gives each dimensional column its unit in brackets
  (:func:`csv_header`): ``qmin [m]``, ``impact_velocity_rms_G1 [m/s]``, ``rattle_G2 [J]``,
  ``impacts [1/period]`` (per excitation period), ``wall_time [s]``; a column without
  brackets is a count, a code, a ratio or nondimensional (the impact pair's deformations).

The partial file that makes a sweep resumable is the pipeline's
(:mod:`vibrogear.pipeline.resume`, :func:`vibrogear.analyses.sweep.sweep.resumable_sweep`).

All final files are written atomically (temporary file in the same folder + rename).
"""
from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path

import numpy as np

from ..pipeline.files import atomic_write_bytes, atomic_write_npz

__all__ = ["write_sweep", "sweep_arrays", "read_sweep_npz", "csv_header"]

CSV_COLUMNS = ("direction", "index", "param", "qmin", "qmax", "period_n", "impacts",
               "clusters", "defect", "status", "message", "wall_time", "motion_class",
               "lyapunov", "lyapunov_lo", "lyapunov_hi", "transient_used", "settled_by",
               "base_f2_order", "strob_flatness", "strob_peak_fraction")


#: (pattern of a column name less its ``_err`` / ``_tol_err`` companion suffix, unit); the
#: units a model's length, time and energy units fill in
_UNITS = ((r"qmin|qmax|qmax_res|hysteresis_.+", "{length}"),
          (r"lyapunov(_lo)?_per_s", "1/s"), (r"lyapunov(_lo|_floor)?_per_period", "1/period"), (r"impact_velocity_(rms|max)_.+", "{length}/s"),
          (r"rattle_.+", "{energy}"), (r"impacts(_drive_.+|_back_.+)?", "1/period"),
          (r"lyapunov(_lo|_hi)?", "1/{time}"), (r"wall_time", "s"),
          (r"transient_used", "periods"))


def csv_header(columns, *, param_name: str = "param", param_unit: str = "",
               length_unit: str = "", time_unit_s: float = 1.0) -> list[str]:
    """``columns`` as the header of ``sweep.csv``: ``param`` becomes the parameter's name
    (with its unit in brackets where the unit is not the name), and a dimensional column
    gets its unit in brackets.  ``length_unit`` "" (a nondimensional model): the model's
    lengths, rates, energies and times have no unit."""
    dims = {"length": length_unit, "energy": "J" if length_unit == "m" else "",
            "time": ("s" if time_unit_s == 1.0 else f"({time_unit_s:g} s)") if length_unit
            else ""}
    out = []
    for c in columns:
        if c == "param":
            out.append(param_name if param_unit in ("", param_name)
                       else f"{param_name} [{param_unit}]")
            continue
        base = re.sub(r"(_tol_err|_err)$", "", c)
        unit = next((u for pat, u in _UNITS if re.fullmatch(pat, base)), "")
        if "{" in unit:
            need = re.findall(r"{(\w+)}", unit)
            unit = unit.format(**dims) if all(dims[k] for k in need) else ""
        out.append(f"{c} [{unit}]" if unit else c)
    return out


def _cell(x) -> str:
    if isinstance(x, (float, np.floating)):
        return repr(float(x)) if math.isfinite(x) else ""
    return str(x)


def sweep_arrays(result) -> dict:
    """The arrays that ``sweep.npz`` holds (NaN/inf replaced), as a plain dict
    (:meth:`~vibrogear.solvers.sequential.sweep.SweepResult.arrays`)."""
    return result.arrays()


def write_sweep(result, out_dir, *, stem: str = "sweep", param_unit: str = "",
                length_unit: str = "", time_unit_s: float = 1.0) -> dict:
    """Write ``stem.npz`` and ``stem.csv`` into ``out_dir``; returns {kind: path}.  The
    units name the CSV's columns (:func:`csv_header`)."""
    out_dir = Path(out_dir)
    arrays = sweep_arrays(result)
    npz = atomic_write_npz(out_dir / f"{stem}.npz", arrays)
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    metrics = sorted(result.metrics)
    extra = result.motion_class is not None
    w.writerow(csv_header(CSV_COLUMNS + tuple(metrics) if extra else CSV_COLUMNS[:12],
                          param_name=result.param_name, param_unit=param_unit,
                          length_unit=length_unit, time_unit_s=time_unit_s))
    spectral = result.spectral if extra else {}
    for k in range(result.param.size):
        row = [str(result.direction[k]), int(result.index[k]), float(result.param[k]),
               float(result.qmin[k]), float(result.qmax[k]), int(result.period_n[k]),
               float(result.impacts[k]), int(result.clusters[k]), float(result.defect[k]),
               int(result.status[k]), result.message[k], float(result.point_wall[k])]
        if extra:
            ci = np.asarray(result.lyapunov_ci[k], dtype=float)
            row += [result.motion_legend[int(result.motion_class[k])], float(result.lyapunov[k]),
                    float(ci[0]), float(ci[1]), int(result.transient_used[k]),
                    str(result.settled_by[k])]
            row += [float(v[k]) for v in spectral.values()]
            row += [result.metrics[n][k].item() for n in metrics]
        w.writerow([_cell(v) for v in row])
    csv_path = atomic_write_bytes(out_dir / f"{stem}.csv", text.getvalue().encode())
    return {"npz": npz, "csv": csv_path}


def read_sweep_npz(path) -> dict:
    """The arrays of a written ``sweep.npz`` as a plain dict."""
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}
