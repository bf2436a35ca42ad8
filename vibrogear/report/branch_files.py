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

__all__ = ["write_branches", "CSV_COLUMNS"]

CSV_COLUMNS = ("branch", "n_periods", "param", "period", "stable", "label", "qmin", "qmax",
               "impacts", "max_abs_multiplier", "residual", "neutral")


def _cell(x) -> str:
    if isinstance(x, (float, np.floating)):
        return repr(float(x)) if math.isfinite(x) else ""
    return str(x)


def write_branches(result, out_dir) -> dict:
    """``branch.npz`` and ``branch.csv`` in ``out_dir`` from a continuation's result (its
    :meth:`arrays`)."""
    arrays = result.arrays()
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
