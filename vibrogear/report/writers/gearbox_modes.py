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
from ..plots.gearbox import plot_resonance_map, write_modes_csv

__all__ = ["write", "figure"]


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    out = Path(out)
    files = {"csv": str(write_modes_csv(out / "modes.csv", r.f_hz, r.fd_hz, r.zeta,
                                        list(r.names), r.shares, r.mesh,
                                        list(r.mesh_names)))}
    save_figure(figure(r), out / "resonance_map")
    files["png"] = str(out / "resonance_map.png")
    return files


def figure(r):
    """The resonance map of a gearbox's modes
    (:class:`~vibrogear.analyses.gearbox_modes.GearboxModesResult`) as a Figure, the
    report's ``resonance_map.png``."""
    return plot_resonance_map(r.f_hz, r.mesh, r.mesh_teeth, r.rpm_lo, r.rpm_hi, title=r.title,
                              orders=r.orders, crossings=r.resonances)
