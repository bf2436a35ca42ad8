"""Cost of the Lyapunov evidence: a two-stage sweep point with and without it (issue 10's
target: the exponent costs at most 1.5x the point without it).

Each speed's point is run by :func:`vibrogear.solvers.sequential.sweep_point.run_point` from the same
settled state twice, ``lyapunov=True`` and ``False``, at the demo sweep's settings and
tolerance (the accuracy rule); both in this run, alternating, best of ``--repeats``.  The
exponent is computed only where the record has no period, so the ratio is reported per point
with the point's class.

Run: .venv/bin/python benchmarks/bench_lyapunov.py   (never run by the tests)
Writes benchmarks/results/bench_lyapunov.json.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from vibrogear.analyses.study import build_study, integration_options  # noqa: E402
from vibrogear.config import load_scene  # noqa: E402
from vibrogear.solvers.sequential.motion import MOTION_LEGEND  # noqa: E402
from vibrogear.solvers.sequential.sweep_point import run_point  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default=str(ROOT / "configs" / "two_stage.toml"))
    ap.add_argument("--rpm", type=float, nargs="*", default=[1700.0, 2000.0, 2400.0, 2800.0])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/bench_lyapunov.json"))
    args = ap.parse_args()
    scene = load_scene(args.scene)
    study = build_study(scene)
    cfg = scene.sweep
    opts = integration_options(scene, record=True, period_tol=cfg.period_tol)
    kw = dict(transient_periods=cfg.transient_periods, record_periods=cfg.record_periods,
              max_period=cfg.max_period, period_tol=cfg.period_tol, cluster_tol=1e-3,
              options=opts, keep_states=False, extra_transient_periods=0, settle=True,
              second_tolerance=False)
    rows = []
    for rpm in args.rpm:
        # a settled seed: one point without the exponent, then time both from its end
        seed = run_point(study.model, rpm, study.start(rpm), "up", 0, lyapunov=False,
                         **kw).u_end
        best = {True: np.inf, False: np.inf}
        rec = None
        for _ in range(args.repeats):
            for lyap in (False, True):
                t0 = time.perf_counter()
                r = run_point(study.model, rpm, seed, "up", 0, lyapunov=lyap, **kw)
                best[lyap] = min(best[lyap], time.perf_counter() - t0)
                if lyap:
                    rec = r
        rows.append({"rpm": rpm, "class": MOTION_LEGEND[int(rec.motion_class)],
                     "lyapunov": float(rec.lyapunov), "without_s": best[False],
                     "with_s": best[True], "ratio": best[True] / best[False]})
        print(f"{rpm:7.1f} rpm  {rows[-1]['class']:15s} without {best[False]:.3f} s  with "
              f"{best[True]:.3f} s  ratio {rows[-1]['ratio']:.2f} (target <= 1.5)")
    ratios = [r["ratio"] for r in rows]
    out = {"scene": Path(args.scene).name, "rtol": opts.rtol, "points": rows,
           "ratio_max": max(ratios), "ratio_mean": float(np.mean(ratios)), "target": 1.5,
           "load_average": list(os.getloadavg())}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(out, indent=1))
    print(f"ratio mean {out['ratio_mean']:.2f}, max {out['ratio_max']:.2f} -> {args.out}")


if __name__ == "__main__":
    main()
