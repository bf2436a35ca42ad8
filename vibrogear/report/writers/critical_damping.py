"""Files and figures of the impact pair's ``critical_damping`` analysis
(:mod:`vibrogear.analyses.critical_damping`).

* ``critical_damping.json``: the analysis' entry of ``summary.json`` (non-finite numbers as null);
* ``critical_damping.png/.svg``: the two fold curves meeting at the cusp.
"""
from __future__ import annotations

import json
from pathlib import Path

from ...pipeline.files import atomic_write_text, finite_json
from ..plots.critical_damping import plot_fold_cusp
from ..figure import save_figure

__all__ = ["write"]


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    out = Path(out)
    files = {"json": str(atomic_write_text(out / "critical_damping.json",
                                           json.dumps(finite_json(outcome.record()), indent=2)))}
    save_figure(plot_fold_cusp(r.result, title=r.title, extra_scans=list(r.extra_scans)),
                out / "critical_damping")
    files["png"] = str(out / "critical_damping.png")
    return files
