"""Housing p-refinement study (issue 23): 100 master modes of configs/housing.toml with P2 and P3
Lagrange tetrahedra on the same coarse meshes, ``mpirun -n 2``, empty vibrogear cache per run.

Conforming FE eigenvalues are upper bounds of the continuum ones, and on one mesh the P2 space lies
inside the P3 space, so P3 lowers every frequency of that mesh (min-max).  Comparing the P3
frequencies of two meshes (and the P2 -> P3 step on each) with the uniform and graded P2
h-sequences of ``bench_housing_convergence.py`` (``results/bench_housing_convergence.json``,
``..._graded.json``) tells which limit can be trusted; every run (these and the P2 sequences) is
then measured against that reference: f1, f100, max over the modes (and which), and the modes the
two-stage scene's criterion needs (up to 2 x the highest excitation frequency).

The reference (:func:`p3_reference`): the P2 -> P3 step on one mesh (0.8-3.1 %) dwarfs every P3
mesh step (<= 0.4 %), most of which comes from the re-entrant junction edges, so an additive model
f = f* + B h_bulk^qb + C h_edge^qe is fitted per mode from four P3 levels: the junction edges at
0.024 / 0.012 / 0.006 (``edge_distance`` 0.012, bulk 0.024) and the bulk step 0.024 -> 0.020 at edge
0.012; its uncertainty is the spread over the order ranges plus its miss of the uniform P3 0.020 run.

Each run's DOF, wall (whole CLI process), eigen-solve time, peak memory (the ranks' summed maxrss,
and the resident set size of the run's process tree sampled every 0.5 s) and frequencies are
appended to ``benchmarks/results/bench_housing_p_refinement.json`` (rerun to resume: levels already
there are skipped).  Runs whose process tree exceeds ``--mem-limit-gb`` are killed and recorded as
failed.  ``--timing`` reruns the frontier candidates back to back (P2 0.024 first and last), for
wall-time ratios under one load.

Usage: ``python benchmarks/bench_housing_p_refinement.py [--levels 0.024:3 0.024:3:0.012:0.006:0.012 ...]``
with a level ``size:degree[:bore_size[:edge_size[:edge_distance[:tol]]]]`` (0 or empty: the default:
bore_size = size / 2, no grading, edge_distance 2 x wall, tol 1e-8); ``--timing``; ``--analyse-only``.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_housing_convergence import OUT as OUT_UNIFORM, OUT_GRADED, ROOT, SCENE, VG, mpirun  # noqa: E402

OUT = ROOT / "benchmarks" / "results" / "bench_housing_p_refinement.json"
#: the two-stage scene's highest excitation frequency at its top speed (3000 rpm: G1's second
#: transmission-error harmonic, 2 x 40 teeth x 50 Hz; ``master_level.excitation_frequencies_hz``)
F_EXC_HZ = 4000.0


def _tree_rss_mb(pid: int) -> float:
    """Resident set size of ``pid`` and all its descendants, MB (Linux /proc)."""
    children: dict[int, list[int]] = {}
    rss: dict[int, float] = {}
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat") as fh:
                parts = fh.read().rsplit(")", 1)[1].split()
            children.setdefault(int(parts[1]), []).append(int(d))
            rss[int(d)] = int(parts[21]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20
        except (OSError, IndexError, ValueError):
            continue
    total, todo = 0.0, [pid]
    while todo:
        p = todo.pop()
        total += rss.get(p, 0.0)
        todo.extend(children.get(p, []))
    return total


def run_modes(size: float, degree: int, *, bore_size: float | None = None, edge_size: float | None = None,
              count: int = 100, n: int = 2, tmp: Path, sets=(), mem_limit_gb: float = 12.0,
              timeout: float = 1800.0) -> dict:
    """One empty-cache ``vibrogear modes`` run (fresh vibrogear cache; the form-compiler cache
    ``XDG_CACHE_HOME`` is shared within one invocation, as in bench_housing_convergence)."""
    bore_size = size / 2 if bore_size is None else bore_size
    cache = Path(tempfile.mkdtemp(prefix="c-", dir=tmp))
    out = Path(tempfile.mkdtemp(prefix="o-", dir=tmp))
    args = ['housing.mesh.element="tet"', f"housing.modes.count={count}", "housing.modes.shapes=0", f"housing.mesh.size={size}",
            f"housing.mesh.bore_size={bore_size}", f"housing.mesh.degree={degree}",
            *([f"housing.mesh.edge_size={edge_size}"] if edge_size else []), *sets]
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "VIBROGEAR_CACHE_DIR": str(cache),
           "XDG_CACHE_HOME": str(tmp / "xdg")}
    cmd = (mpirun(n) + ["--oversubscribe"] if n > 1 else []) + [str(VG), "modes", str(SCENE), "--quiet",
                                                               "--out", str(out)]
    for a in args:
        cmd += ["--set", a]
    row = {"size": size, "bore_size": bore_size, "degree": degree, "edge_size": edge_size,
           "n_processes": n, "overrides": args, "load_average_start": os.getloadavg()}
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    peak, killed = 0.0, None
    while proc.poll() is None:
        peak = max(peak, _tree_rss_mb(proc.pid))
        if peak > mem_limit_gb * 1024:
            killed = f"memory: process tree above {mem_limit_gb:g} GB"
        elif time.perf_counter() - t0 > timeout:
            killed = f"timeout after {timeout:g} s"
        if killed:
            os.killpg(proc.pid, signal.SIGKILL)
            break
        time.sleep(0.5)
    _, stderr = proc.communicate()
    wall = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    # CPU seconds of the whole process tree (mpirun and the ranks): less sensitive to other jobs
    # on the machine than the wall
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    row.update(wall_s=wall, cpu_s=cpu, peak_tree_rss_mb=peak, load_average=os.getloadavg())
    try:
        if killed or proc.returncode != 0:
            row.update(failed=killed or f"rc={proc.returncode}: {stderr[-1500:]}")
            return row
        s = json.loads((out / "summary.json").read_text())["results"]["modes"]
        row.update(n_dofs=s["n_dofs"], eigensolve_s=s["timings_s"]["eigensolve"], timings_s=s["timings_s"],
                   peak_memory_mb=s["peak_memory_mb"], error_estimates=s["error_estimates"],
                   frequencies_hz=s["frequencies_hz"])
        return row
    finally:
        shutil.rmtree(cache, ignore_errors=True)
        shutil.rmtree(out, ignore_errors=True)


def run_key(r: dict) -> tuple:
    """(size, degree, bore_size, edge_size, edge_distance, tol) of a run; None: the default."""
    ov = dict(o.split("=", 1) for o in r.get("overrides", []))
    dist, tol = ov.get("housing.mesh.edge_distance"), ov.get("housing.modes.tol")
    return (round(r["size"], 9), int(r.get("degree", 2)), round(r.get("bore_size") or r["size"] / 2, 9),
            round(r["edge_size"], 9) if r.get("edge_size") else None,
            float(dist) if dist and r.get("edge_size") else None, float(tol) if tol else None)


def parse_level(lv: str) -> tuple:
    """``size:degree[:bore_size[:edge_size[:edge_distance[:tol]]]]`` (0 or empty: the default)."""
    v = [float(x) if x else 0.0 for x in lv.split(":")] + [0.0] * 4
    size, deg = v[0], int(v[1])
    return (round(size, 9), deg, round(v[2] or size / 2, 9), round(v[3], 9) or None,
            (v[4] or None) if v[3] else None, v[5] or None)


#: the reference levels (keys as in :func:`run_key`): P3 on the bulk mesh 0.024 (bore 0.012) with
#: the junction edges at 0.024 (uniform), 0.012, 0.006 (edge_distance 0.012), and the bulk step to
#: 0.020 (bore 0.010) at edge size 0.012
REF_U = (0.024, 3, 0.012, None, None, None)
REF_E1 = (0.024, 3, 0.012, 0.012, 0.012, None)
REF_E2 = (0.024, 3, 0.012, 0.006, 0.012, None)
REF_B = (0.02, 3, 0.01, 0.012, 0.012, None)
#: bulk order range (central 2) and edge order range used for the reference and its uncertainty
BULK_ORDERS, BULK_ORDER = (1.5, 3.0), 2.0
EDGE_ORDERS = (1.0, 2.0)
DEFAULT_LEVELS = ["0.024:2", "0.024:3", "0.024:3:0.024", "0.020:3", "0.024:3:0.012:0.012",
                  "0.024:3:0.012:0.012:0.012", "0.024:3:0.012:0.006:0.012", "0.020:3:0.010:0.012:0.012",
                  "0.024:2:0.012:0:0:1e-5", "0.024:3:0.024:0:0:1e-5", "0.024:3:0.012:0:0:1e-5", "0.024:3:0.018"]
#: the frontier candidates, rerun back to back by --timing (ratios under one load)
TIMING_LEVELS = ["0.024:2", "0.024:3:0.024:0:0:1e-5", "0.024:3:0.018:0:0:1e-5", "0.024:3:0.012:0:0:1e-5",
                 "0.024:3", "0.024:2"]


def errors(F: np.ndarray, ref: np.ndarray, band: np.ndarray) -> dict:
    """Relative errors (signed: F above ref is positive) against ``ref``; ``band`` selects the
    modes the reduced model needs."""
    e = (F - ref) / ref
    a = np.abs(e)
    return {"max_rel_error": float(a.max()), "max_error_mode": int(np.argmax(a)) + 1,
            "rel_error_mode1": float(e[0]), "rel_error_last": float(e[-1]),
            "median_rel_error": float(np.median(e)), "min_rel_error": float(e.min()),
            "max_rel_error_band": float(a[band].max()) if band.any() else None,
            "n_band": int(band.sum())}


def p3_reference(F: dict) -> dict:
    """Additive error model f(h_bulk, h_edge) = f* + B h_bulk^qb + C h_edge^qe from the four P3
    reference levels: the edge sequence (0.024, 0.012, 0.006 at bulk 0.024) gives the edge
    remainder with its observed ratio (clipped to orders 1..2), the bulk step 0.024 -> 0.020 at edge
    0.012 the bulk term (order 2; 1.5 and 3 for the range).  Uncertainty: the spread over the order
    ranges plus the model's miss of the uniform P3 0.020 run (measured, not fitted)."""
    u, e1, e2, b = (F[k] for k in (REF_U, REF_E1, REF_E2, REF_B))
    d1, d2, db = e1 - u, e2 - e1, b - e1
    ratio = d2 / d1

    def model(r_edge, qb):
        edge = -d2 * r_edge / (1 - r_edge)                    # remainder at edge 0.006 (> 0)
        bulk = -db / (1 - (REF_B[0] / REF_U[0]) ** qb)         # bulk term at 0.024 (> 0)
        return e2 - edge - bulk, edge, bulk
    r_c = np.clip(ratio, 0.5 ** EDGE_ORDERS[1], 0.5 ** EDGE_ORDERS[0])
    ref, edge, bulk = model(r_c, BULK_ORDER)
    cands = [model(np.full_like(d2, 0.5 ** qe), qb)[0] for qe in EDGE_ORDERS for qb in BULK_ORDERS]
    spread = np.maximum(ref - np.min(cands, axis=0), np.max(cands, axis=0) - ref)
    info = {"reference_hz": ref.tolist(), "edge_ratio_per_mode": ratio.tolist(),
            "edge_order_median": float(-np.log2(np.median(ratio))),
            "edge_remainder_rel": (edge / ref).tolist(), "bulk_term_at_0024_rel": (bulk / ref).tolist(),
            "order_spread_rel": (spread / ref).tolist()}
    uni = F.get((0.02, 3, 0.01, None, None, None))
    miss = np.zeros_like(ref)
    if uni is not None:          # the model's prediction of the uniform 0.020 P3 run
        qe = -np.log2(r_c)
        pred = ref + edge * (0.020 / 0.006) ** qe + bulk * (0.020 / 0.024) ** BULK_ORDER
        miss = np.abs(uni - pred)
        info["uniform_0020_vs_model_rel"] = ((uni - pred) / pred).tolist()
    unc = spread + miss
    info.update(uncertainty_rel=(unc / ref).tolist(), uncertainty_rel_max=float(np.max(unc / ref)),
                uncertainty_rel_median=float(np.median(unc / ref)),
                uncertainty_max_mode=int(np.argmax(unc / ref)) + 1)
    return info


