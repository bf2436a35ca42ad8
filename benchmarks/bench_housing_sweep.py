"""Housing geometry sweep: each variant reused from the previous one against its own fresh solve.

One run, side by side: the wall-thickness variants of a housing (Q3 hexahedra) are solved in order
by :func:`vibrogear.models.housing.sweep.sweep_housing_modes` with reuse (moved mesh nodes, the
factor refactored numerically, the previous modes as start); right after each variant, the
same variant is solved afresh (its own generated mesh, assembly, factor, random-start block
Lanczos) in the same process.  Reported: each variant's seconds by stage, the ratio reused / fresh,
the largest relative difference of its ``count`` frequencies from the fresh ones, the residuals,
(all points with the base housing's mesh sizes, as the ``housing_sweep`` analysis runs them),
and the machine's load average (the machine is shared: compare ratios within the run, not seconds).

    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python benchmarks/bench_housing_sweep.py \\
        --config configs/housing.toml --count 100 --min 0.010 --max 0.016 --n 8
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="configs/housing.toml")
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("--min", type=float, default=0.010)
    ap.add_argument("--max", type=float, default=0.016)
    ap.add_argument("--n", type=int, default=8)
    ap.add_argument("--degree", type=int, default=3)
    ap.add_argument("--tol", type=float, default=None, help="the reused start's tolerance (default: the sweep's)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "bench_housing_sweep.json"))
    args = ap.parse_args(argv)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

    from vibrogear.config.base import build
    from vibrogear.config.sections.housing import HousingSweepConfig, pinned_hex_sizes
    from vibrogear.config.scene import load_scene
    from vibrogear.models.housing.sweep import DEFAULT_TOL, sweep_housing_modes

    base = load_scene(ROOT / args.config, ('housing.mesh.element="hex"', f"housing.mesh.degree={args.degree}")).housing
    # the [housing_sweep] the analysis would run: its points share the base housing's mesh sizes
    opts = build(HousingSweepConfig, {"parameter": "housing.wall_thickness", "min": args.min, "max": args.max,
                                      "n": args.n, "n_freqs": args.count}, "housing_sweep")
    values = np.array(opts.points())
    cfgs = opts.housing_points(base)
    tol = DEFAULT_TOL if args.tol is None else args.tol
    load0 = os.getloadavg()
    rows = []

    def stages(v):
        return {k: round(float(s), 3) for k, s in v.timings.items()}

    def side_by_side(i, reused):
        fresh = sweep_housing_modes([cfgs[i]], count=args.count, reuse=False)[0]
        diff = float(np.max(np.abs(reused.freqs_hz / fresh.freqs_hz - 1.0)))
        rows.append({"wall_thickness": float(values[i]), "n_dofs": fresh.n_dofs,
                     "reused": {"start": reused.start, "mesh": reused.mesh, "seconds": round(reused.seconds, 3),
                                "stages": stages(reused), "steps": reused.steps, "n_rhs": reused.n_rhs,
                                "criterion": reused.bound,
                                "residual_max": reused.residual, "product_check": reused.product_check,
                                "guard_spread": reused.spread, "guard_band": reused.band,
                                "note": reused.note},
                     "fresh": {"seconds": round(fresh.seconds, 3), "stages": stages(fresh), "n_rhs": fresh.n_rhs,
                               "residual_max": fresh.residual},
                     "ratio": round(reused.seconds / fresh.seconds, 3),
                     "max_rel_freq_diff": diff, "f1_hz": float(fresh.freqs_hz[0]),
                     f"f{args.count}_hz": float(fresh.freqs_hz[-1])})
        r = rows[-1]
        print(f"t = {values[i] * 1e3:.2f} mm: {reused.start:8s} {reused.seconds:6.1f} s, fresh {fresh.seconds:6.1f} s, "
              f"ratio {r['ratio']:.2f}, max |df/f| {diff:.1e}, steps {reused.steps}", flush=True)

    t0 = time.perf_counter()
    sweep_housing_modes(cfgs, count=args.count, reuse=True, tol=tol, on_variant=side_by_side)
    further = [r for r in rows[1:] if r["reused"]["start"] == "previous"]
    summary = {
        "config": args.config, "element": "hex", "degree": args.degree, "count": args.count,
        "wall_thickness": [float(v) for v in values], "tolerance": tol,
        "mesh_sizes_m": pinned_hex_sizes(base), "base_wall_thickness": base.wall_thickness,
        "ratio_further_max": max((r["ratio"] for r in further), default=None),
        "ratio_further_mean": float(np.mean([r["ratio"] for r in further])) if further else None,
        "max_rel_freq_diff": max(r["max_rel_freq_diff"] for r in rows),
        "seconds_total": round(time.perf_counter() - t0, 1),
        "load_average_start": load0, "load_average_end": os.getloadavg(),
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
        "variants": rows,
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(summary, indent=1))
    print(f"further variants: ratio max {summary['ratio_further_max']}, mean {summary['ratio_further_mean']}; "
          f"max |df/f| {summary['max_rel_freq_diff']:.1e}; load {load0[0]:.1f} -> {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
