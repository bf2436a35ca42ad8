"""Is a sweep point without a period a slow transient?  Newton on the period map from its
settled state.

A lightly damped mode decays over thousands of excitation periods; a transient that is
stopped "by statistics" then still wanders, the stroboscopic samples show no period, and
the point would be called quasi-periodic although the attractor is a periodic orbit.  So
before a point without a period is called quasi-periodic or chaotic, its settled state
seeds shooting (:func:`~vibrogear.solvers.periodic.shooting.shoot`: Newton on
u(nT; u0) - u0) for n = 1, 2:

* converged and stable (every nontrivial Floquet multiplier inside the unit circle): the
  point is periodic; the record is taken again on the orbit and its multipliers reported;
* converged and unstable: the next period is tried (beyond a period doubling the period-2
  orbit holds the attractor); if none is stable the class stands (the motion does not stay
  on the orbit) and the shortest unstable orbit is reported beside it (its period, largest
  multiplier, extrema);
* not converged within ``MAX_ITER`` iterations: no orbit near the settled state.

Only periods over which the record's stroboscopic samples drift by at most :data:`NEAR` are
tried (:func:`near_periods`): the drift of a slow transient is small, that of a torus or of
chaos is the attractor's size, and a gearbox's Newton iteration costs a full monodromy.

Two ways to the orbit, the cheap one first:

* **Extrapolation** of the record's stroboscopic states (reduced rank extrapolation, RRE, on
  the last ``EXTRAPOLATE`` states of the n-period map): a transient decaying along a few slow
  modes converges geometrically, x_k = x* + sum_j c_j mu_j^k v_j, and RRE solves for x*.  One
  plain integration over n periods from x* checks it; the record's geometric approach to
  it (:func:`_approaches`: RRE also finds unstable orbits) is the evidence of stability and
  its rate estimates the largest multiplier.  It costs n periods, whatever the model's size.
* **Newton** (:func:`~vibrogear.solvers.periodic.shooting.shoot`), on models of at most
  :data:`NEWTON_MAX_STATES` states (a gearbox's iteration integrates the full variational
  equations: ~300 columns, seconds each): it also finds unstable orbits, with all their
  multipliers.

The tolerance is the sweep's ``period_tol`` in the units the stroboscopic map is judged in
(each block's largest |value|: positions, velocities), a tenth of it for margin, converted to
the shooting residual |u(nT) - u0| / (1 + |u0|): a gearbox's states are ~1e-5, where an
unscaled 1e-4 would accept any state.  On the sweep's integrator options.
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np

from ...config.options import IntegrationOptions, ShootingOptions
from ..periodic.floquet import split_trivial
from ..integrator.integrate import integrate
from ..periodic.shooting import shoot
from .motion import block_scaled

__all__ = ["OrbitCheck", "check_orbit", "near_periods", "extrapolate", "MAX_ITER", "NEAR",
           "PROBE_ITER", "PROBE_DROP", "NEWTON_MAX_STATES", "EXTRAPOLATE"]

#: Newton iterations per period tried (a slow transient's settled state is close)
MAX_ITER = 6
#: a period is tried only where the record's stroboscopic samples drift by at most this
#: (scaled as the period test scales them) over one period: a slow transient drifts little,
#: chaos and tori by the size of the attractor.  Each Newton iteration of a large model
#: integrates the full variational equations, so chaos is not shot at.
NEAR = 0.05
#: Newton is tried on models of at most this many states
NEWTON_MAX_STATES = 128
#: stroboscopic states of the n-period map that the extrapolation uses (its last ones)
EXTRAPOLATE = 8
#: restarts of the extrapolation from integrated iterates (each EXTRAPOLATE x n periods)
CYCLES = 3
#: an extrapolated orbit counts as stable only if the record approached it this fast ...
APPROACH_RATE = 0.995
#: ... and its last iterate is this much closer than its first
APPROACH_SHRINK = 0.9
#: the probe: Newton iterations before it must show quadratic convergence ...
PROBE_ITER = 2
#: ... by a residual below this fraction of the record's drift over the period
PROBE_DROP = 1e-2


@dataclass(frozen=True, eq=False)
class OrbitCheck:
    """What shooting from a settled state found."""
    period_n: int                 # orbit's period in excitation periods (0: none found)
    stable: bool
    max_multiplier: float         # largest nontrivial |Floquet multiplier| (NaN: none found)
    residual: float               # periodicity residual of the last Newton iterate
    u0: np.ndarray | None         # the orbit's state at phase 0
    qmin: float                   # extrema of the monitored deformation over the orbit
    qmax: float
    iterations: int
    rhs_calls: int
    wall_s: float
    message: str
    method: str = ""              # "extrapolation" or "newton"

    def as_metrics(self) -> dict:
        """The evidence for the sweep's point metrics (``orbit_*``)."""
        return {"orbit_period_n": self.period_n, "orbit_stable": float(self.stable),
                "orbit_max_multiplier": self.max_multiplier, "orbit_residual": self.residual,
                "orbit_qmin": self.qmin, "orbit_qmax": self.qmax,
                "orbit_newton": float(self.method == "newton")}


