"""The issue's gearbox performance targets, side by side in one run (``make bench-gearbox``).

1. Accuracy and baseline (benchmarks/bench_gearbox_integrator.py on the real two_stage
   model, ``--points`` speeds): the loosest rtol whose mesh-deformation extrema are within
   1e-3 of an rtol = 1e-10 reference, and the same points with scipy solve_ivp(RK45) and a
   dense numpy right-hand side at its own loosest such rtol -> per-point time ratio.
2. The two_stage sequential sweep: ``--speeds`` (700) speeds x 200 mesh periods (168
   transient + 32 recorded) from 1500 to 3000 rpm at that rtol, up, in 2 segments on 2
   local processes -> wall time (target <= 90 s).
3. One periodic orbit + monodromy (variational equations, 320 x 321) of the 160-DOF model
   over one mesh period -> wall time (target <= 1 s).

Writes benchmarks/results/bench_gearbox.json.  Needs the two_stage housing (built and cached
on first use, ~1 min).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path[:0] = [str(ROOT), str(HERE)]

SCENE = ROOT / "configs" / "two_stage.toml"


def two_stage_case(n: int = 700):
    """(ReducedModel, static state at the first speed, speeds) of configs/two_stage.toml."""
    from vibrogear.config import load_scene
    from vibrogear.models.gearbox import build_gearbox
    from vibrogear.solvers.static import static_equilibrium

    scene = load_scene(SCENE)
    gm = build_gearbox(scene)
    params = np.linspace(scene.sweep.omega_min, scene.sweep.omega_max, n)
    st = static_equilibrium(gm.reduced, params[0])
    return gm.reduced, st.u0, params


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speeds", type=int, default=700)
    ap.add_argument("--points", type=int, default=3, help="speeds timed against scipy")
    ap.add_argument("--rtol", type=float, default=None, help="skip part 1, use this rtol")
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/bench_gearbox.json"))
    a = ap.parse_args(argv)
    from vibrogear.solvers.integrate import IntegrationOptions, integrate
    from vibrogear.solvers.shooting import periodic_flow
    from vibrogear.solvers.sweep import sweep

    res: dict = {}
    if a.rtol is None:
        import bench_gearbox_integrator as big

        part1 = big.main(["--model", "bench_gearbox:two_stage_case", "--points", str(a.points),
                          "--repeats", "1", "--atol-scale", "1e-6",
                          "--out", str(ROOT / "benchmarks/results/bench_gearbox_ratio.json")])
        rtol = part1["ours"]["rtol"]
        res["baseline"] = {"rtol_ours": rtol, "rtol_scipy": part1["scipy_rk45_dense"]["rtol"],
                           "mean_s_ours": part1["ours"]["mean_time_s"],
                           "mean_s_scipy": part1["scipy_rk45_dense"]["mean_time_s"],
                           "ratio_wall": part1["speedup"], "ratio_cpu": part1["speedup_cpu"]}
    else:
        rtol = a.rtol
    model, u0, params = two_stage_case(a.speeds)
    opts = IntegrationOptions(rtol=rtol, atol=rtol * 1e-6, max_steps=50_000_000)
    integrate(model, params[0], u0, 0.0, model.excitation_period(params[0]), options=opts)
    t = time.perf_counter()
    sw = sweep(model, params, directions=("up",), transient_periods=168, record_periods=32,
               extra_transient_periods=0, options=opts, u0=u0, segments=2, workers=2)
    sweep_wall = time.perf_counter() - t
    res["sweep"] = {"speeds": int(params.size), "mesh_periods_per_speed": 200, "rtol": rtol,
                    "wall_s": sweep_wall, "target_s": 90.0, "steps": sw.steps,
                    "rhs_calls": sw.rhs_calls, "failed": int(np.sum(sw.status != 0)),
                    "us_per_rhs_per_core": 2e6 * sweep_wall / max(sw.rhs_calls, 1)}
    # orbit + monodromy at the top speed, from a settled state
    p = params[-1]
    T = model.excitation_period(p)
    warm = integrate(model, p, u0, 0.0, 100 * T, options=opts)
    best = np.inf
    for _ in range(3):
        t = time.perf_counter()
        fl = periodic_flow(model, p, warm.u_end, options=IntegrationOptions(rtol=1e-8, atol=1e-14))
        best = min(best, time.perf_counter() - t)
    res["orbit_monodromy"] = {"rpm": float(p), "states": model.n_states, "wall_s": best,
                              "target_s": 1.0, "monodromy_shape": list(fl.monodromy.shape)}
    print(f"sweep: {params.size} speeds x 200 mesh periods at rtol {rtol:g}: {sweep_wall:.1f} s "
          f"(target 90 s), {res['sweep']['us_per_rhs_per_core']:.1f} us per RHS per core")
    if "baseline" in res:
        b = res["baseline"]
        print(f"per point: ours {b['mean_s_ours']:.3f} s, scipy RK45 + dense RHS "
              f"{b['mean_s_scipy']:.3f} s: ratio {b['ratio_wall']:.1f} (target 30), "
              f"CPU ratio {b['ratio_cpu']:.1f}")
    print(f"orbit + monodromy ({model.n_states} states): {best:.3f} s (target 1 s)")
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(res, indent=1))
    return res


if __name__ == "__main__":
    main()
