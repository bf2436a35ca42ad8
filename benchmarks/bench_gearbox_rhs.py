"""Right-hand side and integration cost on the real two-stage gearbox reduced model.

Builds the reduced model of ``--scene`` (default configs/two_stage.toml) and its static
equilibrium u0, or loads ``(model, u0)`` from ``--pickle``, and prints

* us per call of the compiled ``kernels.accel``, called from a compiled driver on states
  sampled along a trajectory (best of ``--repeats``, CPU time of this process);
* the integration of ``--periods`` excitation periods from u0 at each ``--rtol``
  (atol ``--atol``): wall time (best of ``--repeats``), steps, RHS calls, us per RHS.

Never run by the tests.

Run:  .venv/bin/python benchmarks/bench_gearbox_rhs.py [--scene FILE | --pickle PATH] [--param 2400]
"""
from __future__ import annotations

import argparse
import os
import pickle
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import numpy as np  # noqa: E402
from numba import njit  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate  # noqa: E402
from vibrogear.solvers.integrator.kernels import accel, contact_modes, model_arrays  # noqa: E402


@njit(cache=True)
def _drive(A, Om, Y, n_calls):
    """n_calls of accel, cycling through the states Y (rows)."""
    n = Y.shape[1]
    m = n // 2
    nc = A.C.shape[0]
    H = A.Fc.shape[0]
    r = A.P.shape[0]
    cs = np.empty(H)
    sn = np.empty(H)
    out = np.empty(n)
    Cx = np.empty(nc)
    Cv = np.empty(nc)
    kd = np.empty(nc)
    cd = np.empty(nc)
    tmp = np.empty(2 * r + 1)
    mode = np.zeros(nc, np.int64)
    contact_modes(A, 0.0, Om, Y[0, :m], mode)
    s = 0.0
    for k in range(n_calls):
        accel(1e-3 * k, Y[k % Y.shape[0]], mode, A, Om, cs, sn, out, Cx, Cv, kd, cd, tmp)
        s += out[m]
    return s


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default=str(Path(__file__).resolve().parents[1] / "configs"
                                           / "two_stage.toml"))
    ap.add_argument("--pickle", default=None, help="(model, u0) pickled, instead of --scene")
    ap.add_argument("--param", type=float, default=2400.0)
    ap.add_argument("--periods", type=float, default=200.0)
    ap.add_argument("--rtol", type=float, nargs="+", default=[1e-5, 1e-6])
    ap.add_argument("--atol", type=float, default=1e-12)
    ap.add_argument("--calls", type=int, default=50_000)
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    if a.pickle:
        with open(a.pickle, "rb") as fh:
            model, u0 = pickle.load(fh)
    else:
        from vibrogear.analyses.study import build_study
        from vibrogear.config import load_scene
        study = build_study(load_scene(a.scene))
        model, u0 = study.model, study.start(a.param)
    u0 = np.ascontiguousarray(u0, dtype=float)
    p = a.param
    T = model.excitation_period(p)
    A, Om, *_ = model_arrays(model, p)
    print(f"model {model.name}: m = {model.n_modes}, P {A.P.shape}, {model.contacts.count} contacts, "
          f"H = {model.n_harmonics}; param {p:g}, period {T:.6g}")

    # states along a short trajectory (realistic contact activity)
    opts = IntegrationOptions(rtol=1e-6, atol=a.atol)
    tr = integrate(model, p, u0, 0.0, 10 * T, t_eval=np.linspace(0.0, 10 * T, 997), options=opts)
    Y = np.ascontiguousarray(tr.u)
    _drive(A, Om, Y, 10)
    best = np.inf
    for _ in range(a.repeats):
        c0 = time.process_time()
        _drive(A, Om, Y, a.calls)
        best = min(best, (time.process_time() - c0) / a.calls)
    print(f"accel: {best * 1e6:.2f} us per call (best of {a.repeats} x {a.calls} calls)")

    for rtol in a.rtol:
        opts = IntegrationOptions(rtol=rtol, atol=a.atol)
        integrate(model, p, u0, 0.0, T, options=opts)        # JIT warm
        wall = np.inf
        for _ in range(a.repeats):
            t0 = time.perf_counter()
            tr = integrate(model, p, u0, 0.0, a.periods * T, options=opts)
            wall = min(wall, time.perf_counter() - t0)
        print(f"{a.periods:g} periods, rtol {rtol:g}, atol {a.atol:g}: {wall:.3f} s "
              f"(best of {a.repeats}), {tr.steps} steps ({tr.rejected} rejected), "
              f"{tr.rhs_calls} RHS, {tr.events} events, {wall / tr.rhs_calls * 1e6:.2f} us per RHS, "
              f"status {tr.message}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
