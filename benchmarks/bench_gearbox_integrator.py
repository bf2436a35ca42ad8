"""Time per speed point on a gearbox-sized model: our compiled integrator against the scipy
baseline (benchmarks/scipy_baseline.py: dense numpy RHS + solve_ivp RK45), at equal accuracy.

Both run the same sequential sweep: each speed point integrates ``--periods`` excitation
periods from t = 0, seeded from the previous point's end state, and reports the extrema
of the monitored contact deformation over the last ``--record-periods`` periods (ours:
located on its dense output; scipy: dense output on a fine grid, refined by a parabola).
The accuracy of a run is the largest over the points of
max(|min - min_ref|, |max - max_ref|) / (max_ref - min_ref), with the reference the same
sweep by our integrator at rtol = ``--ref-rtol`` (1e-10).  For each method the loosest
rtol of a ladder (atol = rtol * ``--atol-scale``) with accuracy <= ``--target`` (1e-3) is
kept; its per-point wall times are reported (ours: best of ``--repeats`` sweeps, JIT-warm;
scipy: the ladder's own run).  The scipy baseline has no events: RK45 steps across the
contact switches and pays for them with small steps; the comparison is at equal error.

Model: ``--model module:function`` returning (ReducedModel, u0, params) (module looked up
on sys.path, benchmarks/ and the repository root included); default the synthetic
gearbox, benchmarks/synthetic_gearbox.py:gearbox_case (160 modes, 41 contacts, time in
ms).  ``--points N`` speeds are taken evenly from ``params`` (ends included).

Run:  .venv/bin/python benchmarks/bench_gearbox_integrator.py [--points 3]
Writes benchmarks/results/bench_gearbox_integrator.json.  Never run by the tests.
"""
from __future__ import annotations

import argparse
import importlib
import json
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")   # single thread, like the compiled loop
import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path[:0] = [str(ROOT), str(HERE)]

from bench_integrator import code_version  # noqa: E402
from scipy_baseline import dense_rhs, solve_points_scipy  # noqa: E402

from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate  # noqa: E402

LADDER = (1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7)
DOPRI5_STABILITY = 3.3   # |h lambda| on the imaginary axis inside DOPRI5's stability region


def load_case(spec: str):
    mod, _, fn = spec.partition(":")
    if not fn:
        raise SystemExit("--model must be module:function")
    model, u0, params = getattr(importlib.import_module(mod), fn)()
    return model, np.asarray(u0, dtype=float), np.atleast_1d(np.asarray(params, dtype=float))


def pick(params: np.ndarray, n: int) -> np.ndarray:
    if n >= params.size:
        return params
    return params[np.unique(np.round(np.linspace(0, params.size - 1, n)).astype(int))]


def run_ours(model, params, u0, a, rtol):
    """Our sequential sweep: one dict per point."""
    opts = IntegrationOptions(rtol=rtol, atol=rtol * a.atol_scale, max_steps=50_000_000)
    seed, out = u0, []
    for p in params:
        T = model.excitation_period(p)
        wall, cpu = time.perf_counter(), time.process_time()
        tr = integrate(model, p, seed, 0.0, a.periods * T, options=opts,
                       record_from=(a.periods - a.record_periods) * T)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        ok = tr.status == 0
        if ok:
            seed = tr.u_end
        out.append(dict(param=float(p), time_s=wall, cpu_s=cpu, ok=ok, message=tr.message,
                        steps=tr.steps, rejected=tr.rejected, rhs_calls=tr.rhs_calls,
                        events=tr.events, monitor_losses=tr.monitor_losses,
                        qmin=tr.monitor_min if ok else np.nan,
                        qmax=tr.monitor_max if ok else np.nan))
    return out


def run_scipy(model, params, u0, a, rtol):
    pts = solve_points_scipy(model, params, u0, periods=a.periods, rtol=rtol,
                             atol=rtol * a.atol_scale,
                             record_from=a.periods - a.record_periods)
    return [dict(param=p.param, time_s=p.wall_time, cpu_s=p.cpu_time,
                 solve_time_s=p.solve_time, ok=p.ok, message=p.message, steps=p.steps,
                 rhs_calls=p.rhs_calls,
                 qmin=p.monitor_min, qmax=p.monitor_max) for p in pts]


def errors(run, ref):
    out = []
    for r, q in zip(run, ref):
        span = q["qmax"] - q["qmin"]
        e = max(abs(r["qmin"] - q["qmin"]), abs(r["qmax"] - q["qmax"])) / span
        out.append(float(e) if np.isfinite(e) else np.inf)
    return out


