"""Housing mesh-convergence study: 100 master modes of configs/housing.toml on P2 meshes of
decreasing size (``bore_size = size / 2``, the default rule), ``mpirun -n 2``, empty vibrogear
cache per run.  The reference is the Richardson extrapolation of the three finest meshes with the
observed order per mode (and, as a cross-check, a least-squares fit f = f0 + C h^p over all
levels).  Each run's DOF, wall, eigen-solve time, peak memory and frequencies are appended to
benchmarks/results/bench_housing_convergence.json (rerun with the same sizes to resume); the
errors of every level against the reference are written at the end.

Usage: ``python benchmarks/bench_housing_convergence.py [--sizes 0.024 0.018 ...] [--count 100]``

``--graded``: meshes graded towards the re-entrant junction edges (``[housing.mesh] edge_size``,
``edge_distance``), results in benchmarks/results/bench_housing_convergence_graded.json.  Each
level is ``size:edge_size`` (``--levels 0.024:0.006 0.024:0.003 ...``) or a size of ``--sizes``
with ``edge_size = --edge-ratio x size``; ``edge_distance`` is fixed (``--edge-distance``), so a
sequence with one ratio scales the whole size function uniformly (a proper h-sequence for
Richardson).  The graded reference is the Richardson limit of the three finest levels with
``edge_size / size = --edge-ratio``; every level's errors are given against it and against the
uniform study's reference.
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
OUT_GRADED = ROOT / "benchmarks" / "results" / "bench_housing_convergence_graded.json"


def mpirun(n: int) -> list[str]:
    return [shutil.which("mpirun") or "mpirun", "-n", str(n)] + (
        ["--allow-run-as-root"] if os.geteuid() == 0 else [])


def run_modes(size: float, *, count: int, n: int, sets=(), tmp: Path, timeout: float | None = None,
              scene: Path = SCENE, edge_size: float | None = None, edge_distance: float | None = None) -> dict:
    """One empty-cache ``vibrogear modes`` run; its summary plus the wall of the whole process."""
    cache = Path(tempfile.mkdtemp(prefix="c-", dir=tmp))
    out = Path(tempfile.mkdtemp(prefix="o-", dir=tmp))
    grading = [] if edge_size is None else [f"housing.mesh.edge_size={edge_size}"] + (
        [] if edge_distance is None else [f"housing.mesh.edge_distance={edge_distance}"])
    args = ['housing.mesh.element="tet"', f"housing.modes.count={count}", "housing.modes.shapes=0", "housing.mesh.degree=2",
            f"housing.mesh.size={size}",
            f"housing.mesh.bore_size={size / 2}", *grading, *sets]
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
    return {"size": size, "bore_size": size / 2, "edge_size": edge_size, "edge_distance": edge_distance,
            "n_processes": n, "overrides": args, "wall_s": wall,
            "n_dofs": s["n_dofs"], "eigensolve_s": s["timings_s"]["eigensolve"], "timings_s": s["timings_s"],
            "peak_memory_mb": s["peak_memory_mb"], "error_estimates": s["error_estimates"],
            "frequencies_hz": s["frequencies_hz"], "load_average": os.getloadavg()}


def reference(rows: list[dict], count: int) -> dict:
    """Richardson limit of the three finest levels (observed order per mode, clipped to [1, 4])."""
    from vibrogear.analyses.housing.convergence import observed_order, richardson

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


def errors(F: np.ndarray, ref: np.ndarray) -> dict:
    e = np.abs(F - ref) / ref
    return {"max_rel_error": float(e.max()), "max_error_mode": int(np.argmax(e)) + 1,
            "rel_error_mode1": float(e[0]), "rel_error_last": float(e[-1])}


def main_graded(a) -> None:
    rec = json.loads(OUT_GRADED.read_text()) if OUT_GRADED.is_file() else {
        "scene": "configs/housing.toml", "runs": []}
    levels = [tuple(float(v) for v in lv.split(":")) for lv in a.levels] if a.levels else [
        (s, round(a.edge_ratio * s, 9)) for s in a.sizes]
    tmp = Path(tempfile.mkdtemp(prefix="vg-conv-"))

    def same(r, size, he):
        return (abs(r["size"] - size) < 1e-12 and (r.get("edge_size") or 0) == he
                and r.get("edge_distance") == (a.edge_distance if he else None) and len(r["frequencies_hz"]) >= a.count)
    try:
        for size, he in levels:
            he = he or 0.0  # 0: the uniform mesh (same-run baseline)
            if any(same(r, size, he) for r in rec["runs"]):
                continue
            r = run_modes(size, count=a.count, n=a.n, tmp=tmp, edge_size=he or None,
                          edge_distance=a.edge_distance if he else None)
            print(f"size {size:.4f} edge {he:.4f}: {r['n_dofs']} DOF, wall {r['wall_s']:.1f} s, eigen "
                  f"{r['eigensolve_s']:.1f} s, peak {r['peak_memory_mb']:.0f} MB, f1 {r['frequencies_hz'][0]:.2f}, "
                  f"f{a.count} {r['frequencies_hz'][a.count - 1]:.1f}, load {os.getloadavg()[0]:.1f}", flush=True)
            rec["runs"].append(r)
            OUT_GRADED.write_text(json.dumps(rec, indent=1))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    seq = [r for r in rec["runs"] if r.get("edge_size") and r.get("edge_distance") == a.edge_distance
           and abs(r["edge_size"] / r["size"] - a.edge_ratio) < 1e-6]
    refs = {}
    if len(seq) >= 3:
        rec["convergence"] = reference(seq, a.count)
        rec["convergence"].update(edge_ratio=a.edge_ratio, edge_distance=a.edge_distance)
        refs["graded"] = np.array(rec["convergence"]["reference_hz"])
    if OUT.is_file() and "convergence" in json.loads(OUT.read_text()):
        refs["uniform"] = np.array(json.loads(OUT.read_text())["convergence"]["reference_hz"][:a.count])
    rec["levels"] = []
    for r in sorted(rec["runs"], key=lambda r: (-r["size"], -(r.get("edge_size") or r["size"]))):
        F = np.array(r["frequencies_hz"][:a.count])
        lv = {"size": r["size"], "edge_size": r.get("edge_size"), "edge_distance": r.get("edge_distance"),
              "n_dofs": r["n_dofs"], "wall_s": r["wall_s"], "eigensolve_s": r["eigensolve_s"],
              "load_average": r["load_average"], "f1_hz": F[0], "f_last_hz": F[-1]}
        for name, ref in refs.items():
            lv[f"vs_{name}"] = errors(F, ref)
        rec["levels"].append(lv)
        print(f"size {lv['size']:.4f} edge {lv['edge_size'] or 0:.4f} ({lv['n_dofs']} DOF, eigen "
              f"{lv['eigensolve_s']:.1f} s): " + "; ".join(
                  f"vs {name}: max {100 * e['max_rel_error']:.2f} % (mode {e['max_error_mode']}), f1 "
                  f"{100 * e['rel_error_mode1']:.2f} %, f{a.count} {100 * e['rel_error_last']:.2f} %"
                  for name, e in ((k, lv[f"vs_{k}"]) for k in refs)))
    OUT_GRADED.write_text(json.dumps(rec, indent=1))
    print(f"wrote {OUT_GRADED.relative_to(ROOT)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sizes", type=float, nargs="+", default=[0.024, 0.020, 0.0156, 0.012, 0.010])
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("-n", type=int, default=2)
    ap.add_argument("--graded", action="store_true", help="meshes graded towards the junction edges")
    ap.add_argument("--levels", nargs="+", help="graded levels size:edge_size (edge_size 0: uniform)")
    ap.add_argument("--edge-ratio", type=float, default=0.25, help="edge_size / size of the graded sequence")
    ap.add_argument("--edge-distance", type=float, default=0.024, help="edge_distance, m (fixed)")
    a = ap.parse_args()
    if a.graded:
        main_graded(a)
        return
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
