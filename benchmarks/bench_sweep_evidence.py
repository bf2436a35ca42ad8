"""What a sweep point's evidence costs against the bare integration of the same periods
(issue target: <= 1.5x), on the demo scene's [sweep] (configs/two_stage.toml).

For ``--points`` consecutive speeds of the scene's grid (upward, each seeded by the last,
as in the sweep), in this process:

* the point as the sweep runs it (:func:`~vibrogear.solvers.sequential.sweep_point.run_point`),
  its wall time split by phase (transient, record, Lyapunov, orbit check, metrics, second
  tolerance; ``PointRecord.timings``) and the rest (per-point overhead);
* the bare integration of the same periods (``transient_used + record_periods``) from the
  same seed: one integrator call, no dense output.

Writes benchmarks/results/bench_sweep_evidence.json (sums, the ratio, the split).
``--set key=value`` overrides the scene as on the command line.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import numpy as np  # noqa: E402

from vibrogear.analyses.study import build_study, integration_options  # noqa: E402
from vibrogear.config import load_scene  # noqa: E402
from vibrogear.config.options import SweepOptions  # noqa: E402
from vibrogear.solvers.integrator.integrate import integrate  # noqa: E402
from vibrogear.solvers.sequential.sweep_point import run_point  # noqa: E402

PHASES = ("transient", "record", "lyapunov", "orbit_check", "metrics", "second_tolerance")


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default=str(HERE.parent / "configs" / "two_stage.toml"))
    ap.add_argument("--points", type=int, default=16)
    ap.add_argument("--set", action="append", default=[], dest="overrides")
    ap.add_argument("--out", default=str(HERE / "results" / "bench_sweep_evidence.json"))
    a = ap.parse_args(argv)
    scene = load_scene(a.scene, overrides=a.overrides)
    study = build_study(scene)
    model, cfg = study.model, scene.sweep
    opts = integration_options(scene, record=True, period_tol=cfg.period_tol, study=study)
    settings = SweepOptions.of(cfg)
    params = np.linspace(cfg.param_min, cfg.param_max, cfg.n_points)[: a.points]
    seed = study.start(params[0])
    run_point(model, float(params[0]), seed, "up", 0, settings, options=opts)   # compile
    split = {k: 0.0 for k in PHASES}
    point_wall = bare_wall = 0.0
    periods = point_calls = bare_calls = 0
    rows = []
    cpu0 = time.process_time()
    for i, p in enumerate(params):
        t = time.perf_counter()
        rec = run_point(model, float(p), seed, "up", i, settings, options=opts)
        w = time.perf_counter() - t
        k = rec.transient_used + cfg.record_periods
        T = model.excitation_period(float(p))
        t = time.perf_counter()
        bare = integrate(model, float(p), seed, 0.0, k * T, options=opts)
        b = time.perf_counter() - t
        point_calls += rec.rhs_calls
        bare_calls += bare.rhs_calls
        point_wall += w
        bare_wall += b
        periods += k
        for ph, v in getattr(rec, "timings", {}).items():   # (absent before 2026-11-25)
            split[ph] += v
        rows.append({"param": float(p), "wall_s": w, "bare_s": b, "periods": k,
                     "class": int(rec.motion_class), "settled_by": rec.settled_by})
        seed = rec.u_end
    cpu = time.process_time() - cpu0
    split["overhead"] = point_wall - sum(split.values())
    out = {
        "scene": a.scene, "overrides": a.overrides, "points": len(params),
        "rtol": opts.rtol, "atol": opts.atol,
        "point_wall_s": point_wall, "bare_integration_s": bare_wall, "cpu_s": cpu,
        "ratio": point_wall / bare_wall,
        # the same ratio in right-hand-side calls: the integration work alone, independent
        # of the machine's load (what the wall ratio adds to it is per-call and Python cost)
        "rhs_calls_point": point_calls, "rhs_calls_bare": bare_calls,
        "rhs_ratio": point_calls / max(bare_calls, 1), "mean_transient_periods": periods / len(params)
        - cfg.record_periods, "target_ratio": 1.5,
        "periods_bare": periods,
        "split_s": split, "split_ratio": {k: v / bare_wall for k, v in split.items()},
        "load_average": os.getloadavg(), "rows": rows,
    }
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(out, indent=1))
    print(json.dumps({k: out[k] for k in ("points", "rtol", "point_wall_s",
                                            "bare_integration_s", "ratio", "rhs_ratio",
                                            "split_ratio")},
                     indent=1))
    return out


if __name__ == "__main__":
    main()
