"""Largest Lyapunov exponent of a forced ReducedModel with a confidence interval.

Benettin's method with two nearby trajectories (an estimate independent of the
variational equations, which the compiled integrator carries for the whole monodromy
only): the reference trajectory and a perturbed one, started ``d0`` apart (in scaled
state units) along a tangent direction v, are integrated over ``chunk`` excitation
periods by the *same* procedure (one integrator call each, same options, from the same
phase), so their integration errors are correlated and their difference is the action
of the flow's derivative on d0 v to O(d0^2) -- contact switches included: the perturbed
trajectory locates its own events, which is what the saltation matrix linearises.  The
log growth of |delta| is recorded at every period end; at the end of each chunk the
difference is renormalised to length d0 and becomes the next direction.

With g_k the log growth over period k and T the excitation period, the exponent is
lambda = mean(g) / T (in 1 / the model's time unit, like ln|mu| / T of a Floquet
multiplier mu; divided by ``ReducedModel.time_unit_s`` it is in 1/s, times T it is the
log growth per excitation period).  The first chunk aligns v with the leading direction and is left out;
the other chunks are the blocks of the interval: lambda_b = sum of g over block b /
(chunk T), the estimate their mean and the 95 % interval mean +- t_{B-1} s / sqrt(B)
(Student's t, s the standard deviation of the block estimates).  Norm: each state block
(displacements, velocities) divided by its scale (``scale``), so d0 is relative.
"""
from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass

import numpy as np

from ...models.reduced import ReducedModel
from ..integrator.integrate import IntegrationOptions, integrate
from ...status import Outcome, Status

__all__ = ["LyapunovResult", "largest_lyapunov", "tangent_chunk", "block_estimate",
           "state_scale", "initial_direction", "D0", "CHUNK"]

#: relative size of the perturbation (scaled state units)
D0 = 1e-6
#: excitation periods between renormalisations (one integrator call each)
CHUNK = 4


@dataclass(frozen=True, eq=False)
class LyapunovResult:
    exponent: float              # in 1 / model time unit (NaN when undetermined)
    ci: tuple[float, float]      # 95 % confidence interval (NaN when < 2 blocks)
    blocks: np.ndarray           # per-block estimates
    log_growth: np.ndarray       # (periods,) log growth per excitation period
    period: float                # excitation period T
    status: Status
    message: str
    rhs_calls: int
    wall_time: float

    @property
    def ok(self) -> bool:
        return self.status == Status.OK

    @property
    def outcome(self) -> Outcome:
        """The error estimate is the half width of the exponent's 95 % interval."""
        lo, hi = self.ci
        return Outcome(self.status, self.message, {"rhs_calls": self.rhs_calls,
                                                   "periods": self.log_growth.size},
                       self.wall_time, {"exponent_ci_half_width": (hi - lo) / 2})


def state_scale(samples, m: int) -> np.ndarray:
    """(n,) per-state scales: the largest |value| of the displacement and the velocity
    block over ``samples`` (k, n) (a tiny floor keeps a resting block usable)."""
    s = np.abs(np.atleast_2d(np.asarray(samples, dtype=float)))
    sx = float(np.max(s[:, :m], initial=0.0))
    sv = float(np.max(s[:, m:], initial=0.0))
    out = np.empty(s.shape[1])
    out[:m] = sx if sx > 1e-300 else 1.0
    out[m:] = sv if sv > 1e-300 else 1.0
    return out


def tangent_chunk(model: ReducedModel, param: float, u_start, reference, direction,
                  scale, *, options: IntegrationOptions, d0: float = D0, t_start: float = 0.0):
    """One chunk of Benettin's method.

    ``u_start``: the reference state at the chunk's start (phase 0, an integrator end
    state); ``reference`` (K, n): the reference states at the K period ends, integrated
    from ``u_start`` over [0, K T] by one :func:`integrate` call with ``options``;
    ``direction`` (n,): unit tangent in scaled units.  Returns (log growth per period
    (K,), next unit direction, rhs calls, trajectory status).  ``t_start``: the model time
    the reference started from (the forcing's phase; 0 unless the model is multi-frequency:
    ``ReducedModel.phase_time``)."""
    reference = np.atleast_2d(np.asarray(reference, dtype=float))
    K = reference.shape[0]
    T = model.excitation_period(param)
    v = np.asarray(direction, dtype=float)
    u_p = np.asarray(u_start, dtype=float) + d0 * v * scale
    t_eval = t_start + np.arange(1, K + 1) * T
    tr = integrate(model, param, u_p, t_start, t_start + K * T, t_eval=t_eval, options=options)
    if not tr.ok:
        return np.full(K, math.nan), v, tr.rhs_calls, tr.status
    diff = (tr.u - reference) / scale
    norms = np.linalg.norm(diff, axis=1)
    prev = np.concatenate([[d0], norms[:-1]])
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.log(norms / prev)
    last = diff[-1]
    nl = float(np.linalg.norm(last))
    if not (math.isfinite(nl) and nl > 0):
        return np.full(K, math.nan), v, tr.rhs_calls, Status.NONFINITE
    return g, last / nl, tr.rhs_calls, Status.OK


