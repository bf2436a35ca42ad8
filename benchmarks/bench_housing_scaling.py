"""Housing scaling: DOF against wall time and peak memory per rank, 1 and 2 MPI ranks, direct
(block Lanczos on the Cholesky factor) against iterative (SLEPc Krylov-Schur with CG + GAMG inner
solves), fitted power laws t = a N^b, mem = c N^d and their projection to 1M and 4M DOF.

Each point is one empty-cache ``vibrogear modes`` run (``count`` modes, default 20) of
configs/housing.toml (or --scene) at a mesh size; points are appended to
benchmarks/results/bench_housing_scaling.json (rerun to add points; existing ones are kept) and
the fits are recomputed over all stored points.  The 2-rank direct points at 100 modes come from
bench_housing_convergence.json.

Usage: ``python benchmarks/bench_housing_scaling.py --sizes 0.024 0.0156 --ranks 1 2
--solvers block krylovschur_gamg [--count 20] [--scene configs/housing_small.toml]``
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from bench_housing_convergence import ROOT, SCENE, run_modes

OUT = ROOT / "benchmarks" / "results" / "bench_housing_scaling.json"


def fit(points: list[dict], key: str) -> dict | None:
    """Least-squares power law key = a N^b over ``points`` (n_dofs, key), and its values at 1M, 4M."""
    pts = [(p["n_dofs"], p[key]) for p in points if p.get("status") == "ok" and p.get(key)]
    if len(pts) < 2:
        return None
    N, y = np.array(pts, dtype=float).T
    b, log_a = np.polyfit(np.log(N), np.log(y), 1)
    return {"a": float(np.exp(log_a)), "b": float(b), "n_points": len(pts),
            "at_1M": float(np.exp(log_a) * 1e6 ** b), "at_4M": float(np.exp(log_a) * 4e6 ** b)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sizes", type=float, nargs="+", default=[0.024, 0.0156])
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--solvers", nargs="+", default=["block"])
    ap.add_argument("--count", type=int, default=20)
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--scene", type=Path, default=SCENE)
    ap.add_argument("--timeout", type=float, default=900.0)
    a = ap.parse_args()
    a.scene = a.scene.resolve()
    rec = json.loads(OUT.read_text()) if OUT.is_file() else {"points": []}
    tmp = Path(tempfile.mkdtemp(prefix="vg-scal-"))
    try:
        for solver in a.solvers:
            for n in a.ranks:
                for size in a.sizes:
                    p = {"scene": str(a.scene.relative_to(ROOT)), "size": size, "solver": solver,
                         "n_processes": n, "count": a.count, "tol": a.tol}
                    try:
                        r = run_modes(size, count=a.count, n=n, tmp=tmp, timeout=a.timeout, scene=a.scene,
                                      sets=[f"housing.modes.solver={solver}", f"housing.modes.tol={a.tol}"])
                    except subprocess.TimeoutExpired:
                        p.update(status="timeout", wall_s=a.timeout)
                    except RuntimeError as exc:
                        p.update(status="failed", error=str(exc)[-600:])
                    else:
                        p.update(status="ok", n_dofs=r["n_dofs"], wall_s=r["wall_s"], eigensolve_s=r["eigensolve_s"],
                                 peak_memory_mb_sum=r["peak_memory_mb"],
                                 peak_memory_mb_per_rank=r["peak_memory_mb"] / n,
                                 max_residual=r["error_estimates"]["max_eigen_residual"],
                                 f1_hz=r["frequencies_hz"][0], load_average=r["load_average"])
                    print(json.dumps(p), flush=True)
                    rec["points"].append(p)
                    OUT.write_text(json.dumps(rec, indent=1))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    fits = {}
    for group in sorted({(p["solver"], p["n_processes"], p["count"]) for p in rec["points"]}):
        pts = [p for p in rec["points"] if (p["solver"], p["n_processes"], p["count"]) == group]
        fits["{} n={} count={}".format(*group)] = {
            k: fit(pts, k) for k in ("wall_s", "eigensolve_s", "peak_memory_mb_per_rank")}
    rec["fits"] = fits
    rec["load_average_after"] = os.getloadavg()
    OUT.write_text(json.dumps(rec, indent=1))
    print(json.dumps(fits, indent=1))


if __name__ == "__main__":
    main()
