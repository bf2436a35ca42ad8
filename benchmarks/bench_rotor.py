"""Rotor timings (prints; no assertions).  Run: .venv/bin/python benchmarks/bench_rotor.py

- assembly + modal analysis (12 modes at 3000 rpm) of a 100-element shaft; target < 0.2 s
- Campbell diagram of a 48-element rotor (Friswell Example 5.9.1 meshed with 48 elements,
  the ROSS benchmark model) at 31 speeds, 0-4000 rpm, 1x critical speeds; target <= 0.8 s
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from rotor_fixtures import friswell_two_disc, rotor_from_dict  # noqa: E402

from vibrogear.solvers.rotor.campbell import campbell_diagram  # noqa: E402
from vibrogear.solvers.rotor.modes import rotor_modes  # noqa: E402


def best_of(fn, repeat=5):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), float(np.median(times)), out


def shaft_100():
    return rotor_from_dict({
        "material": {"E": 211e9, "G": 81.2e9, "rho": 7810.0, "internal_damping": 1e-6},
        "sections": [{"length": 1.5, "outer_diameter": 0.05, "elements": 100}],
        "discs": [{"position": 0.45, "outer_diameter": 0.28, "inner_diameter": 0.05,
                   "width": 0.07}],
        "bearings": [{"position": z, "kxx": 1e6, "kyy": 8e5, "cxx": 100.0, "cyy": 100.0}
                     for z in (0.0, 1.5)]})


def main():
    rotor_modes(shaft_100(), 3000.0, count=12)          # warm-up (imports, caches)
    best, med, res = best_of(lambda: rotor_modes(shaft_100(), 3000.0, count=12))
    print(f"100-element shaft ({res.shapes.shape[0]} DOF): assembly + 12 complex modes: "
          f"best {best * 1e3:.1f} ms, median {med * 1e3:.1f} ms "
          f"(error estimate {res.error_estimate:.1e})")
    m48 = friswell_two_disc(48)
    speeds = np.linspace(0.0, 4000.0, 31)
    best, med, cb = best_of(lambda: campbell_diagram(friswell_two_disc(48), speeds, n_modes=8))
    print(f"48-element rotor ({m48.n_dofs} DOF), Campbell at 31 speeds, 8 lines, 1x critical "
          f"speeds: best {best * 1e3:.1f} ms, median {med * 1e3:.1f} ms "
          f"(error estimate {cb.error_estimate:.1e})")


if __name__ == "__main__":
    main()
