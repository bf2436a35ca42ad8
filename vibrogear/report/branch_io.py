"""Write continuation branches as ``branch.npz`` / ``branch.csv``.

``neutral`` is the number of trivial multipliers 1 of a point (an orbit family: a free gear
touching nothing); ``max_abs_multiplier`` is over the other, nontrivial multipliers (the
ones that decide stability); ``floquet`` in the npz holds all of them."""
from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from ..pipeline.files import atomic_write_bytes, atomic_write_npz

__all__ = ["branch_arrays", "write_branches", "CSV_COLUMNS"]

CSV_COLUMNS = ("branch", "n_periods", "param", "period", "stable", "label", "qmin", "qmax",
               "impacts", "max_abs_multiplier", "residual", "neutral")


def branch_arrays(branches) -> dict:
    """Concatenate the points of all branches (period-1 first) into flat arrays."""
    rows = [(b_i, b, p) for b_i, b in enumerate(branches) for p in b.points]
    n = rows[0][2].u0.size if rows else 0
    param = np.array([p.param for _, _, p in rows], dtype=float)
    scale = np.array([b.period_scale for _, b, _ in rows], dtype=float)
    return {
        "param": param,
        "period": scale / param if rows else np.zeros(0),
        "u0": np.array([p.u0 for _, _, p in rows]).reshape(len(rows), n),
        "floquet": np.array([p.floquet for _, _, p in rows], dtype=complex).reshape(len(rows), n),
        "stable": np.array([p.stable for _, _, p in rows], dtype=bool),
        "label": np.array([p.label for _, _, p in rows], dtype="<U2"),
        "branch": np.array([i for i, _, _ in rows], dtype=np.int64),
        "n_periods": np.array([b.n_periods for _, b, _ in rows], dtype=np.int64),
        "qmin": np.array([p.qmin for _, _, p in rows], dtype=float),
        "qmax": np.array([p.qmax for _, _, p in rows], dtype=float),
        "impacts": np.array([p.impacts for _, _, p in rows], dtype=np.int64),
        "residual": np.array([p.residual for _, _, p in rows], dtype=float),
        "neutral": np.array([p.neutral for _, _, p in rows], dtype=np.int64),
        "max_abs_multiplier": np.array([p.max_abs_multiplier for _, _, p in rows], dtype=float),
    }


def _cell(x) -> str:
    if isinstance(x, (float, np.floating)):
        return repr(float(x)) if math.isfinite(x) else ""
    return str(x)


def write_branches(branches, out_dir) -> dict:
    arrays = branch_arrays(branches)
    for key, a in arrays.items():
        if a.dtype.kind in "fc" and not np.all(np.isfinite(a)):
            raise ValueError(f"branch array {key!r} holds non-finite values")
    out_dir = Path(out_dir)
    npz = atomic_write_npz(out_dir / "branch.npz", arrays)
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    for k in range(arrays["param"].size):
        w.writerow([_cell(v) for v in (
            int(arrays["branch"][k]), int(arrays["n_periods"][k]), float(arrays["param"][k]),
            float(arrays["period"][k]), bool(arrays["stable"][k]), str(arrays["label"][k]),
            float(arrays["qmin"][k]), float(arrays["qmax"][k]), int(arrays["impacts"][k]),
            float(arrays["max_abs_multiplier"][k]), float(arrays["residual"][k]),
            int(arrays["neutral"][k]))])
    csv_path = atomic_write_bytes(out_dir / "branch.csv", text.getvalue().encode())
    return {"npz": npz, "csv": csv_path}
