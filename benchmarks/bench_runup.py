"""The 10 s run-up of the two-stage gearbox (configs/two_stage.toml [runup] with rate = 150
rpm/s, up only: 1500 -> 3000 rpm in 10 s; the demo runs 300 rpm/s both ways) through the whole analysis (chunked integration, envelopes, order tracks,
waterfall): wall time against the target of 30 s, steps per mesh period.

Baseline measured in the same run: one integrate() call over the same number of mesh
periods at the run's mean speed (2250 rpm), i.e. the cost of the motion without chunks; the
ratio is what the chunks of constant speed (restarts, repacking the speed-dependent
coupling) cost.  Also the solver alone at 4, 2 and 1 chunks per mesh period, and at 1 chunk
at the [integration] section's rtol (1e-6) instead of [runup] rtol.

Run: .venv/bin/python benchmarks/bench_runup.py   (never run by the tests; ~3 min)
Writes benchmarks/results/bench_runup.json.
"""
from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from vibrogear.analyses.runup import runup  # noqa: E402
from vibrogear.analyses.study import build_study, integration_options  # noqa: E402
from vibrogear.config import load_scene  # noqa: E402
from vibrogear.pipeline.outcome import RunContext  # noqa: E402
from vibrogear.solvers.integrator.integrate import integrate  # noqa: E402
from vibrogear.solvers.sequential.ramp import SpeedProfile, ramp  # noqa: E402

TARGET_S = 30.0


def main() -> dict:
    scene = load_scene(ROOT / "configs" / "two_stage.toml",
                       ("runup.rate=150.0", 'runup.directions=["up"]'))
    cfg = scene.runup
    study = build_study(scene)
    model = study.model
    opts = integration_options(scene, record=True, section=scene.runup)
    times, rpm = cfg.profile()
    prof = SpeedProfile.of(times, rpm, study.time_unit_s)
    periods = float(np.trapz(prof.params, prof.times) * model.omega_per_param / (2 * np.pi))
    u0 = study.start(rpm[0])
    # warm-up (JIT / cache load)
    integrate(model, rpm[0], u0, 0.0, 5 * model.excitation_period(rpm[0]), options=opts)

    t0 = time.perf_counter()
    out = runup.run(study, scene, RunContext(out=Path("/tmp"), quiet=True))
    wall_analysis = time.perf_counter() - t0
    r = out.result.runs[0].ramp

    mean = 0.5 * (rpm[0] + rpm[-1])
    t0 = time.perf_counter()
    base = integrate(model, mean, r.u_end, 0.0, periods * model.excitation_period(mean),
                     options=opts)
    wall_base = time.perf_counter() - t0

    solver = {}
    for cpp in (4, 2, 1):
        t0 = time.perf_counter()
        rr = ramp(model, prof, u0, options=opts, chunks_per_period=cpp,
                  samples_per_period=cfg.samples_per_period, settle_periods=cfg.settle_periods,
                  rows=study.contact_groups["mesh"])
        solver[str(cpp)] = {"wall_s": time.perf_counter() - t0, "steps": rr.steps,
                            "steps_per_mesh_period": (rr.steps - rr.settle_steps) / rr.periods,
                            "chunks": rr.chunks}
    t0 = time.perf_counter()
    fine = ramp(model, prof, u0, options=scene.integration, chunks_per_period=1,
                samples_per_period=cfg.samples_per_period, settle_periods=cfg.settle_periods,
                rows=study.contact_groups["mesh"])
    solver["1 at [integration] rtol"] = {
        "rtol": scene.integration.rtol, "wall_s": time.perf_counter() - t0, "steps": fine.steps,
        "steps_per_mesh_period": (fine.steps - fine.settle_steps) / fine.periods}
    res = {
        "benchmark": "two_stage [runup]: 10 s run-up 1500 -> 3000 rpm at 150 rpm/s, "
                     f"settle {cfg.settle_periods} mesh periods, {cfg.chunks_per_period} "
                     f"chunks and {cfg.samples_per_period} samples per mesh period",
        "machine": f"{platform.node()} ({os.cpu_count()} cores, shared: timings +-30 %)",
        "load_average_1_5_15": list(os.getloadavg()),
        "rtol": opts.rtol, "atol": opts.atol, "m": model.n_modes,
        "mesh_periods": r.periods,
        "wall_s_analysis": wall_analysis, "wall_s_solver": r.wall_time,
        "target_s": TARGET_S, "ratio_to_target": wall_analysis / TARGET_S,
        "steps": r.steps, "steps_per_mesh_period": (r.steps - r.settle_steps) / r.periods,
        "chunks": r.chunks, "us_per_step": 1e6 * r.wall_time / max(r.steps, 1),
        "baseline_one_integration": {
            "what": f"one integrate() over {periods:.0f} mesh periods at {mean:g} rpm",
            "wall_s": wall_base, "steps": base.steps,
            "steps_per_mesh_period": base.steps / periods},
        "ratio_solver_to_baseline": r.wall_time / wall_base,
        "solver_by_chunks_per_period": solver,
    }
    print(f"run-up analysis {wall_analysis:.1f} s (target {TARGET_S:g} s; solver "
          f"{r.wall_time:.1f} s, {res['steps_per_mesh_period']:.0f} steps/mesh period); "
          f"one integration of as many periods {wall_base:.1f} s; "
          + ", ".join(f"{k} chunks/period {v['wall_s']:.1f} s" for k, v in solver.items()))
    path = ROOT / "benchmarks" / "results" / "bench_runup.json"
    path.write_text(json.dumps(res, indent=1))
    return res


if __name__ == "__main__":
    main()
