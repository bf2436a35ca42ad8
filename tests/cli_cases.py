"""Helpers of the CLI case tables (tests/unit/test_extreme_*.py): the argument list of one
run, the pytest.param entries of a case table, and a run's outputs read back."""
from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest


def cli_args(verb: str, scene: str, out, overrides) -> list:
    """``verb scene --quiet --out out --set o ...``."""
    args = [verb, scene, "--quiet", "--out", str(out)]
    for o in overrides:
        args += ["--set", o]
    return args


def cases(table, ci=None) -> list:
    """pytest.param entries, the id being each case's first value (entries that are already
    pytest.param, e.g. the slow ones, keep their marks).  ``ci``: the ids the CI tier runs;
    the others are marked ``system`` (``make test-system``)."""
    out = []
    for c in table:
        values, marks = (c.values, list(c.marks)) if hasattr(c, "values") else (c, [])
        if ci is not None and values[0] not in ci:
            marks.append(pytest.mark.system)
        out.append(pytest.param(*values[1:], marks=marks, id=values[0]))
    return out


def read_outputs(out: Path, analysis: str, *, text_columns=None):
    """(summary of ``analysis`` with the run's notes, ``<analysis>.npz`` arrays,
    ``<analysis>.csv`` rows) of a finished run; no NaN or infinity in summary.json.  With
    ``text_columns`` (the csv's non-numeric columns) every float array and every other csv
    cell must be finite too."""
    text = (out / "summary.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    doc = json.loads(text)
    s = dict(doc["results"][analysis], notes=doc.get("notes", []))
    with np.load(out / f"{analysis}.npz") as z:
        arrays = {k: z[k] for k in z.files}
    with open(out / f"{analysis}.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    if text_columns is not None:
        for k, v in arrays.items():
            if v.dtype.kind in "fc":
                assert np.all(np.isfinite(v)), k
        for r in rows:
            for k, v in r.items():
                if k not in text_columns:
                    assert math.isfinite(float(v)), (k, r)
    return s, arrays, rows
