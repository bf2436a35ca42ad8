"""Per sweep point, the evidence of its stroboscopic samples that backs its class: a
quasi-periodic point's second base frequency, a chaotic point's broadband Poincare spectrum
(:func:`~.spectral_lines.stroboscopic_evidence`)."""
from __future__ import annotations

import math

import numpy as np

from .motion import QUASI_PERIODIC
from .spectral_lines import stroboscopic_evidence

__all__ = ["SPECTRAL_COLUMNS", "spectral_evidence"]

#: the columns of :func:`spectral_evidence` (sweep.npz / sweep.csv)
SPECTRAL_COLUMNS = ("base_f2_order", "strob_flatness", "strob_peak_fraction")


def spectral_evidence(result) -> dict:
    """Per point, from its stroboscopic samples ``poincare``
    (:func:`~vibrogear.solvers.sequential.spectral_lines.stroboscopic_evidence`):
    ``base_f2_order`` (a quasi-periodic point's second base frequency in orders of the
    excitation, the rotation number in (0, 1/2]; 0 elsewhere), ``strob_flatness`` and
    ``strob_peak_fraction``; 0 for failed points."""
    N = result.param.size
    out = {k: np.zeros(N) for k in SPECTRAL_COLUMNS}
    for k in range(N):
        if result.status[k] != 0:
            continue
        ev = stroboscopic_evidence(np.asarray(result.poincare[k], dtype=float))
        if not all(math.isfinite(v) for v in ev.values()):
            continue
        if int(result.motion_class[k]) == QUASI_PERIODIC:
            out["base_f2_order"][k] = ev["nu"]
        out["strob_flatness"][k] = ev["flatness"]
        out["strob_peak_fraction"][k] = ev["peak_fraction"]
    return out
