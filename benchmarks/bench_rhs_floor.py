"""Where the right-hand side's time goes: the two-stage gearbox RHS against its own
multiply-add floor, measured on this machine in one run (issue 11 item 4).

Three compiled drivers on the same states (sampled along 10 periods of the settled
rattle, m = 146, frequency level), best of ``--repeats`` CPU times per call:

* ``rhs``: the full right-hand side (:func:`vibrogear.solvers.integrator.kernels.accel`, through
  bench_gearbox's driver);
* ``linear_algebra``: its multiply-adds alone, through the same compiled helpers on the
  same arrays: the modal diagonal, the projections c_j . x, c_j . v of every row of G,
  the low-rank coupling P^T (Kc P x + Bc P v), and one axpy of G's row per contact in
  contact (what the force adds) -- no harmonics, contact law or mode logic;
* ``peak``: a contiguous fused multiply-add loop of the same number of multiply-adds
  (L1/L2-resident, vectorised): the rate this core reaches on such loops.

The difference rhs - linear_algebra is the contact law, harmonics and bookkeeping; the
ratio linear_algebra / peak what the short, ragged rows cost over one long row.  Then the
integrator's step over 50 periods at the sweep's rtol: us per step, and what it costs
besides its right-hand sides.
Writes benchmarks/results/bench_rhs_floor.json.  Never run by the tests.

Run:  .venv/bin/python benchmarks/bench_rhs_floor.py
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import numpy as np  # noqa: E402
from numba import njit  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path[:0] = [str(ROOT), str(HERE)]

from vibrogear.solvers.integrator.kernels import (FAST, contact_modes, project_coupling, row_axpy,
    rows_project, scatter_coupling)


@njit(cache=True, fastmath=FAST)
def _drive_linear(A, Y, modes, n_calls):
    n = Y.shape[1]
    m = n // 2
    nc, r = A.C.shape[0], A.P.shape[0]
    out = np.empty(n)
    Cx, Cv = np.empty(nc), np.empty(nc)
    tmp = np.empty(2 * r + 1)
    s = 0.0
    for k in range(n_calls):
        j = k % Y.shape[0]
        y = Y[j]
        x = y[:m]
        v = y[m:]
        acc = out[m:]
        for i in range(m):
            out[i] = v[i]
            acc[i] = A.F0[i] - A.damp[i] * v[i] - A.w2[i] * x[i]
        rows_project(A, 0, nc, x, v, Cx, Cv)
        if r > 0:
            project_coupling(A, x, v, tmp[:r], tmp[r:2 * r])
            scatter_coupling(A, A.WT, A.wlo, A.whi, A.Kc, A.Bc, A.klo, A.khi, A.blo, A.bhi,
                             tmp[:2 * r], acc, 1.0)
        md = modes[j]
        for c in range(nc):
            if md[c] != 0:
                row_axpy(A, c, 1e-9 * Cx[c], acc)
        s += out[m]
    return s


@njit(cache=True, fastmath=FAST)
def _drive_peak(a, b, reps):
    s = 0.0
    for _ in range(reps):
        t = 0.0
        for i in range(a.shape[0]):
            t += a[i] * b[i]
        s += t
        b[0] += 1e-300
    return s


def _best(fn, *args, repeats=5):
    fn(*args[:-1], 10)
    best = np.inf
    for _ in range(repeats):
        c = time.process_time()
        fn(*args)
        best = min(best, time.process_time() - c)
    return best


def _macs(A, modes) -> float:
    """Multiply-adds of one RHS's linear algebra (mean over the states' contact modes)."""
    gl = (A.ghi - A.glo).astype(float)
    nc = A.C.shape[0]
    proj = 2 * gl.sum()                                   # every row of G, x and v
    single = A.pg < 0
    scatter = float((A.whi - A.wlo).sum())                # every column of Pu^T [Kc | Bc]
    dense = float(sum((A.khi[k] - A.klo[k]) + (A.bhi[k] - A.blo[k]) + gl[A.pg[k]]
                      for k in A.pdk))
    force = float(np.mean([(gl[:nc] * (md != 0)).sum() for md in modes]))
    modal = 3 * A.w2.shape[0] + 2 * int(single.sum())
    return proj + scatter + dense + force + modal


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=100_000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/bench_rhs_floor.json"))
    a = ap.parse_args(argv)
    from bench_gearbox import _drive_rhs, two_stage_short_case
    from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
    from vibrogear.solvers.integrator.kernels import model_arrays

    model, u, params = two_stage_short_case(1)
    p = float(params[0])
    T = model.excitation_period(p)
    tr = integrate(model, p, u, 0.0, 10 * T, t_eval=np.linspace(0.0, 10 * T, 997),
                   options=IntegrationOptions(rtol=1e-6, atol=1e-12))
    A, Om = model_arrays(model, p)[:2]
    Y = np.ascontiguousarray(tr.u)
    m = model.n_modes
    modes = np.zeros((Y.shape[0], A.C.shape[0]), np.int64)
    for k in range(Y.shape[0]):
        contact_modes(A, 1e-3 * k, Om, Y[k, :m], modes[k])
    calls = a.calls
    rhs = _best(_drive_rhs, A, Om, Y, calls, repeats=a.repeats) / calls
    lin = _best(_drive_linear, A, Y, modes, calls, repeats=a.repeats) / calls
    macs = _macs(A, modes)
    nvec = int(round(macs))
    rng = np.random.default_rng(0)
    va, vb = rng.standard_normal(nvec), rng.standard_normal(nvec)
    peak = _best(_drive_peak, va, vb, calls, repeats=a.repeats) / calls
    # the integrator's step: 50 periods from the settled state at the sweep's rtol (the
    # accuracy rule's 3.9e-4 for an error of 1e-3), best of the repeats
    opts = IntegrationOptions(rtol=3.9e-4, atol=3.9e-10)
    integrate(model, p, u, 0.0, T, options=opts)
    wall, steps, nrhs = np.inf, 0, 0
    for _ in range(a.repeats):
        c = time.process_time()
        tr50 = integrate(model, p, u, 0.0, 50 * T, options=opts)
        wall = min(wall, time.process_time() - c)
        steps, nrhs = tr50.steps, tr50.rhs_calls
    us_step = 1e6 * wall / steps
    res = {
        "machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
        "model": f"two_stage m = {m}, {A.C.shape[0]} contacts, G {A.G.shape}, P {A.P.shape}",
        "speed_rpm": p, "multiply_adds_per_rhs": macs,
        "contacts_in_contact_mean": float(np.mean((modes != 0).sum(axis=1))),
        "us_rhs": 1e6 * rhs, "us_linear_algebra": 1e6 * lin, "us_peak_same_macs": 1e6 * peak,
        "us_contact_law_and_bookkeeping": 1e6 * (rhs - lin),
        "gmacs_linear_algebra": macs / lin / 1e9, "gmacs_peak": macs / peak / 1e9,
        "integration_rtol": opts.rtol, "steps_per_period": steps / 50.0,
        "rhs_per_step": nrhs / steps, "us_per_step": us_step,
        "us_per_step_besides_rhs": us_step - nrhs / steps * 1e6 * rhs,
    }
    print(f"{res['model']} at {p:g} rpm: {macs:.0f} multiply-adds per RHS "
          f"({res['contacts_in_contact_mean']:.1f} contacts in contact on average)")
    print(f"  RHS                         {res['us_rhs']:.2f} us")
    print(f"  its linear algebra alone    {res['us_linear_algebra']:.2f} us "
          f"({res['gmacs_linear_algebra']:.1f} G multiply-adds/s)")
    print(f"  contact law, harmonics, ... {res['us_contact_law_and_bookkeeping']:.2f} us")
    print(f"  one contiguous loop, same multiply-adds: {res['us_peak_same_macs']:.2f} us "
          f"({res['gmacs_peak']:.1f} G/s): the floor on this core")
    print(f"  integrator step at rtol {opts.rtol:g}: {us_step:.1f} us ({res['rhs_per_step']:.2f} "
          f"RHS per step, {res['steps_per_period']:.0f} steps per mesh period); besides the "
          f"RHS {res['us_per_step_besides_rhs']:.1f} us per step (stages, error norm, dense "
          f"output, event search, monitor)")
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(res, indent=2) + "\n")
    print(f"wrote {a.out}")
    return res


if __name__ == "__main__":
    main()
