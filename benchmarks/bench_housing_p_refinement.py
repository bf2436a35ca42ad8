"""Housing p-refinement study (issue 23): 100 master modes of configs/housing.toml with P2 and P3
Lagrange tetrahedra on the same coarse meshes, ``mpirun -n 2``, empty vibrogear cache per run.

Conforming FE eigenvalues are upper bounds of the continuum ones, and on one mesh the P2 space lies
inside the P3 space, so P3 lowers every frequency of that mesh (min-max).  Comparing the P3
frequencies of two meshes (and the P2 -> P3 step on each) with the uniform and graded P2
h-sequences of ``bench_housing_convergence.py`` (``results/bench_housing_convergence.json``,
``..._graded.json``) tells which limit can be trusted; every run (these and the P2 sequences) is
then measured against that reference: f1, f100, max over the modes (and which), and the modes the
two-stage scene's criterion needs (up to 2 x the highest excitation frequency).

Each run's DOF, wall (whole CLI process), eigen-solve time, peak memory (the sum of the resident
set sizes of the run's process tree, sampled every 0.5 s, and the ranks' own maxrss) and
frequencies are appended to ``benchmarks/results/bench_housing_p_refinement.json`` (rerun with the
same levels to resume; ``--baseline`` reruns the P2 0.024 mesh in this invocation, for ratios under
the same load).  Runs whose process tree exceeds ``--mem-limit-gb`` are killed and recorded as such.

Usage: ``python benchmarks/bench_housing_p_refinement.py [--levels 0.024:2 0.024:3 0.020:3 ...]``
with a level ``size:degree[:bore_size[:edge_size]]`` (bore_size default size / 2, 0 or missing
edge_size: no grading; edge_distance stays its default 2 x wall).
"""
from __future__ import annotations

