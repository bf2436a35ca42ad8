"""Two-stage gearbox continuation (configs/two_stage.toml, 1500-3000 rpm, start at 3000 rpm,
Floquet multipliers and LP / PD / NS location included; target: the whole branch <= 120 s
on 2 cores).  In one run: the first ``N_RATIO`` points with the tangent's columns
integrated in this process alone and split over two processes (solvers/integrator/split_flow.py),
their ratio, then the whole branch as the scene runs it (split, quasi-Newton corrector).
``--exact``: also the first points with the exact Newton corrector (every iterate an orbit
with the variational equations) against the quasi-Newton corrector (solvers/periodic/corrector.py).

Run: .venv/bin/python benchmarks/bench_two_stage_continuation.py [--exact]   (never run by
the tests)
Writes benchmarks/results/bench_two_stage_continuation.json.
"""
from __future__ import annotations

import dataclasses
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from vibrogear.solvers.periodic.starting_orbit import starting_orbit  # noqa: E402
from vibrogear.analyses.study import build_study, integration_options  # noqa: E402
from vibrogear.config.scene import load_scene  # noqa: E402
from vibrogear.solvers.periodic.continuation import (PeriodicOrbitProblem, PseudoArclength,
    continuation)

TARGET_S = 120.0
N_RATIO = 40


def run(study, scene, u0, n, guess, *, quasi_newton: bool, max_points: int,
        split: bool = True) -> dict:
    cfg = scene.continuation
    options = dataclasses.replace(cfg.options(), max_points=max_points)
    scale = (options.param_max - options.param_min) / float(np.linalg.norm(guess))
    # the analysis's integrator options ([continuation] rtol; scene.integration is the
    # scene default, rtol 1e-9 with atol 1e-11: a tighter error than the analysis runs at)
    opts = integration_options(scene, section=scene.continuation, study=study)
    method = PseudoArclength(integration=opts, tol=scene.shooting.tol,
                             param_scale=scale, locate_tol=2e-4, quasi_newton=quasi_newton,
                             split_columns=split)
    t0 = time.perf_counter()
    res = continuation(PeriodicOrbitProblem(study.model, u0, options.param_max, n_periods=n,
                                            direction=-1), method, options)
    wall = time.perf_counter() - t0
    b = res.branches[0]
    return {"quasi_newton": quasi_newton, "split_columns": res.counters["split_columns"],
            "wall_s": wall, "points": len(b.points),
            "rpm_reached": float(min(p.param for p in b.points)),
            "flows_with_monodromy": res.counters["flows"],
            "flows_without": res.counters.get("plain_flows", 0), "status": b.message,
            "special_points": [(p.label, round(p.param, 1)) for p in b.points if p.label]}


def main() -> dict:
    scene = load_scene(ROOT / "configs" / "two_stage.toml")
    study = build_study(scene)
    cfg = scene.continuation
    t0 = time.perf_counter()
    u0, n, guess, how = starting_orbit(study.model, cfg.rpm_max, study.start(cfg.rpm_max),
                                       transient_periods=cfg.transient_periods,
                                       options=integration_options(
                                           scene, section=cfg, study=study),
                                       tol=scene.shooting.tol,
                                       max_iter=3 * cfg.max_corrector_iter)
    start_s = time.perf_counter() - t0
    one = run(study, scene, u0, n, guess, quasi_newton=True, max_points=N_RATIO, split=False)
    two = run(study, scene, u0, n, guess, quasi_newton=True, max_points=N_RATIO)
    first = {"one_process": one, "split": two,
             "ratio_one_process_over_split": one["wall_s"] / two["wall_s"]}
    print(f"first {N_RATIO} points: one process {one['wall_s']:.1f} s, tangent split over two "
          f"{two['wall_s']:.1f} s ({two['flows_with_monodromy']} monodromies + "
          f"{two['flows_without']} orbits without, to {two['rpm_reached']:.0f} rpm): ratio "
          f"{first['ratio_one_process_over_split']:.2f}")
    if "--exact" in sys.argv[1:]:
        exact = run(study, scene, u0, n, guess, quasi_newton=False, max_points=N_RATIO)
        first.update(exact=exact, ratio_exact_over_quasi_newton=exact["wall_s"] / two["wall_s"])
        print(f"  exact corrector {exact['wall_s']:.1f} s: ratio "
              f"{first['ratio_exact_over_quasi_newton']:.2f}")
    whole = run(study, scene, u0, n, guess, quasi_newton=True, max_points=cfg.max_points)
    res = {"benchmark": "two_stage continuation from 3000 rpm", "start_s": start_s,
           "start": how, "first_points": first, "whole_branch": whole, "target_s": TARGET_S,
           "whole_incl_start_s": start_s + whole["wall_s"]}
    print(f"whole branch: {whole['points']} points to {whole['rpm_reached']:.0f} rpm, "
          f"{start_s + whole['wall_s']:.1f} s with the start (target <= {TARGET_S:.0f} s: "
          f"{'met' if start_s + whole['wall_s'] <= TARGET_S else 'NOT met'}); {whole['status']}")
    out = ROOT / "benchmarks" / "results" / "bench_two_stage_continuation.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(res, indent=2))
    return res


if __name__ == "__main__":
    main()
