"""The periodic orbit a continuation starts from, at one end of its parameter range.

``transient_periods`` excitation periods from the static equilibrium settle the motion; the
sweep's period detection (:func:`~vibrogear.solvers.sequential.sweep.classify_period` on
``RECORD_PERIODS`` stroboscopic states) gives its period n (a rattle cycle of a free gear
spans n mesh periods), and shooting over n periods converges onto it.  Where that shooting
fails, or the settled motion is not periodic (chaotic rattle: then before a period-1 Newton
from the settled motion), the period-1 orbit that continues the static equilibrium is shot
from the equilibrium itself: it exists, unstable, inside the rattle windows, and its branch
shows where stability is lost (PD / NS / LP).

Shared by the verbs that trace branches (``continuation``, the operating map's LP / PD
curves), so that neither imports the other.
"""
from __future__ import annotations

import numpy as np

from ...config.options import ShootingOptions
from ...pipeline.executors import blas_threads
from ..integrator.integrate import integrate
from ..integrator.split_flow import ColumnSplit
from ..sequential.sweep import classify_period
from .shooting import shoot

__all__ = ["starting_orbit", "RECORD_PERIODS"]

#: stroboscopic periods recorded after the transient to detect the period of the start
RECORD_PERIODS = 24


def starting_orbit(model, p0: float, u_static, *, transient_periods: int, options, tol: float,
                   max_iter: int, max_period: int = 8, period_tol: float = 1e-4):
    """(u0, n_periods, guess, how): a converged periodic orbit at ``p0`` to start from (see
    the module docstring), the state Newton started from, and ``how``, which start worked.
    u0 is None when none did.  The monodromies of the shooting share their columns with a
    second process where the model is big enough (:class:`ColumnSplit`)."""
    with blas_threads(1), ColumnSplit(model) as split:
        return _starting_orbit(model, p0, u_static, transient_periods, options,
                               ShootingOptions(tol=tol, max_iter=max_iter), max_period,
                               period_tol, split)


def _starting_orbit(model, p0, u_static, transient_periods, options, shooting, max_period,
                    period_tol, split):
    T = model.excitation_period(p0)
    warm = integrate(model, p0, u_static, 0.0, max(int(transient_periods), 1) * T,
                     options=options)
    tried = []
    settled = []                # (n_periods, guess) to shoot from, in order
    if warm.ok:
        R = max(RECORD_PERIODS, 2 * int(max_period) + 1)
        rec = integrate(model, p0, warm.u_end, 0.0, R * T, t_eval=np.arange(R + 1) * T,
                        options=options)
        n, _ = (classify_period(rec.u, max_period, period_tol, split=model.n_modes)
                if rec.ok else (0, np.nan))
        settled = [(k, warm.u_end) for k in dict.fromkeys((n, 1)) if k >= 1]
        if not n:
            tried.append("settled motion not classified periodic")
    else:
        tried.append(f"transient: {warm.message}")
    # a periodic settled motion first (its orbit is the one the gearbox runs on); where the
    # motion is not periodic (chaotic rattle), a period-1 Newton from it rarely converges
    # (two-stage gearbox at 3000 rpm: 6 orbits with the monodromy, then its line search
    # fails): the static equilibrium's orbit first there, the settled motion after it
    static = (1, u_static)
    order = settled[:1] + [static] + settled[1:] if settled and n else [static] + settled
    for k, guess in order:
        sh = shoot(model, p0, guess, n_periods=k, options=options, shooting=shooting,
                   split=split)
        where = "the static equilibrium" if guess is u_static else "the settled motion"
        if sh.converged:
            note = f" ({'; '.join(tried)})" if tried else ""
            return sh.u0, k, guess, f"period-{k} orbit from {where}{note}"
        tried.append(f"period-{k} from {where}: {sh.message}")
    return None, 1, u_static, "; ".join(tried)
