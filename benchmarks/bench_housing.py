"""Housing benchmark: 100 master modes of the P2 gearbox housing (configs/housing.toml).

Prints wall times (no assertions).  Runs, each with an empty vibrogear cache:
  1. ``mpirun -n 2`` with an empty FFCx cache  -> first-run form-compilation time
  2. ``mpirun -n 2`` with a warm FFCx cache     -> the <= 35 s target (meshing + assembly + solve)
  3. optionally (--serial) one process with two OpenBLAS threads (CHOLMOD's supernodal factor and
     the dense block products then use both cores)
and then a cached rerun of the CLI (target <= 3 s).  Stage times (the eigen-solve split into
factorization, triangular solves, orthogonalization, mass products) and peak memory come from
each run's summary.json; wall is the whole CLI process (start-up, meshing, plots, XDMF included).
Results go to benchmarks/results/bench_housing.json.
Usage: ``python benchmarks/bench_housing.py [--serial] [--set k=v ...]``
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

ROOT = Path(__file__).resolve().parents[1]
TARGET_S = 35.0
SCENE = ROOT / "configs" / "housing.toml"
VG = Path(sys.executable).parent / "vibrogear"


def run(label, cmd, env, out):
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        print(f"{label}: FAILED rc={r.returncode}\n{r.stderr[-3000:]}")
        sys.exit(1)
    s = json.loads((out / "summary.json").read_text())["results"]["modes"]
    t = s["timings_s"]
    print(f"{label:<34} wall {wall:6.2f} s ({wall / TARGET_S:.2f} x target) | DOF {s['n_dofs']} | modes {s['n_modes']} | "
          f"f1 {s['frequencies_hz'][0]:.2f} Hz f_last {s['frequencies_hz'][-1]:.1f} Hz | "
          f"peak mem {s['peak_memory_mb']:.0f} MB (sum over ranks)")
    print("    stages: " + ", ".join(f"{k} {v:.2f}" for k, v in t.items() if not k.startswith("eigensolve_")))
    print("    eigensolve: " + ", ".join(f"{k[11:]} {v:.2f}" for k, v in t.items() if k.startswith("eigensolve_")))
    print(f"    max residual {s['error_estimates']['max_eigen_residual']:.2e}, "
          f"|V^T M V - I| {s['error_estimates']['mass_orthonormality_error']:.1e}")
    return wall, s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--serial", action="store_true", help="also time one process (2 BLAS threads)")
    ap.add_argument("--set", dest="sets", action="append", default=[])
    ap.add_argument("-n", type=int, default=2, help="MPI ranks")
    a = ap.parse_args()
    # ~160k P2 DOF: global size 1.5 x wall, 12 mm at the bores
    sets = ["--set", 'housing.mesh.element="tet"', "--set", "housing.modes.count=100", "--set", "housing.mesh.degree=2",
            "--set", "housing.mesh.size=0.018",
            "--set", "housing.mesh.bore_size=0.012"] + [x for s in a.sets for x in ("--set", s)]
    tmp = Path(tempfile.mkdtemp(prefix="vg-bench-"))
    base = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    mpi = [shutil.which("mpirun") or "mpirun", "-n", str(a.n)] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])
    runs = [("mpirun cold (FFCx cache empty)", mpi, tmp / "xdg_cold", tmp / "c1"),
            (f"mpirun -n {a.n} warm", mpi, tmp / "xdg_warm", tmp / "c2")]
    if a.serial:
        runs.append(("serial warm (2 BLAS threads)", [], tmp / "xdg_warm", tmp / "c3"))
    # warm the FFCx cache of the warm runs without touching the vibrogear caches being timed
    env = {**base, "XDG_CACHE_HOME": str(tmp / "xdg_warm"), "VIBROGEAR_CACHE_DIR": str(tmp / "c0")}
    subprocess.run([str(VG), "modes", str(SCENE), "--quiet", "--out", str(tmp / "o0")] + sets +
                   ["--set", "housing.mesh.size=0.024", "--set", "housing.modes.count=2"],
                   env=env, cwd=ROOT, capture_output=True)
    results = {}
    for label, pre, xdg, cache in runs:
        env = {**base, "XDG_CACHE_HOME": str(xdg), "VIBROGEAR_CACHE_DIR": str(cache),
               "OPENBLAS_NUM_THREADS": "1" if pre else "2"}
        out = tmp / f"out-{cache.name}"
        results[label] = run(label, pre + [str(VG), "modes", str(SCENE), "--quiet", "--out", str(out)] + sets,
                             env, out)
    env = {**base, "XDG_CACHE_HOME": str(tmp / "xdg_warm"), "VIBROGEAR_CACHE_DIR": str(tmp / "c2")}
    out = tmp / "out-cached"
    wall, s = run("cached rerun (serial CLI)", [str(VG), "modes", str(SCENE), "--quiet", "--out", str(out)] + sets,
                  env, out)
    cold = results["mpirun cold (FFCx cache empty)"][1]["timings_s"]["form_compilation"]
    warm = results[f"mpirun -n {a.n} warm"][1]["timings_s"]["form_compilation"]
    print(f"\nfirst-run form compilation {cold:.2f} s (warm cache: {warm:.2f} s); "
          f"cached rerun {wall:.2f} s (cached={s['cached']})")
    load = os.getloadavg()
    print(f"load average after: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    keep = ("n_dofs", "n_modes", "n_processes", "timings_s", "peak_memory_mb", "error_estimates")
    record = {"scene": str(SCENE.relative_to(ROOT)), "overrides": sets[1::2], "target_s": TARGET_S,
              "load_average_after": load,
              "runs": {k: {"wall_s": w, **{f: s_[f] for f in keep}} for k, (w, s_) in results.items()},
              "cached_rerun_wall_s": wall, "first_run_form_compilation_s": cold}
    out_json = ROOT / "benchmarks" / "results" / "bench_housing.json"
    out_json.parent.mkdir(parents=True, exist_ok=True)
    out_json.write_text(json.dumps(record, indent=2))
    print(f"wrote {out_json.relative_to(ROOT)}")
    shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
