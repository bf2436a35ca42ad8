"""Files and figures of the gearbox ``modes`` analysis
(:mod:`vibrogear.analyses.gearbox_modes`).

* ``modes.csv``: the elastic modes of the linearised reduced model, their dominant
  subsystem and the strain-energy share of each gear mesh.
* ``resonance_map.png/.svg``: natural frequencies against every mesh's orders over the
  speed range, the resonance speeds marked.
"""
from __future__ import annotations

from pathlib import Path

from ..figure import save_figure
from ..plots.gearbox import resonance_map_figure, write_modes_csv

__all__ = ["write"]


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    out = Path(out)
    files = {"csv": str(write_modes_csv(out / "modes.csv", r.f_hz, r.fd_hz, r.zeta,
                                        list(r.names), r.shares, r.mesh,
                                        list(r.mesh_names)))}
    save_figure(resonance_map_figure(r), out / "resonance_map")
    files["png"] = str(out / "resonance_map.png")
    return files
