"""Files and figures of the gearbox ``modes`` analysis
(:mod:`vibrogear.analyses.gearbox_modes`).

* ``modes.csv``: the elastic modes of the linearised reduced model, their dominant
  subsystem and the strain-energy share of each gear mesh.
* ``resonance_map.png/.svg``: natural frequencies against every mesh's orders over the
  speed range, the resonance speeds marked.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ...pipeline.files import atomic_write_bytes
from ..figure import save_figure
from ..plots.gearbox import resonance_map_figure

__all__ = ["write", "write_modes_csv"]


def write_modes_csv(path, f_hz, fd_hz, zeta, names, shares, mesh, mesh_names) -> Path:
    """modes.csv: index, frequency_hz (natural frequency |lambda| / 2 pi, as in the rotor's
    modes.csv), damped_frequency_hz, damping_ratio, dominant subsystem, its energy share,
    and the strain-energy share of each gear mesh; frequencies at full precision."""
    cols = ["index", "frequency_hz", "damped_frequency_hz", "damping_ratio", "dominant",
            "share"] + [f"mesh_energy_{n}" for n in mesh_names]
    lines = [",".join(cols)]
    for i in range(len(f_hz)):
        k = int(np.argmax(shares[:, i]))
        row = [str(i), repr(float(f_hz[i])), repr(float(fd_hz[i])), f"{zeta[i]:.6g}", names[k],
               f"{shares[k, i]:.3f}"]
        row += [f"{mesh[j, i]:.4g}" for j in range(mesh.shape[0])]
        lines.append(",".join(row))
    return atomic_write_bytes(Path(path), ("\n".join(lines) + "\n").encode())


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    out = Path(out)
    files = {"csv": str(write_modes_csv(out / "modes.csv", r.f_hz, r.fd_hz, r.zeta,
                                        list(r.names), r.shares, r.mesh,
                                        list(r.mesh_names)))}
    save_figure(resonance_map_figure(r), out / "resonance_map")
    files["png"] = str(out / "resonance_map.png")
    return files