def ladder(name, runner, ref, a):
    """Loosest rtol of LADDER whose sweep meets the target at every point; also the
    history of every rung (per-point errors, times, rhs calls)."""
    history = []
    for rtol in LADDER:
        run = runner(rtol)
        err = errors(run, ref)
        history.append(dict(rtol=rtol, err=err, time_s=[r["time_s"] for r in run],
                            rhs_calls=[r["rhs_calls"] for r in run],
                            steps=[r["steps"] for r in run]))
        print(f"  {name:5s} rtol={rtol:7.1e}: max err {max(err):.2e}  "
              f"{sum(r['time_s'] for r in run):8.3f} s  "
              f"{sum(r['steps'] for r in run):9d} steps  {sum(r['rhs_calls'] for r in run):9d} rhs",
              flush=True)
        if max(err) <= a.target:
            for r, e in zip(run, err):
                r["err"] = e
            return rtol, run, history
    raise SystemExit(f"{name}: no rtol in the ladder reaches error <= {a.target:g}")


def per_point_loosest(history, target):
    """For each point: the loosest rung meeting the target there alone, and its time."""
    out = []
    for i in range(len(history[0]["err"])):
        h = next(h for h in history if h["err"][i] <= target)
        out.append(dict(rtol=h["rtol"], time_s=h["time_s"][i], rhs_calls=h["rhs_calls"][i]))
    return out