def analyse(rec: dict, count: int) -> None:
    runs = [r for r in rec["runs"] if not r.get("failed") and len(r.get("frequencies_hz", [])) >= count]
    allruns = [{**r, "study": "p-refinement"} for r in runs]
    for name, path in (("uniform P2", OUT_UNIFORM), ("graded P2", OUT_GRADED)):
        if path.is_file():
            for r in json.loads(path.read_text())["runs"]:
                if len(r["frequencies_hz"]) >= count:
                    allruns.append({**r, "degree": 2, "study": name,
                                    "overrides": r.get("overrides", []) + ([f"housing.mesh.edge_distance="
                                                                            f"{r['edge_distance']}"]
                                                                           if r.get("edge_distance") else [])})
    F = {run_key(r): np.array(r["frequencies_hz"][:count]) for r in runs}
    if not all(k in F for k in (REF_U, REF_E1, REF_E2, REF_B)):
        print("reference levels missing: run the default levels first")
        return
    info = p3_reference(F)
    ref = np.array(info["reference_hz"])
    # every conforming discretisation is an upper bound (up to the faceting of the bores)
    upper = np.min(np.array([np.array(r["frequencies_hz"][:count]) for r in allruns]), axis=0)
    info["upper_bound_hz"] = upper.tolist()
    info["reference_vs_upper_bound_rel"] = {"median": float(np.median((ref - upper) / upper)),
                                           "max": float(np.max((ref - upper) / upper))}
    for name, path in (("uniform", OUT_UNIFORM), ("graded", OUT_GRADED)):
        if path.is_file() and "convergence" in json.loads(path.read_text()):
            R = np.array(json.loads(path.read_text())["convergence"]["reference_hz"][:count])
            e = (R - ref) / ref
            info[f"{name}_p2_richardson_vs_reference"] = {"median": float(np.median(e)), "min": float(e.min()),
                                                         "max": float(e.max())}
    band = ref <= 2 * F_EXC_HZ
    info["band"] = {"f_exc_hz": F_EXC_HZ, "cutoff_hz": 2 * F_EXC_HZ, "n_modes": int(band.sum()),
                    "note": "2 x the two-stage scene's highest excitation (8 kHz) lies above mode 100"}
    rec["reference"] = info
    rec["levels"] = []
    for r in sorted(allruns, key=lambda r: (r["study"], r["degree"], -r["size"], -(r.get("edge_size") or r["size"]))):
        Fr = np.array(r["frequencies_hz"][:count])
        e = errors(Fr, ref, band)
        k = run_key(r)
        lv = {"study": r["study"], "size": k[0], "degree": k[1], "bore_size": k[2], "edge_size": k[3],
              "edge_distance": k[4] if r["study"] == "p-refinement" else r.get("edge_distance"), "tol": k[5],
              "n_dofs": r["n_dofs"], "wall_s": r["wall_s"], "cpu_s": r.get("cpu_s"), "eigensolve_s": r["eigensolve_s"],
              "peak_memory_mb": r["peak_memory_mb"], "peak_tree_rss_mb": r.get("peak_tree_rss_mb"),
              "load_average": r["load_average"], "f1_hz": float(Fr[0]), "f_last_hz": float(Fr[-1]),
              "within_1pct_all": bool(e["max_rel_error"] <= 0.01),
              "within_1pct_with_uncertainty": bool(np.all(np.abs(Fr - ref) + np.array(info["uncertainty_rel"]) * ref
                                                          <= 0.01 * ref)), **e}
        rec["levels"].append(lv)
        print(f"{lv['study']:13s} {lv['size']:.4f}/{lv['bore_size']:.4f} P{lv['degree']} edge {lv['edge_size'] or 0:.4f}"
              f"/{lv['edge_distance'] or 0:.3f} tol {lv['tol'] or 1e-8:g}: {lv['n_dofs']:7d} DOF wall {lv['wall_s']:6.1f} s "
              f"eigen {lv['eigensolve_s']:6.1f} s mem {lv['peak_memory_mb'] / 1024:4.1f} GB f1 {Fr[0]:.2f} f{count} "
              f"{Fr[-1]:.1f} | max {100 * e['max_rel_error']:.2f} % (mode {e['max_error_mode']}) f1 "
              f"{100 * e['rel_error_mode1']:+.2f} % f{count} {100 * e['rel_error_last']:+.2f} % median "
              f"{100 * e['median_rel_error']:+.2f} %{'  <1% incl. unc.' if lv['within_1pct_with_uncertainty'] else ''}")
    print(f"reference: f1 {ref[0]:.2f} Hz, f{count} {ref[-1]:.1f} Hz; uncertainty median "
          f"{100 * info['uncertainty_rel_median']:.2f} %, max {100 * info['uncertainty_rel_max']:.2f} % (mode "
          f"{info['uncertainty_max_mode']}); edge order (median) {info['edge_order_median']:.2f}; reference vs "
          f"lowest computed: median {100 * info['reference_vs_upper_bound_rel']['median']:+.2f} %")
    for name in ("uniform", "graded"):
        if f"{name}_p2_richardson_vs_reference" in info:
            e = info[f"{name}_p2_richardson_vs_reference"]
            print(f"{name} P2 Richardson limit vs reference: median {100 * e['median']:+.2f} %, "
                  f"{100 * e['min']:+.2f} ... {100 * e['max']:+.2f} %")
    for t in rec.get("timing", []):
        base = [r for r in t["runs"] if run_key(r) == (0.024, 2, 0.012, None, None, None) and not r.get("failed")]
        for r in t["runs"]:
            if not r.get("failed"):
                print(f"timing {t['started']}: {run_key(r)} wall {r['wall_s']:.1f} s eigen {r['eigensolve_s']:.1f} s"
                      f" cpu {r.get('cpu_s', float('nan')):.1f} s load {r['load_average'][0]:.1f}"
                      + (f" ({r['wall_s'] / np.mean([b['wall_s'] for b in base]):.2f}x P2 0.024)" if base else ""))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--levels", nargs="+", default=DEFAULT_LEVELS,
                    help="size:degree[:bore_size[:edge_size[:edge_distance[:tol]]]]")
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("-n", type=int, default=2)
    ap.add_argument("--mem-limit-gb", type=float, default=12.0)
    ap.add_argument("--timing", action="store_true",
                    help="rerun the frontier candidates (TIMING_LEVELS or --levels) back to back")
    ap.add_argument("--analyse-only", action="store_true")
    a = ap.parse_args()
    rec = json.loads(OUT.read_text()) if OUT.is_file() else {"scene": "configs/housing.toml", "runs": []}
    tmp = Path(tempfile.mkdtemp(prefix="vg-pref-"))
    levels = [parse_level(lv) for lv in (a.levels if not a.timing or a.levels is not DEFAULT_LEVELS
                                         else TIMING_LEVELS)]
    timing = {"started": time.strftime("%Y-%m-%d %H:%M:%S"), "runs": []}
    try:
        for key in ([] if a.analyse_only else levels):
            if not a.timing and any(run_key(r) == key and not r.get("failed") for r in rec["runs"]):
                continue
            size, deg, hb, he, dist, tol = key
            sets = ([f"housing.mesh.edge_distance={dist}"] if dist else []) + (
                [f"housing.modes.tol={tol}"] if tol else [])
            r = run_modes(size, deg, bore_size=hb, edge_size=he, count=a.count, n=a.n, tmp=tmp, sets=sets,
                          mem_limit_gb=a.mem_limit_gb)
            if r.get("failed"):
                print(f"{key}: FAILED ({r['failed'][:300]}), wall {r['wall_s']:.1f} s, peak tree RSS "
                      f"{r['peak_tree_rss_mb']:.0f} MB", flush=True)
            else:
                print(f"{key}: {r['n_dofs']} DOF, wall {r['wall_s']:.1f} s, eigen {r['eigensolve_s']:.1f} s, peak "
                      f"{r['peak_memory_mb']:.0f} MB (tree {r['peak_tree_rss_mb']:.0f}), f1 {r['frequencies_hz'][0]:.2f}, "
                      f"f{a.count} {r['frequencies_hz'][a.count - 1]:.1f}, load {os.getloadavg()[0]:.1f}", flush=True)
            if a.timing:
                timing["runs"].append(r)
                rec.setdefault("timing", [])
                if timing not in rec["timing"]:
                    rec["timing"].append(timing)
            else:
                rec["runs"].append(r)
            OUT.write_text(json.dumps(rec, indent=1))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    analyse(rec, a.count)
    OUT.write_text(json.dumps(rec, indent=1))
    print(f"wrote {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
