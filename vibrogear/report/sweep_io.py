"""Files of a sweep: ``sweep.npz``, ``sweep.csv`` and the append-as-you-go partial file.

* ``sweep.npz`` (DESIGN.md): ``param``, ``direction`` ("up"/"down"), ``qmin``, ``qmax``,
  ``poincare`` (points x samples), ``period_n`` (0 = not periodic), ``impacts`` (contact
  losses per excitation period), plus ``index``, ``status``, ``ok``, ``defect``,
  ``clusters``, ``u_end`` and the scalar error estimates.  No NaN/inf is ever written:
  failed points carry 0 placeholders and ``ok = False`` / ``status < 0``.
* ``sweep.csv`` repeats the per-point scalars; missing values are empty cells.

The partial file that makes a sweep resumable is the pipeline's
(:mod:`vibrogear.pipeline.resume`, :func:`vibrogear.analyses.sweep.resumable_sweep`).

All final files are written atomically (temporary file in the same folder + rename).
"""
from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from ..pipeline.files import atomic_write_bytes

__all__ = ["write_sweep", "sweep_arrays", "read_sweep_npz"]

CSV_COLUMNS = ("direction", "index", "param", "qmin", "qmax", "period_n", "impacts",
               "clusters", "defect", "status", "message", "wall_time")


def _finite(a, fill=0.0) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    return np.where(np.isfinite(a), a, fill)


def _cell(x) -> str:
    if isinstance(x, (float, np.floating)):
        return repr(float(x)) if math.isfinite(x) else ""
    return str(x)


def sweep_arrays(result) -> dict:
    """The arrays that ``sweep.npz`` holds (NaN/inf replaced), as a plain dict."""
    ok = result.status == 0
    return dict(
        param=_finite(result.param), direction=np.asarray(result.direction, dtype="<U4"),
        qmin=_finite(result.qmin), qmax=_finite(result.qmax),
        poincare=_finite(result.poincare), period_n=np.asarray(result.period_n, np.int64),
        impacts=_finite(result.impacts), index=np.asarray(result.index, np.int64),
        status=np.asarray(result.status, np.int64), ok=ok,
        defect=_finite(result.defect), clusters=np.asarray(result.clusters, np.int64),
        u_end=_finite(result.u_end), point_wall=_finite(result.point_wall),
        message=np.asarray(result.message, dtype=str) if result.message else np.zeros(0, "<U1"),
        rtol=np.asarray(result.rtol, np.float64), atol=np.asarray(result.atol, np.float64),
        period_tol=np.asarray(result.period_tol, np.float64),
        param_name=np.asarray(result.param_name),
    )


def write_sweep(result, out_dir, *, stem: str = "sweep") -> dict:
    """Write ``stem.npz`` and ``stem.csv`` into ``out_dir``; returns {kind: path}."""
    out_dir = Path(out_dir)
    arrays = sweep_arrays(result)
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    npz = atomic_write_bytes(out_dir / f"{stem}.npz", buf.getvalue())
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    for k in range(result.param.size):
        w.writerow([_cell(v) for v in (
            str(result.direction[k]), int(result.index[k]), float(result.param[k]),
            float(result.qmin[k]), float(result.qmax[k]), int(result.period_n[k]),
            float(result.impacts[k]), int(result.clusters[k]), float(result.defect[k]),
            int(result.status[k]), result.message[k], float(result.point_wall[k]))])
    csv_path = atomic_write_bytes(out_dir / f"{stem}.csv", text.getvalue().encode())
    return {"npz": npz, "csv": csv_path}


def read_sweep_npz(path) -> dict:
    """The arrays of a written ``sweep.npz`` as a plain dict."""
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}
