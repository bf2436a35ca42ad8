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
* converged and unstable: the class stands (the motion does not stay on the orbit) and
  the orbit is reported beside it (its period, largest multiplier, extrema);
* not converged within ``MAX_ITER`` iterations: no orbit near the settled state.

The residual tolerance is the sweep's ``period_tol`` (the same test that calls a
stroboscopic map periodic), on the sweep's integrator options.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ...config.options import IntegrationOptions, ShootingOptions
from ..periodic.floquet import split_trivial
from ..periodic.shooting import shoot

__all__ = ["OrbitCheck", "check_orbit", "MAX_ITER"]

#: Newton iterations per period tried (a slow transient's settled state is close)
MAX_ITER = 8


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

    def as_metrics(self) -> dict:
        """The evidence for the sweep's point metrics (``orbit_*``)."""
        return {"orbit_period_n": self.period_n, "orbit_stable": float(self.stable),
                "orbit_max_multiplier": self.max_multiplier, "orbit_residual": self.residual,
                "orbit_qmin": self.qmin, "orbit_qmax": self.qmax}


def check_orbit(model, param: float, u_settled, *, period_tol: float,
                options: IntegrationOptions, periods=(1, 2)) -> OrbitCheck:
    """Shoot from ``u_settled`` (phase 0) for each period in ``periods``, shortest first;
    the first converged orbit is returned (module docstring)."""
    wall = time.perf_counter()
    shooting = ShootingOptions(tol=float(period_tol), max_iter=MAX_ITER)
    iters, calls, last, residual = 0, 0, "no period tried", math.nan
    for n in periods:
        sh = shoot(model, param, np.asarray(u_settled, dtype=float), n_periods=int(n),
                   options=options, shooting=shooting)
        iters += sh.iterations
        calls += sh.rhs_calls
        residual = float(sh.residual)
        if sh.converged:
            nontrivial = np.abs(split_trivial(sh.floquet, sh.neutral)[0])
            return OrbitCheck(int(n), bool(sh.stable),
                              float(nontrivial.max()) if nontrivial.size else math.nan,
                              residual, sh.u0.copy(), float(sh.monitor_min),
                              float(sh.monitor_max), iters, calls,
                              time.perf_counter() - wall,
                              f"period-{n} orbit, {'stable' if sh.stable else 'unstable'}")
        last = f"period {n}: {sh.message}"
    return OrbitCheck(0, False, math.nan, residual, None, math.nan, math.nan, iters, calls,
                      time.perf_counter() - wall, f"no orbit near the settled state ({last})")
