"""Integrator throughput: compiled DOPRI5 (modal diagonal + low-rank RHS, located contact
events) against scipy ``solve_ivp(RK45)`` with a dense numpy right-hand side, at equal error.

Model: a synthetic 160-mode reduced gearbox (modal frequencies 50 Hz - 10 kHz log-spaced,
1-2 % modal damping, a rank-12 linear coupling), one gear mesh with backlash (dead zone
gap_hi = 0, gap_lo = -backlash, 1e8 N/m, mesh-stiffness modulation and a 3-harmonic
kinematic error, 800 Hz mesh frequency) and 4 bearings x 10 Hertzian one-sided contacts
(exponent 1.5, 2 um clearance), statically preloaded so that some rolling elements stay
closed and others open.  SI units with unit modal masses.

Error: max |delta_mesh - delta_ref| over the record window (the last 20 mesh periods,
sampled 40 times per period) divided by the range of delta_ref there; the reference is
our integrator at rtol = 1e-12.  For each method the loosest tolerance in a ladder with
error <= 1e-3 is kept and timed there.

Run:  .venv/bin/python benchmarks/bench_integrator.py [--periods 200] [--scipy-periods 20]
(about 3 minutes; most of it is the rtol = 1e-12 reference).
Writes benchmarks/results/bench_integrator.json.  Never run by the tests.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")   # single thread, like the compiled loop
import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402
from scipy.optimize import root  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel  # noqa: E402
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate  # noqa: E402

F_MESH = 800.0            # Hz
TOL_LADDER = (1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 3e-8, 1e-8)
TARGET_ERR = 1e-3
ATOL_SCALE = 1e-4         # atol = rtol * ATOL_SCALE (modal displacements ~ 1e-7 .. 1e-2 m)


def build_model(seed: int = 7) -> ReducedModel:
    rng = np.random.default_rng(seed)
    m, H, r = 160, 3, 12
    f = np.logspace(np.log10(50.0), np.log10(10e3), m)
    w = 2 * np.pi * f
    zeta = rng.uniform(0.01, 0.02, m)
    weight = 0.3 / np.sqrt(1.0 + np.arange(m) / 20.0)    # low modes participate more

    def direction():
        return rng.normal(size=m) * weight

    P = rng.normal(size=(r, m)) * weight
    Q = rng.normal(size=(r, r))
    Kc0 = 1e6 * (Q @ Q.T / r + np.eye(r))                 # SPD: stiffens, never destabilises
    z = np.zeros((r, r))
    coupling = LinearCoupling(P, Kc0, z, z.copy(), z.copy())

    backlash, k_mesh, F_mesh = 100e-6, 1e8, 2000.0
    c_mesh = direction()
    dirs, k_hi, k_lo, g_hi, g_lo, expo, cdamp = [c_mesh], [k_mesh], [k_mesh], [0.0], \
        [-backlash], [1.0], [2 * 0.05 * np.sqrt(k_mesh * 1.0)]
    F0 = F_mesh * c_mesh
    n_b, n_el, k_hertz, clear = 4, 10, 1e10, 2e-6
    for b in range(n_b):
        cx, cy = direction(), direction()
        phi = 2 * np.pi * np.arange(n_el) / n_el + rng.uniform(0, 2 * np.pi / n_el)
        for p in phi:
            dirs.append(np.cos(p) * cx + np.sin(p) * cy)
        k_hi += [k_hertz] * n_el
        k_lo += [k_hertz] * n_el
        g_hi += [clear] * n_el
        g_lo += [-np.inf] * n_el
        expo += [1.5] * n_el
        cdamp += [0.0] * n_el
        psi = rng.uniform(0, 2 * np.pi)
        F0 = F0 + rng.uniform(1000.0, 3000.0) * (np.cos(psi) * cx + np.sin(psi) * cy)
    nc = len(dirs)
    kmc = np.zeros((nc, H))
    kmc[0, :2] = [0.10, 0.03]
    ec = np.zeros((nc, H))
    es = np.zeros((nc, H))
    ec[0] = [10e-6, 3e-6, 1e-6]
    es[0] = [0.0, 1.5e-6, 0.0]
    contacts = ContactSet(np.array(dirs), np.array(k_hi), np.array(k_lo), np.array(g_hi),
                          np.array(g_lo), np.array(expo), np.array(cdamp), kmc,
                          np.zeros((nc, H)), ec, es,
                          names=("mesh",) + tuple(f"b{i // n_el}e{i % n_el}"
                                                  for i in range(n_b * n_el)))
    forcing = Forcing(F0=F0, Fc=np.zeros((H, m)), Fs=np.zeros((H, m)))
    return ReducedModel(omega2=w ** 2, damping=2 * zeta * w, coupling=coupling,
                        forcing=forcing, contacts=contacts, omega_per_param=2 * np.pi,
                        monitor=0, name="synthetic_gearbox_160", param_name="f_mesh_hz")


# ---------------------------------------------------------------- dense numpy baseline

class DenseRHS:
    """u' = A u + forcing - [0; C^T f(C x - e(t), C v - e'(t))] with a dense 2m x 2m A."""

    def __init__(self, model: ReducedModel, param: float):
        m = model.n_modes
        cp, ct, fo = model.coupling, model.contacts, model.forcing
        K = np.diag(model.omega2) + cp.P.T @ cp.Kc0 @ cp.P
        B = np.diag(model.damping) + cp.P.T @ cp.Bc0 @ cp.P
        self.A = np.block([[np.zeros((m, m)), np.eye(m)], [-K, -B]])
        self.m, self.W = m, model.excitation_frequency(param)
        self.C = np.array(ct.directions)
        self.h = np.arange(1, model.n_harmonics + 1)
        self.ct, self.fo = ct, fo
        self.calls = 0

    def __call__(self, t, u):
        self.calls += 1
        m, ct, fo = self.m, self.ct, self.fo
        arg = self.h * self.W * t
        cs, sn = np.cos(arg), np.sin(arg)
        du = self.A @ u
        du[m:] += fo.F0 + cs @ fo.Fc + sn @ fo.Fs
        e = ct.error_cos @ cs + ct.error_sin @ sn
        ed = (ct.error_sin @ (self.h * cs) - ct.error_cos @ (self.h * sn)) * self.W
        d = self.C @ u[:m] - e
        dd = self.C @ u[m:] - ed
        mod = 1.0 + ct.stiffness_cos @ cs + ct.stiffness_sin @ sn
        hi = np.maximum(d - ct.gap_hi, 0.0)
        lo = np.maximum(ct.gap_lo - d, 0.0)
        f = ct.k_hi * mod * hi ** ct.exponent - ct.k_lo * mod * lo ** ct.exponent
        f = f + ct.damping * dd * ((hi > 0) | (lo > 0))
        du[m:] -= self.C.T @ f
        return du


def static_state(model: ReducedModel) -> np.ndarray:
    """Static equilibrium at t = 0 (kinematic error frozen), solved with scipy root."""
    rhs = DenseRHS(model, F_MESH)
    m = model.n_modes
    sol = root(lambda x: rhs(0.0, np.concatenate([x, np.zeros(m)]))[m:],
               np.linalg.solve(-rhs.A[m:, :m], model.forcing.F0), method="hybr")
    return np.concatenate([sol.x, np.zeros(m)])


def mesh_deformation(model, t, states) -> np.ndarray:
    ct = model.contacts
    arg = np.outer(t, np.arange(1, model.n_harmonics + 1)) * model.excitation_frequency(F_MESH)
    e = np.cos(arg) @ ct.error_cos[0] + np.sin(arg) @ ct.error_sin[0]
    return states[:, :model.n_modes] @ ct.directions[0] - e


# ---------------------------------------------------------------- runs

def run_ours(model, u0, t1, t_eval, rtol):
    opts = IntegrationOptions(rtol=rtol, atol=rtol * ATOL_SCALE, max_steps=20_000_000)
    t = time.perf_counter()
    tr = integrate(model, F_MESH, u0, 0.0, t1, t_eval=t_eval, options=opts)
    wall = time.perf_counter() - t
    if tr.status != 0:
        raise RuntimeError(f"integrate failed at rtol={rtol:g}: {tr.message}")
    return mesh_deformation(model, t_eval, tr.u), wall, tr


def run_scipy(model, u0, t1, t_eval, rtol):
    rhs = DenseRHS(model, F_MESH)
    t = time.perf_counter()
    sol = solve_ivp(rhs, (0.0, t1), u0, method="RK45", t_eval=t_eval, rtol=rtol,
                    atol=rtol * ATOL_SCALE)
    wall = time.perf_counter() - t
    if sol.status != 0:
        raise RuntimeError(f"solve_ivp failed at rtol={rtol:g}: {sol.message}")
    return mesh_deformation(model, t_eval, sol.y.T), wall, rhs.calls


def code_version() -> dict:
    """HEAD and whether the compiled solver sources differ from it (timings depend on it)."""
    def git(*args):
        try:
            return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                                  timeout=10).stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return ""
    dirty = git("status", "--porcelain", "--", "vibrogear/solvers/integrator/dopri.py",
                "vibrogear/solvers/integrator/kernels.py", "vibrogear/solvers/integrator/integrate.py")
    return {"head": git("rev-parse", "--short", "HEAD"), "solver_sources_modified": bool(dirty)}


def rel_err(d, ref):
    return float(np.max(np.abs(d - ref)) / (ref.max() - ref.min()))


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--periods", type=int, default=200)
    ap.add_argument("--scipy-periods", type=int, default=None,
                    help="shorter window integrated by scipy when it is too slow (its time "
                         "is then scaled to --periods); default: all --periods")
    ap.add_argument("--record-periods", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--ref-rtol", type=float, default=1e-12)
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/bench_integrator.json"))
    a = ap.parse_args(argv)
    version = code_version()          # before the (long) run: the sources it imported
    model = build_model()
    T = 1.0 / F_MESH
    u0 = static_state(model)

    def window(n_periods):
        t1 = n_periods * T
        rec = min(a.record_periods, n_periods)
        return t1, np.linspace(t1 - rec * T, t1, 40 * rec + 1)

    t1, t_eval = window(a.periods)
    # first call in this process (numba compile, or loading its on-disk cache) vs warm
    one = np.linspace(0.0, T, 41)
    t = time.perf_counter()
    run_ours(model, u0, T, one, 1e-6)
    first_call = time.perf_counter() - t
    t = time.perf_counter()
    run_ours(model, u0, T, one, 1e-6)
    warm_call = time.perf_counter() - t
    ref, ref_wall, tr_ref = run_ours(model, u0, t1, t_eval, a.ref_rtol)
    print(f"model: {model.n_modes} modes, {model.contacts.count} contacts, "
          f"mesh {F_MESH:g} Hz, {a.periods} periods ({t1:.4g} s)")
    print(f"reference rtol={a.ref_rtol:g}: {ref_wall:.3f} s, {tr_ref.steps} steps, "
          f"{tr_ref.events} events, mesh losses {tr_ref.monitor_losses}; "
          f"delta range {ref.min():.3e} .. {ref.max():.3e} m")
    ours = None
    for tol in TOL_LADDER:
        d, wall, tr = run_ours(model, u0, t1, t_eval, tol)
        err = rel_err(d, ref)
        print(f"  ours  rtol={tol:7.1e}: err {err:.2e}  {wall:.3f} s  {tr.steps} steps")
        if err <= TARGET_ERR:
            ours = dict(rtol=tol, err=err, steps=tr.steps, rhs_calls=tr.rhs_calls,
                        events=tr.events)
            break
    if ours is None:
        raise SystemExit("our integrator never reached the target error")
    walls = []
    for _ in range(a.repeats):
        _, wall, _ = run_ours(model, u0, t1, t_eval, ours["rtol"])
        walls.append(wall)
    ours["time_s"] = min(walls)
    # scipy: the same window, or a shorter one with its own reference (then scaled)
    if a.scipy_periods is None or a.scipy_periods >= a.periods:
        a.scipy_periods = a.periods
        ts1, ts_eval, sref, our_short = t1, t_eval, ref, ours["time_s"]
    else:
        ts1, ts_eval = window(a.scipy_periods)
        sref, _, _ = run_ours(model, u0, ts1, ts_eval, a.ref_rtol)
        _, our_short, _ = run_ours(model, u0, ts1, ts_eval, ours["rtol"])
    sp = None
    for tol in TOL_LADDER:
        d, wall, calls = run_scipy(model, u0, ts1, ts_eval, tol)
        err = rel_err(d, sref)
        print(f"  scipy rtol={tol:7.1e}: err {err:.2e}  {wall:.3f} s  {calls} rhs calls "
              f"({a.scipy_periods} periods)")
        if err <= TARGET_ERR:
            sp = dict(rtol=tol, err=err, rhs_calls=calls, window_periods=a.scipy_periods,
                      window_time_s=wall)
            break
    if sp is None:
        raise SystemExit("scipy never reached the target error")
    scale = a.periods / a.scipy_periods
    sp["time_s"] = sp["window_time_s"] * scale
    sp["scaled"] = scale != 1.0
    ratio = sp["time_s"] / ours["time_s"]
    ratio_window = sp["window_time_s"] / our_short
    calls_per_step = ours["rhs_calls"] / max(ours["steps"], 1)
    print(f"one mesh period: first call (JIT compile or cache load + run) {first_call:.3f} s, "
          f"JIT-warm call {warm_call:.4f} s")
    print(f"ours : rtol {ours['rtol']:.0e}, {a.periods} periods: {ours['time_s']:.3f} s "
          f"(JIT-warm, best of {a.repeats})")
    if sp["scaled"]:
        print(f"scipy: rtol {sp['rtol']:.0e}, {a.scipy_periods} periods: "
              f"{sp['window_time_s']:.3f} s -> scaled x{scale:g} to {a.periods} periods: "
              f"{sp['time_s']:.2f} s (SCALED, not measured)")
    else:
        print(f"scipy: rtol {sp['rtol']:.0e}, {a.periods} periods: {sp['time_s']:.3f} s "
              f"(measured, one run)")
    print(f"ours: {ours['steps']} steps, {ours['events']} located contact events, "
          f"{calls_per_step:.2f} rhs calls per step, "
          f"{1e6 * ours['time_s'] / ours['rhs_calls']:.1f} us per rhs call (loop included)")
    print(f"speed-up at error <= {TARGET_ERR:g}: {ratio:.1f}x "
          f"(same {a.scipy_periods}-period window: {ratio_window:.1f}x; target >= 30x)")
    res = dict(model=dict(modes=model.n_modes, contacts=model.contacts.count,
                          f_mesh_hz=F_MESH, periods=a.periods),
               target_error=TARGET_ERR, atol_over_rtol=ATOL_SCALE,
               reference=dict(rtol=a.ref_rtol, time_s=ref_wall, steps=tr_ref.steps,
                              events=tr_ref.events),
               first_call_one_period_s=first_call, warm_call_one_period_s=warm_call,
               ours=ours, scipy_rk45_dense=sp, speedup=ratio,
               speedup_same_window=ratio_window, ours_window_time_s=our_short,
               blas_threads=os.environ.get("OPENBLAS_NUM_THREADS"), code=version,
               machine=dict(python=platform.python_version(), node=platform.node(),
                            processor=platform.processor() or platform.machine()))
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(res, indent=2) + "\n")
    print(f"wrote {out}")
    return res


if __name__ == "__main__":
    main()