def near_periods(samples, periods=(1, 2), near: float = NEAR) -> tuple[int, ...]:
    """The periods n whose stroboscopic drift max_k |x_{k+n} - x_k| of the positions (in
    units of their largest |value|, as the period test scales them) is at most ``near``.
    Positions only: the velocities at phase 0 can be near zero on the orbit itself, which
    makes their scaled drift large on any transient."""
    s = np.asarray(samples, dtype=float)
    if s.ndim != 2 or s.shape[0] < 2 or not np.all(np.isfinite(s)):
        return ()
    z = block_scaled(s[:, :max(s.shape[1] // 2, 1)], None)
    return tuple(n for n in periods if n < s.shape[0]
                 and float(np.max(np.abs(z[n:] - z[:-n]))) <= near)


def extrapolate(xs) -> tuple[np.ndarray, float]:
    """(x*, |mu|): the fixed point of a geometrically converging vector sequence ``xs``
    (K, N) by reduced rank extrapolation (min |sum g_i (x_{i+1} - x_i)| with sum g_i = 1,
    x* = sum g_i x_i), and the decay rate of its steps (a least-squares fit of log |dx_k|
    against k: the largest multiplier of the slow modes)."""
    xs = np.asarray(xs, dtype=float)
    U = np.diff(xs, axis=0)                       # (K-1, N)
    G = U @ U.T
    g = np.linalg.lstsq(G + 1e-14 * np.trace(G) * np.eye(len(G)), np.ones(len(G)),
                        rcond=None)[0]
    g = g / g.sum() if g.sum() != 0 else np.full(len(G), 1.0 / len(G))
    step = np.linalg.norm(U, axis=1)
    ok = step > 0
    rate = math.nan
    if np.count_nonzero(ok) >= 2:
        k = np.flatnonzero(ok)
        rate = float(np.exp(np.polyfit(k, np.log(step[ok]), 1)[0]))
    return g @ xs[:-1], rate


def _extrapolated(model, param, drift, n, period_tol, options, m):
    """The orbit of period n by extrapolation (module docstring), restarted from integrated
    iterates up to :data:`CYCLES` times (each ``EXTRAPOLATE`` x n plain periods) until no
    step of such a window moves by more than half ``period_tol`` in the period test's units;
    None if it does not get there."""
    seq = np.asarray(drift, dtype=float)[::-1][::n][::-1][-EXTRAPOLATE:]
    if len(seq) < 4:
        return None
    T = model.excitation_period(param)
    ref = np.max(np.abs(seq), axis=0)
    scale = np.concatenate([np.full(m, max(ref[:m].max(), 1e-300)),
                            np.full(seq.shape[1] - m, max(ref[m:].max(), 1e-300))])
    rate = math.nan
    for cycle in range(CYCLES + 1):
        x, r = extrapolate(seq / scale)
        x = x * scale
        rate = r if cycle == 0 else rate          # the record's decay: the slow multiplier
        t = np.arange(1, EXTRAPOLATE + 1) * (n * T)
        tr = integrate(model, param, x, 0.0, t[-1], t_eval=t, options=options)
        if not tr.ok or not np.all(np.isfinite(tr.u)):
            return None
        # every step of the window, scaled as the period test scales a record: a slow mode
        # that rotates (|mu| ~ 1, small angle) moves little in one period
        z = block_scaled(np.vstack([x, tr.u]), m)
        defect = float(np.max(np.abs(z[1:] - z[:-1])))
        if defect <= 0.5 * period_tol:
            return (x, rate, defect) if _approaches(model, drift, x, n) else None
        seq = np.vstack([x, tr.u])
    return None


def _approaches(model, drift, x, n) -> bool:
    """Stability evidence without multipliers: in the second half of the record the n-period
    iterates approach the fixed point x geometrically (fitted rate <= APPROACH_RATE, the last
    distance at most APPROACH_SHRINK of the first).  The distance is the deviation's modal
    energy sqrt(sum omega_i^2 dq_i^2 + dv_i^2), its running maximum over 4 iterates (a slow
    mode rotates between position and velocity from one period to the next).  RRE also finds
    unstable fixed points, and a torus born at a Neimark-Sacker crossing circles one."""
    seq = np.asarray(drift, dtype=float)[::-1][::n][::-1]
    seq = seq[len(seq) // 2:]                     # the faster modes have decayed there
    m = model.n_modes
    w = np.sqrt(np.maximum(np.asarray(model.omega2, dtype=float), 0.0))
    dev = seq - x
    e = np.sqrt(np.sum((w * dev[:, :m]) ** 2 + dev[:, m:] ** 2, axis=1))
    if len(e) < 8 or not np.all(e > 0):
        return False
    d = np.array([e[k:k + 4].max() for k in range(len(e) - 3)])
    rate = float(np.exp(np.polyfit(np.arange(len(d)), np.log(d), 1)[0]))
    return rate <= APPROACH_RATE and d[-1] <= APPROACH_SHRINK * d[0]


def check_orbit(model, param: float, u_settled, *, period_tol: float,
                options: IntegrationOptions, periods=(1, 2), drift=None) -> OrbitCheck:
    """Shoot from ``u_settled`` (phase 0) for each period in ``periods``, shortest first;
    the first converged orbit is returned (module docstring).  ``drift``: the record's
    stroboscopic states (ending at ``u_settled``): Newton stops after :data:`PROBE_ITER`
    iterations unless its residual fell below :data:`PROBE_DROP` of the record's own
    drift over the period (quadratic convergence near an orbit; none near chaos)."""
    wall = time.perf_counter()
    u = np.asarray(u_settled, dtype=float)
    m = u.size // 2
    scale = min(float(np.max(np.abs(u[:m]))), float(np.max(np.abs(u[m:]))))
    tol = 0.1 * float(period_tol) * max(scale, 1e-300) / (1.0 + float(np.linalg.norm(u)))
    shooting = ShootingOptions(tol=min(tol, 0.1 * float(period_tol)), max_iter=MAX_ITER)
    iters, calls, last, residual = 0, 0, "no period tried", math.nan
    unstable = None
    norm = 1.0 + float(np.linalg.norm(u))
    for n in periods:
        if drift is not None:
            ext = _extrapolated(model, param, drift, n, period_tol, options, m)
            if ext is not None:
                x, rate, defect = ext
                if u.size <= NEWTON_MAX_STATES:        # polished by Newton: all multipliers
                    sh = shoot(model, param, x, n_periods=int(n), options=options,
                               shooting=shooting)
                    iters += sh.iterations
                    calls += sh.rhs_calls
                    if sh.converged:              # Newton's multipliers decide
                        nontrivial = np.abs(split_trivial(sh.floquet, sh.neutral)[0])
                        found = OrbitCheck(int(n), bool(sh.stable), float(nontrivial.max()),
                                           float(sh.residual), sh.u0.copy(),
                                           float(sh.monitor_min), float(sh.monitor_max),
                                           iters, calls, time.perf_counter() - wall,
                                           f"period-{n} orbit, "
                                           f"{'stable' if sh.stable else 'unstable'}", "newton")
                        if found.stable:
                            return found
                        unstable = unstable or found
                        continue
                return OrbitCheck(int(n), True, rate, defect, x, math.nan, math.nan, iters,
                                  calls, time.perf_counter() - wall,
                                  f"period-{n} orbit by extrapolation, decay {rate:.4g} per "
                                  "orbit", "extrapolation")
        if u.size > NEWTON_MAX_STATES:
            last = f"period {n}: not found by extrapolation (Newton is left out above " \
                   f"{NEWTON_MAX_STATES} states)"
            continue
        start, probe = u, None
        if drift is not None and len(drift) > n:
            r0 = float(np.linalg.norm(np.asarray(drift[-1]) - np.asarray(drift[-1 - n]))) / norm
            probe = shoot(model, param, u, n_periods=int(n), options=options,
                          shooting=ShootingOptions(tol=shooting.tol, max_iter=PROBE_ITER))
            iters += probe.iterations
            calls += probe.rhs_calls
            if not probe.converged and not probe.residual < PROBE_DROP * r0:
                residual, last = float(probe.residual), f"period {n}: no convergence"
                continue
            start = probe.u0
        if probe is not None and probe.converged:
            sh = probe
        else:
            sh = shoot(model, param, start, n_periods=int(n), options=options, shooting=shooting)
            iters += sh.iterations
            calls += sh.rhs_calls
        residual = float(sh.residual)
        if sh.converged:
            nontrivial = np.abs(split_trivial(sh.floquet, sh.neutral)[0])
            found = OrbitCheck(int(n), bool(sh.stable),
                               float(nontrivial.max()) if nontrivial.size else math.nan,
                               residual, sh.u0.copy(), float(sh.monitor_min),
                               float(sh.monitor_max), iters, calls,
                               time.perf_counter() - wall,
                               f"period-{n} orbit, {'stable' if sh.stable else 'unstable'}",
                               "newton")
            if found.stable:
                return found
            # unstable (e.g. beyond a period doubling): the next period may hold the attractor
            unstable = unstable or found
            continue
        last = f"period {n}: {sh.message}"
    if unstable is not None:
        return dataclasses.replace(unstable, iterations=iters, rhs_calls=calls,
                                   wall_s=time.perf_counter() - wall)
    return OrbitCheck(0, False, math.nan, residual, None, math.nan, math.nan, iters, calls,
                      time.perf_counter() - wall, f"no orbit near the settled state ({last})")
