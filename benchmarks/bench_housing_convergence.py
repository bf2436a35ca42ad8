"""Housing mesh-convergence study: 100 master modes of configs/housing.toml on P2 meshes of
decreasing size (``bore_size = size / 2``, the default rule), ``mpirun -n 2``, empty vibrogear
cache per run.  The reference is the Richardson extrapolation of the three finest meshes with the
observed order per mode (and, as a cross-check, a least-squares fit f = f0 + C h^p over all
levels).  Each run's DOF, wall, eigen-solve time, peak memory and frequencies are appended to
benchmarks/results/bench_housing_convergence.json (rerun with the same sizes to resume); the
errors of every level against the reference are written at the end.

Usage: ``python benchmarks/bench_housing_convergence.py [--sizes 0.024 0.018 ...] [--count 100]``
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "configs" / "housing.toml"
VG = Path(sys.executable).parent / "vibrogear"
OUT = ROOT / "benchmarks" / "results" / "bench_housing_convergence.json"


def mpirun(n: int) -> list[str]:
    return [shutil.which("mpirun") or "mpirun", "-n", str(n)] + (
        ["--allow-run-as-root"] if os.geteuid() == 0 else [])


def run_modes(size: float, *, count: int, n: int, sets=(), tmp: Path, timeout: float | None = None,
              scene: Path = SCENE) -> dict:
    """One empty-cache ``vibrogear modes`` run; its summary plus the wall of the whole process."""
    cache = Path(tempfile.mkdtemp(prefix="c-", dir=tmp))
    out = Path(tempfile.mkdtemp(prefix="o-", dir=tmp))
    args = [f"housing.modes.count={count}", "housing.modes.shapes=0", f"housing.mesh.size={size}",
            f"housing.mesh.bore_size={size / 2}", *sets]
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "VIBROGEAR_CACHE_DIR": str(cache),
           "XDG_CACHE_HOME": str(tmp / "xdg")}
    cmd = (mpirun(n) if n > 1 else []) + [str(VG), "modes", str(scene), "--quiet", "--out", str(out)]
    for a in args:
        cmd += ["--set", a]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True, timeout=timeout)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise RuntimeError(f"size {size}: rc={r.returncode}\n{r.stderr[-1500:]}")
    s = json.loads((out / "summary.json").read_text())["results"]["modes"]
    shutil.rmtree(cache, ignore_errors=True)
    shutil.rmtree(out, ignore_errors=True)
    return {"size": size, "bore_size": size / 2, "n_processes": n, "overrides": args, "wall_s": wall,
            "n_dofs": s["n_dofs"], "eigensolve_s": s["timings_s"]["eigensolve"], "timings_s": s["timings_s"],
            "peak_memory_mb": s["peak_memory_mb"], "error_estimates": s["error_estimates"],
            "frequencies_hz": s["frequencies_hz"], "load_average": os.getloadavg()}


def reference(rows: list[dict], count: int) -> dict:
    """Richardson limit of the three finest levels (observed order per mode, clipped to [1, 4])."""
    from vibrogear.analyses.housing_study import observed_order, richardson

    rows = sorted(rows, key=lambda r: -r["size"])
    F = np.array([r["frequencies_hz"][:count] for r in rows])
    h = np.array([r["size"] for r in rows])
    p = observed_order(F[-3:], h[-3:])
    p_med = float(np.nanmedian(p))
    p_use = np.clip(np.where(np.isfinite(p), p, p_med), 1.0, 4.0)
    ref = richardson(F[-3:], h[-3:], p_use)
    # least-squares cross-check over all levels with the median order
    A = np.column_stack([np.ones_like(h), h ** p_med])
    ref_ls = np.linalg.lstsq(A, F, rcond=None)[0][0]
    return {"sizes": h.tolist(), "order_per_mode": p.tolist(), "order_median": p_med,
            "reference_hz": ref.tolist(), "reference_lsq_hz": ref_ls.tolist(),
            "reference_spread_max": float(np.max(np.abs(ref - ref_ls) / ref)),
            "levels": [{"size": r["size"], "n_dofs": r["n_dofs"], "wall_s": r["wall_s"],
                        "max_rel_error": float(np.max(np.abs(F[i] - ref) / ref)),
                        "rel_error_mode1": float(abs(F[i, 0] - ref[0]) / ref[0]),
                        "rel_error_last": float(abs(F[i, -1] - ref[-1]) / ref[-1])}
                       for i, r in enumerate(rows)]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sizes", type=float, nargs="+", default=[0.024, 0.020, 0.0156, 0.012, 0.010])
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("-n", type=int, default=2)
    a = ap.parse_args()
    rec = json.loads(OUT.read_text()) if OUT.is_file() else {"scene": "configs/housing.toml", "runs": []}
    tmp = Path(tempfile.mkdtemp(prefix="vg-conv-"))
    try:
        for size in a.sizes:
            if any(abs(r["size"] - size) < 1e-12 and len(r["frequencies_hz"]) >= a.count for r in rec["runs"]):
                continue
            r = run_modes(size, count=a.count, n=a.n, tmp=tmp)
            print(f"size {size:.4f}: {r['n_dofs']} DOF, wall {r['wall_s']:.1f} s, eigen {r['eigensolve_s']:.1f} s, "
                  f"peak {r['peak_memory_mb']:.0f} MB, f1 {r['frequencies_hz'][0]:.2f}, "
                  f"f{a.count} {r['frequencies_hz'][a.count - 1]:.1f}", flush=True)
            rec["runs"].append(r)
            OUT.write_text(json.dumps(rec, indent=1))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if len(rec["runs"]) >= 3:
        rec["convergence"] = reference(rec["runs"], a.count)
        for lv in rec["convergence"]["levels"]:
            print(f"size {lv['size']:.4f} ({lv['n_dofs']} DOF): max error {100 * lv['max_rel_error']:.3f} %, "
                  f"mode 1 {100 * lv['rel_error_mode1']:.3f} %, mode {a.count} {100 * lv['rel_error_last']:.3f} %")
        OUT.write_text(json.dumps(rec, indent=1))
    print(f"wrote {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