def initial_direction(direction, scale, n: int, seed: int = 0) -> np.ndarray:
    """Unit tangent in scaled units: ``direction`` (state units) when given and nonzero,
    else a random one."""
    if direction is not None:
        v = np.asarray(direction, dtype=float) / scale
        nv = float(np.linalg.norm(v))
        if math.isfinite(nv) and nv > 0:
            return v / nv
    v = np.random.default_rng(seed).standard_normal(n)
    return v / np.linalg.norm(v)


@functools.lru_cache(maxsize=64)
def _t975(dof: int) -> float:
    """Student's t 97.5 % quantile (scipy's; a sweep asks for the same few every point)."""
    from scipy.stats import t as student_t

    return float(student_t.ppf(0.975, dof))


def block_estimate(log_growth, period: float, chunk: int = CHUNK, burn: int = 1):
    """(exponent, (lo, hi), block estimates) from per-period log growths: blocks of
    ``chunk`` periods after ``burn`` blocks, Student-t 95 % interval of their mean."""
    g = np.asarray(log_growth, dtype=float)
    nb = g.size // chunk
    if nb - burn >= 1:
        blocks = g[burn * chunk: nb * chunk].reshape(nb - burn, chunk).sum(axis=1) / (
            chunk * period)
    else:                                   # too short for burn-in: use what there is
        blocks = g[: nb * chunk].reshape(nb, chunk).sum(axis=1) / (chunk * period) \
            if nb else np.zeros(0)
    if blocks.size == 0 or not np.all(np.isfinite(blocks)):
        return math.nan, (math.nan, math.nan), blocks
    lam = float(blocks.mean())
    if blocks.size < 2:
        return lam, (math.nan, math.nan), blocks
    half = float(_t975(blocks.size - 1) * blocks.std(ddof=1)
                 / math.sqrt(blocks.size))
    return lam, (lam - half, lam + half), blocks


def largest_lyapunov(model: ReducedModel, param: float, u0, periods: int, *,
                     options: IntegrationOptions = IntegrationOptions(), chunk: int = CHUNK,
                     d0: float = D0, burn: int = 1, seed: int = 0,
                     direction=None, phase0: int = 0) -> LyapunovResult:
    """The largest Lyapunov exponent over ``periods`` excitation periods from ``u0`` (at
    phase 0, on or near the attractor); see the module docstring.  ``direction``: the
    starting tangent (state units; e.g. the difference of two successive stroboscopic
    samples of a trajectory converging to u0: it is already along the slowest decaying
    direction), default random (``seed``).  ``phase0``: the excitation periods the forcing
    has run at ``u0`` (a multi-frequency model's: ``sweep_point.end_phase``)."""
    wall = time.perf_counter()
    u = np.array(u0, dtype=float)
    T = model.excitation_period(param)
    chunk = int(chunk)
    if periods < chunk or chunk < 1:
        raise ValueError("largest_lyapunov: periods must be >= chunk >= 1")
    m = model.n_modes
    scale = None
    v = None
    logs, calls = [], 0
    status, message = Status.OK, "ok"
    for i in range(int(periods) // chunk):
        t_s = model.phase_time(phase0 + i * chunk, param)    # the forcing carried on
        t_eval = t_s + np.arange(1, chunk + 1) * T
        ref = integrate(model, param, u, t_s, t_s + chunk * T, t_eval=t_eval, options=options)
        calls += ref.rhs_calls
        if not ref.ok:
            status, message = ref.status, ref.message
            break
        if scale is None:
            scale = state_scale(np.vstack([u, ref.u]), m)
            v = initial_direction(direction, scale, u.size, seed)
        g, v, c, st = tangent_chunk(model, param, u, ref.u, v, scale, options=options, d0=d0,
                                    t_start=t_s)
        calls += c
        if st != Status.OK:
            status, message = st, f"perturbed trajectory: {st.message}"
            break
        logs.append(g)
        u = ref.u_end
    g = np.concatenate(logs) if logs else np.zeros(0)
    lam, ci, blocks = block_estimate(g, T, chunk, burn)
    return LyapunovResult(exponent=lam, ci=ci, blocks=blocks, log_growth=g, period=T,
                          status=status, message=message, rhs_calls=calls,
                          wall_time=time.perf_counter() - wall)
