"""``vibrogear states`` on the two-stage gearbox: the census's cost, its split (transient,
record, clustering) and a projection to 31 speeds x 32 starts on 2 cores and on 64 MPI ranks.

The issue's case (31 speeds x 32 starts = 992 starts) takes hours on a shared 2-core machine,
so a subset is measured: ``--speeds`` speeds over 1500-3000 rpm x ``--starts`` starts, on 2
worker processes, through the runner (sweep + states in one run, so that each attractor is
also compared with the sweep's path).  Baseline in the same run: the demo's sweep (61
points, up and down), whose points are the same settled sweep points started from the
previous point instead of from a random disturbance.

Projections (not measurements; written as such):
* 2 cores: the measured census wall time scaled by 992 / (starts measured) (the starts are
  independent; the units keep both workers busy);
* 64 ranks: the measured per-start times resampled to 992 starts (fixed seed), grouped into
  units of ``batch`` starts and handed out longest first to 64 ranks (the executor's rule);
  the makespan plus the serial part measured here (grouping, shooting the periodic
  attractors; no branches).

Run: .venv/bin/python benchmarks/bench_states.py [--speeds 4 --starts 8]
Writes benchmarks/results/bench_states.json.
"""
from __future__ import annotations

import argparse
import heapq
import json
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from vibrogear.config import load_scene  # noqa: E402
from vibrogear.pipeline.outcome import RunContext  # noqa: E402
from vibrogear.runner import run_scene  # noqa: E402

FULL_SPEEDS, FULL_STARTS, RANKS = 31, 32, 64


def _lpt_makespan(times, ranks: int) -> float:
    """Longest-first list scheduling of unit times on ``ranks`` workers."""
    load = [0.0] * ranks
    heapq.heapify(load)
    for t in sorted(times, reverse=True):
        heapq.heappush(load, heapq.heappop(load) + t)
    return max(load)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--speeds", type=int, default=4)
    ap.add_argument("--starts", type=int, default=8)
    ap.add_argument("--batch", type=int, default=4)
    ap.add_argument("--out", default="/tmp/bench_states_two_stage")
    a = ap.parse_args(argv)
    sets = ('scene.analyses=["sweep", "states"]', "states.rpm_min=1500.0",
            "states.rpm_max=3000.0", f"states.n_points={a.speeds}",
            f"states.starts={a.starts}", f"states.batch={a.batch}", "states.branches=false",
            "states.workers=2", "sweep.workers=2",
            # the [sweep] settings of the demo
            "states.transient_periods=150", "states.extra_transient_periods=100",
            "states.record_periods=32", "states.max_period=8", "states.period_tol=4e-4",
            "states.settle_window=16")
    scene = load_scene(ROOT / "configs" / "two_stage.toml", sets)
    out = Path(a.out)
    load_before = os.getloadavg()
    t0 = time.perf_counter()
    summary = run_scene(scene, RunContext(out=out, quiet=True))
    wall = time.perf_counter() - t0
    st = summary["results"]["states"]
    sw = summary["results"]["sweep"]
    split = st["wall_split_s"]
    n = a.speeds * a.starts
    with np.load(out / "states.npz") as z:
        classes = [str(z["attractor_class_legend"][c]) for c in z["attractor_class"]]
    partial_times = _start_times(out, st)
    rng = np.random.default_rng(0)
    full = FULL_SPEEDS * FULL_STARTS
    sample = rng.choice(partial_times, size=full, replace=True)
    units = [float(np.sum(sample[k:k + a.batch])) for k in range(0, full, a.batch)]
    serial = split.get("clustering", 0.0) + split.get("orbits", 0.0)
    res = {
        "case": f"two_stage states, measured {a.speeds} speeds x {a.starts} starts "
                f"(1500-3000 rpm), 2 worker processes, branches off"
                + (" (the issue's full size)" if n == full else " (a subset)"),
        "conditions": f"2-core machine, load average {load_before[0]:.2f} at the start and "
                      f"{os.getloadavg()[0]:.2f} at the end (1-minute; 2.0 = both cores busy "
                      f"with this run alone)",
        "python": platform.python_version(),
        "measured": {
            "starts": n, "census_wall_s": split.get("census_wall"),
            "states_total_wall_s": split.get("total_wall"),
            "per_start_cpu_split_s": {k: split.get(k) for k in
                                      ("transient", "record", "lyapunov", "orbit_check",
                                       "metrics", "second_tolerance")},
            "clustering_s": split.get("clustering"), "orbits_s": split.get("orbits"),
            "mean_start_s": float(np.mean(partial_times)),
            "max_start_s": float(np.max(partial_times)),
            "attractors": st["attractors"], "classes": classes,
            "coexisting_at_rpm": st["coexisting_at"],
            "unseen_by_sweep": st.get("unseen_by_sweep"),
            "run_wall_s": wall,
        },
        "baseline_sweep": {"points": sw["points"], "wall_s": summary["wall_time_s"]["sweep"],
                           "per_point_s": summary["wall_time_s"]["sweep"] / sw["points"] * 2},
        "projection_31x32": {
            "starts": full,
            "two_cores_wall_s": split.get("census_wall") * full / n + serial,
            "mpi_64_ranks_wall_s": _lpt_makespan(units, RANKS) + serial,
            "mpi_64_ranks_units": len(units),
            "note": ("2 cores: measured at full size (the census wall time); " if n == full
                     else "2 cores: projected from the measured subset; ")
                    + "64 ranks: a projection, not a measurement (longest-first units of the "
                      "resampled start times + the serial part)",
        },
    }
    path = ROOT / "benchmarks" / "results" / "bench_states.json"
    path.write_text(json.dumps(res, indent=2))
    print(json.dumps(res, indent=2))
    return res


def _start_times(out: Path, st: dict) -> np.ndarray:
    """Wall seconds of each settled start (states.npz ``start_wall_s``)."""
    with np.load(out / "states.npz") as z:
        return np.asarray(z["start_wall_s"], float)


if __name__ == "__main__":
    main()
