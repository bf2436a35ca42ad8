"""Housing eigen-solver comparison: 100 master modes of configs/housing.toml on one mesh with every
``[housing.modes] solver`` (block Lanczos against SLEPc's Krylov-Schur, subspace iteration and
LOBPCG on the same Cholesky factor; optionally the AMG ones), ``mpirun -n 2``, empty vibrogear
cache per run, whole-CLI wall.  The frequency deviation of each run from the first (baseline)
run of the same invocation, and from the mesh-converged reference of
bench_housing_convergence.json when it has this mesh size, go to
benchmarks/results/bench_housing_solvers.json with the wall ratios against the baseline.

Usage: ``python benchmarks/bench_housing_solvers.py [--size 0.0156] [--solvers block krylovschur ...]
[--tol 1e-8] [--repeat 1]``
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

from bench_housing_convergence import OUT as CONV, ROOT, run_modes

OUT = ROOT / "benchmarks" / "results" / "bench_housing_solvers.json"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--size", type=float, default=0.0156)
    ap.add_argument("--solvers", nargs="+", default=["block", "krylovschur", "subspace", "lobpcg"])
    ap.add_argument("--tol", type=float, nargs="+", default=[1e-8])
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("-n", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=400.0)
    ap.add_argument("--tag", default="", help="key of this invocation in the JSON (default: size, ranks)")
    a = ap.parse_args()
    ref = None
    if CONV.is_file() and "convergence" in json.loads(CONV.read_text()):
        ref = np.array(json.loads(CONV.read_text())["convergence"]["reference_hz"][:a.count])
    tmp = Path(tempfile.mkdtemp(prefix="vg-solv-"))
    rows, base = [], None
    try:
        for rep in range(a.repeat):
            for solver in a.solvers:
                for tol in a.tol:
                    sets = [f"housing.modes.solver={solver}", f"housing.modes.tol={tol}"]
                    row = {"solver": solver, "tol": tol, "repeat": rep}
                    try:
                        r = run_modes(a.size, count=a.count, n=a.n, sets=sets, tmp=tmp, timeout=a.timeout)
                    except subprocess.TimeoutExpired:
                        row.update(status="timeout", wall_s=a.timeout)
                    except RuntimeError as exc:
                        row.update(status="failed", error=str(exc)[-600:])
                    else:
                        f = np.array(r.pop("frequencies_hz"))
                        if base is None:
                            base = (r["wall_s"], f)
                        row.update(status="ok", **{k: r[k] for k in ("n_dofs", "wall_s", "eigensolve_s",
                                                                      "peak_memory_mb", "timings_s",
                                                                      "error_estimates", "load_average")},
                                   wall_ratio_to_baseline=r["wall_s"] / base[0],
                                   max_rel_dev_from_baseline=float(np.max(np.abs(f - base[1]) / base[1])),
                                   f1_hz=float(f[0]), f_last_hz=float(f[-1]))
                        if ref is not None and f.size == ref.size:
                            row["max_rel_error_vs_converged"] = float(np.max(np.abs(f - ref) / ref))
                    print(json.dumps({k: v for k, v in row.items() if k not in ("timings_s", "error")}),
                          flush=True)
                    rows.append(row)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    rec = json.loads(OUT.read_text()) if OUT.is_file() else {}
    rec[a.tag or f"size={a.size} n={a.n}"] = {
        "scene": "configs/housing.toml", "size": a.size, "bore_size": a.size / 2, "count": a.count,
        "n_processes": a.n, "baseline": rows[0]["solver"] if rows else None, "runs": rows,
        "load_average_after": os.getloadavg()}
    OUT.write_text(json.dumps(rec, indent=1))
    print(f"wrote {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