import argparse
import json
import os
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
DEFAULT_LEVELS = ["0.024:2", "0.024:3", "0.024:3:0.024", "0.020:3"]
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
    args = [f"housing.modes.count={count}", "housing.modes.shapes=0", f"housing.mesh.size={size}",
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
    row.update(wall_s=wall, peak_tree_rss_mb=peak, load_average=os.getloadavg())
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


def analyse(rec: dict, count: int) -> None:
    runs = [r for r in rec["runs"] if not r.get("failed") and len(r.get("frequencies_hz", [])) >= count]
    seqs = []
    for name, path in (("uniform P2", OUT_UNIFORM), ("graded P2", OUT_GRADED)):
        if path.is_file():
            for r in json.loads(path.read_text())["runs"]:
                if len(r["frequencies_hz"]) >= count:
                    seqs.append({**r, "degree": 2, "study": name})
    allruns = [{**r, "study": "p-refinement"} for r in runs] + seqs
    F = {id(r): np.array(r["frequencies_hz"][:count]) for r in allruns}
    # every conforming discretisation is an upper bound: the lowest frequency of each mode over all
    # runs is the tightest upper bound of the (sharp-edged, straight-sided) continuum value
    upper = np.min(np.array(list(F.values())), axis=0)
    p3 = sorted((r for r in allruns if r["study"] == "p-refinement" and r["degree"] == 3 and not r.get("edge_size")
                 and abs(r["bore_size"] - r["size"] / 2) < 1e-12), key=lambda r: -r["size"])
    p2 = {r["size"]: r for r in allruns if r["degree"] == 2 and not r.get("edge_size")
          and abs(r["bore_size"] - r["size"] / 2) < 1e-12}
    ref_info: dict = {"upper_bound_hz": upper.tolist()}
    if p3:
        fine = p3[-1]
        Ff = F[id(fine)]
        ref_info["finest_p3"] = {"size": fine["size"], "n_dofs": fine["n_dofs"]}
        # the P2 -> P3 step on each mesh, and the P3 change between meshes
        steps = {}
        for r in p3:
            if r["size"] in p2:
                d = (F[id(r)] - F[id(p2[r['size']])]) / F[id(r)]
                steps[str(r["size"])] = {"median": float(np.median(d)), "min": float(d.min()), "max": float(d.max())}
        ref_info["p2_to_p3_step"] = steps
        if len(p3) >= 2:
            c, f = p3[-2], p3[-1]
            d = (F[id(f)] - F[id(c)]) / F[id(f)]
            ref_info["p3_mesh_step"] = {"from": c["size"], "to": f["size"], "median": float(np.median(d)),
                                        "min": float(d.min()), "max": float(d.max())}
            # h-extrapolation of the two P3 meshes: order 1 (the singular-edge worst case seen in
            # the P2 sequences) and order 2 bracket the limit below the finest P3 run
            r_h = c["size"] / f["size"]
            for p in (1.0, 2.0):
                ext = F[id(f)] + (F[id(f)] - F[id(c)]) / (r_h ** p - 1.0)
                ref_info[f"p3_richardson_order{p:g}_hz"] = ext.tolist()
            ref = 0.5 * (np.array(ref_info["p3_richardson_order1_hz"]) + np.array(ref_info["p3_richardson_order2_hz"]))
            unc = np.abs(np.array(ref_info["p3_richardson_order1_hz"]) - np.array(ref_info["p3_richardson_order2_hz"])) / 2
            ref_info["reference_rule"] = ("mean of the order-1 and order-2 h-extrapolations of the two "
                                          "finest P3 meshes; uncertainty: half their difference")
        else:
            ref, unc = Ff.copy(), np.abs(Ff - F[id(p2[fine['size']])]) if fine["size"] in p2 else Ff * 0
            ref_info["reference_rule"] = "finest P3 run (upper bound); uncertainty: its P2 -> P3 step"
        ref_info["reference_hz"] = ref.tolist()
        ref_info["uncertainty_rel"] = (unc / ref).tolist()
        ref_info["uncertainty_rel_max"] = float(np.max(unc / ref))
        ref_info["uncertainty_rel_median"] = float(np.median(unc / ref))
        # the P2 sequences' own limits for comparison
        for name, path in (("uniform", OUT_UNIFORM), ("graded", OUT_GRADED)):
            if path.is_file() and "convergence" in json.loads(path.read_text()):
                R = np.array(json.loads(path.read_text())["convergence"]["reference_hz"][:count])
                e = (R - ref) / ref
                ref_info[f"{name}_p2_richardson_vs_reference"] = {
                    "median": float(np.median(e)), "min": float(e.min()), "max": float(e.max())}
        band = ref <= 2 * F_EXC_HZ
        ref_info["band"] = {"f_exc_hz": F_EXC_HZ, "cutoff_hz": 2 * F_EXC_HZ, "n_modes": int(band.sum())}
        rec["reference"] = ref_info
        rec["levels"] = []
        for r in sorted(allruns, key=lambda r: (r["study"], -r["size"], r["degree"], -(r.get("edge_size") or r["size"]))):
            e = errors(F[id(r)], ref, band)
            rec["levels"].append({"study": r["study"], "size": r["size"], "bore_size": r.get("bore_size"),
                                  "degree": r["degree"], "edge_size": r.get("edge_size"), "n_dofs": r["n_dofs"],
                                  "wall_s": r["wall_s"], "eigensolve_s": r["eigensolve_s"],
                                  "peak_memory_mb": r["peak_memory_mb"], "peak_tree_rss_mb": r.get("peak_tree_rss_mb"),
                                  "load_average": r["load_average"], "f1_hz": float(F[id(r)][0]),
                                  "f_last_hz": float(F[id(r)][-1]), **e})
            print(f"{r['study']:13s} size {r['size']:.4f} bore {r.get('bore_size') or 0:.4f} P{r['degree']} edge "
                  f"{r.get('edge_size') or 0:.4f}: {r['n_dofs']:7d} DOF wall {r['wall_s']:6.1f} s eigen "
                  f"{r['eigensolve_s']:6.1f} s  f1 {F[id(r)][0]:.2f}  f{count} {F[id(r)][-1]:.1f}  max "
                  f"{100 * e['max_rel_error']:.2f} % (mode {e['max_error_mode']}), f1 {100 * e['rel_error_mode1']:+.2f} %, "
                  f"f{count} {100 * e['rel_error_last']:+.2f} %, median {100 * e['median_rel_error']:+.2f} %")
        print(f"reference ({ref_info['reference_rule']}): f1 {ref[0]:.2f} Hz, f{count} {ref[-1]:.1f} Hz, "
              f"uncertainty max {100 * ref_info['uncertainty_rel_max']:.2f} %, median "
              f"{100 * ref_info['uncertainty_rel_median']:.2f} %; upper bound f1 {upper[0]:.2f}, f{count} {upper[-1]:.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--levels", nargs="+", default=DEFAULT_LEVELS,
                    help="size:degree[:bore_size[:edge_size]]")
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("-n", type=int, default=2)
    ap.add_argument("--mem-limit-gb", type=float, default=12.0)
    ap.add_argument("--set", dest="sets", action="append", default=[], help="extra --set for every run")
    ap.add_argument("--baseline", action="store_true", help="rerun P2 0.024 first (same-load ratios)")
    ap.add_argument("--analyse-only", action="store_true")
    a = ap.parse_args()
    rec = json.loads(OUT.read_text()) if OUT.is_file() else {"scene": "configs/housing.toml", "runs": []}
    tmp = Path(tempfile.mkdtemp(prefix="vg-pref-"))
    levels = []
    for lv in a.levels:
        v = [float(x) for x in lv.split(":")]
        levels.append((v[0], int(v[1]), v[2] if len(v) > 2 and v[2] else v[0] / 2,
                       v[3] if len(v) > 3 and v[3] else None))
    if a.baseline:
        levels.insert(0, (0.024, 2, 0.012, None))

    def same(r, size, deg, hb, he):
        return (abs(r["size"] - size) < 1e-12 and r["degree"] == deg and abs(r["bore_size"] - hb) < 1e-12
                and (r.get("edge_size") or None) == he and r.get("overrides", [])[5:] == [
                    *([f"housing.mesh.edge_size={he}"] if he else []), *a.sets])
    try:
        for k, (size, deg, hb, he) in enumerate(levels):
            if a.analyse_only or (not (a.baseline and k == 0) and any(same(r, size, deg, hb, he) for r in rec["runs"])):
                continue
            r = run_modes(size, deg, bore_size=hb, edge_size=he, count=a.count, n=a.n, tmp=tmp, sets=a.sets,
                          mem_limit_gb=a.mem_limit_gb)
            if r.get("failed"):
                print(f"size {size} P{deg} bore {hb} edge {he}: FAILED ({r['failed'][:300]}), wall "
                      f"{r['wall_s']:.1f} s, peak tree RSS {r['peak_tree_rss_mb']:.0f} MB", flush=True)
            else:
                print(f"size {size} P{deg} bore {hb} edge {he}: {r['n_dofs']} DOF, wall {r['wall_s']:.1f} s, eigen "
                      f"{r['eigensolve_s']:.1f} s, peak {r['peak_memory_mb']:.0f} MB (tree {r['peak_tree_rss_mb']:.0f}), "
                      f"f1 {r['frequencies_hz'][0]:.2f}, f{a.count} {r['frequencies_hz'][a.count - 1]:.1f}, load "
                      f"{os.getloadavg()[0]:.1f}", flush=True)
            rec["runs"].append(r)
            OUT.write_text(json.dumps(rec, indent=1))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    analyse(rec, a.count)
    OUT.write_text(json.dumps(rec, indent=1))
    print(f"wrote {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