def finite_json(x):
    """Non-finite floats (errors of failed runs) as null: strict JSON."""
    if isinstance(x, dict):
        return {k: finite_json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [finite_json(v) for v in x]
    if isinstance(x, float) and not np.isfinite(x):
        return None
    return x


def stability_step(model, param, u0) -> float:
    """DOPRI5's explicit stability bound on h from the spectral radius of the Jacobian at u0
    (linear part plus contact tangents; central differences of the dense RHS)."""
    f = dense_rhs(model, param)
    n = u0.size
    J = np.empty((n, n))
    for i in range(n):
        du = np.zeros(n)
        du[i] = 1e-6 * max(1.0, abs(u0[i]))
        J[:, i] = (f(0.0, u0 + du) - f(0.0, u0 - du)) / (2 * du[i])
    return DOPRI5_STABILITY / float(np.max(np.abs(np.linalg.eigvals(J))))


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="synthetic_gearbox:gearbox_case")
    ap.add_argument("--points", type=int, default=3)
    ap.add_argument("--periods", type=int, default=200)
    ap.add_argument("--record-periods", type=int, default=20)
    ap.add_argument("--ref-rtol", type=float, default=1e-10)
    ap.add_argument("--target", type=float, default=1e-3)
    ap.add_argument("--atol-scale", type=float, default=1e-3)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/bench_gearbox_integrator.json"))
    a = ap.parse_args(argv)
    version = code_version()
    load_start = os.getloadavg()
    model, u0, all_params = load_case(a.model)
    params = pick(all_params, a.points)
    T0 = model.excitation_period(params[0])
    t = time.perf_counter()
    integrate(model, params[0], u0, 0.0, T0)
    first_call = time.perf_counter() - t
    print(f"model {model.name}: {model.n_modes} modes, {model.contacts.count} contacts, "
          f"rank {model.coupling.P.shape[0]} coupling; {model.param_name} = "
          f"{', '.join(f'{p:g}' for p in params)}; {a.periods} periods per point "
          f"(first call incl. JIT/cache load: {first_call:.2f} s)", flush=True)
    t = time.perf_counter()
    ref = run_ours(model, params, u0, a, a.ref_rtol)
    ref_wall = time.perf_counter() - t
    if not all(r["ok"] for r in ref):
        raise SystemExit(f"reference failed: {[r['message'] for r in ref]}")
    print(f"reference rtol={a.ref_rtol:g}: {ref_wall:.1f} s, steps {[r['steps'] for r in ref]}")
    rtol_o, ours, hist_o = ladder("ours", lambda tol: run_ours(model, params, u0, a, tol), ref, a)
    for _ in range(a.repeats - 1):
        for r, again in zip(ours, run_ours(model, params, u0, a, rtol_o)):
            r["time_s"] = min(r["time_s"], again["time_s"])
            r["cpu_s"] = min(r["cpu_s"], again["cpu_s"])
    rtol_s, sp, hist_s = ladder("scipy", lambda tol: run_scipy(model, params, u0, a, tol), ref, a)
    loose_o, loose_s = per_point_loosest(hist_o, a.target), per_point_loosest(hist_s, a.target)

    print(f"\n{model.param_name:>8s} | {'ours s':>8s} {'scipy s':>8s} {'ratio':>6s} | "
          f"{'ours rhs':>9s} {'scipy rhs':>9s} | {'ours err':>8s} {'scipy err':>9s} | "
          f"{'steps/T':>7s} {'events/T':>8s} | {'cpu ratio':>9s}")
    for o, s in zip(ours, sp):
        print(f"{o['param']:8.1f} | {o['time_s']:8.3f} {s['time_s']:8.3f} "
              f"{s['time_s'] / o['time_s']:6.1f} | {o['rhs_calls']:9d} {s['rhs_calls']:9d} | "
              f"{o['err']:8.1e} {s['err']:9.1e} | {o['steps'] / a.periods:7.1f} "
              f"{o['events'] / a.periods:8.2f} | {s['cpu_s'] / o['cpu_s']:9.1f}")
    t_o = float(np.mean([o["time_s"] for o in ours]))
    t_s = float(np.mean([s["time_s"] for s in sp]))
    c_o = float(np.mean([o["cpu_s"] for o in ours]))
    c_s = float(np.mean([s["cpu_s"] for s in sp]))
    print(f"{'mean':>8s} | {t_o:8.3f} {t_s:8.3f} {t_s / t_o:6.1f} |   (ours rtol {rtol_o:g}, "
          f"scipy rtol {rtol_s:g}, atol = rtol * {a.atol_scale:g}); CPU time: {c_o:.3f} s vs "
          f"{c_s:.3f} s, ratio {c_s / c_o:.1f}")
    print("one rtol per sweep is what a user can choose; with the loosest rtol meeting the "
          "target at each point alone (known only from the reference; one run each):")
    for o, s in zip(loose_o, loose_s):
        print(f"  {o['rtol']:7.0e} {o['time_s']:8.3f} s | scipy {s['rtol']:7.0e} "
              f"{s['time_s']:8.3f} s | ratio {s['time_s'] / o['time_s']:6.1f}")
    t_lo = float(np.mean([o["time_s"] for o in loose_o]))
    t_ls = float(np.mean([s["time_s"] for s in loose_s]))
    print(f"  mean {t_lo:.3f} s vs {t_ls:.3f} s: ratio {t_ls / t_lo:.1f}")

    # step-count diagnostics: accuracy- or stability-limited?
    h_stab = stability_step(model, params[0], u0)
    diag = []
    for o in ours:
        span = a.periods * model.excitation_period(o["param"])
        h_mean = span / o["steps"]
        diag.append(dict(param=o["param"], h_mean=h_mean, h_over_stability=h_mean / h_stab,
                         rejected_fraction=o["rejected"] / o["steps"],
                         rhs_per_step=o["rhs_calls"] / o["steps"],
                         us_per_rhs=1e6 * o["time_s"] / o["rhs_calls"]))
        print(f"ours at {o['param']:g}: mean step {h_mean:.3g} = {h_mean / h_stab:.2f} x the "
              f"explicit stability bound {h_stab:.3g}; {o['rejected']} rejected; "
              f"{o['events']} events ({o['monitor_losses']} monitored losses in the record "
              f"window); {diag[-1]['rhs_per_step']:.2f} rhs/step, "
              f"{diag[-1]['us_per_rhs']:.1f} us per rhs (loop included)")
    for s in sp:
        us = 1e6 * s["solve_time_s"] / s["rhs_calls"]
        print(f"scipy at {s['param']:g}: {s['steps']} steps, {us:.1f} us per rhs (solve_ivp), "
              f"extrema extraction {s['time_s'] - s['solve_time_s']:.3f} s")
    res = dict(model=dict(name=model.name, spec=a.model, modes=model.n_modes,
                          contacts=model.contacts.count, rank=int(model.coupling.P.shape[0]),
                          param_name=model.param_name, params=params.tolist()),
               periods=a.periods, record_periods=a.record_periods, target_error=a.target,
               atol_over_rtol=a.atol_scale,
               reference=dict(rtol=a.ref_rtol, time_s=ref_wall, points=ref),
               first_call_s=first_call, stability_step=h_stab,
               ours=dict(rtol=rtol_o, points=ours, diagnostics=diag, mean_time_s=t_o,
                         mean_cpu_s=c_o,
                         repeats=a.repeats, ladder=hist_o, per_point_loosest=loose_o),
               scipy_rk45_dense=dict(rtol=rtol_s, points=sp, mean_time_s=t_s, mean_cpu_s=c_s,
                                     ladder=hist_s,
                                     per_point_loosest=loose_s),
               speedup=t_s / t_o, speedup_cpu=c_s / c_o, speedup_per_point_loosest=t_ls / t_lo,
               blas_threads=os.environ.get("OPENBLAS_NUM_THREADS"), code=version,
               machine=dict(python=platform.python_version(), node=platform.node(),
                            processor=platform.processor() or platform.machine(),
                            cpus=os.cpu_count(), loadavg_start=load_start,
                            loadavg_end=os.getloadavg()))
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(finite_json(res), indent=2) + "\n")
    print(f"wrote {out}")
    return res


if __name__ == "__main__":
    main()
