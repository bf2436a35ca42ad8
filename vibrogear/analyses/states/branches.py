"""Orbits and branches of the census's attractors, and what the sweep saw of them.

The pieces of the census's later units (:mod:`.plan` schedules them):

* :func:`shoot_orbit`: a periodic attractor shot over its n periods from its settled state
  (:func:`~vibrogear.solvers.periodic.shooting.shoot`, the continuation's own shooting and
  tolerances, :func:`orbit_options`): its extrema become the orbit's (located by the
  integrator, as a branch point's), its stability the Floquet multipliers'.
* :func:`half_branch`: pseudo-arclength continuation one way from an attractor's orbit,
  within the census's range (:func:`branch_settings`).  Branches that the sweep path never
  reaches (isolas) appear this way with their LP / PD / NS.
* :func:`compare_with_sweep`: whether the sweep (this run's, or ``sweep.npz`` in the output
  folder) passes through each attractor: some direction's sweep, linearly interpolated at
  the attractor's parameter between two good points, has the same periodicity (periodic or
  not) at the nearer point and, for a periodic attractor, extrema within 5 % of the sweep's
  overall range of the monitored deformation (plus 3 standard errors of the attractor's
  extrema); for a non-periodic one (whose extrema are the envelope over its starts' records,
  wider than one record's) a range [qmin, qmax] that overlaps the attractor's over at least
  :data:`~.cluster.RANGE_OVERLAP` of their union, the census's own grouping test.  A
  heuristic, named as such in the summary; ``seen_by_sweep`` is None where there is no
  sweep.
"""
from __future__ import annotations

import math

import numpy as np

from ...config.options import ContinuationOptions, ShootingOptions
from ...solvers.periodic.continuation import PeriodicOrbitProblem, PseudoArclength, continuation
from ...solvers.periodic.shooting import shoot
from .cluster import RANGE_OVERLAP, shared_range
from ..study import integration_options

__all__ = ["orbit_options", "shoot_orbit", "known_branches", "branch_settings", "half_branch",
           "compare_with_sweep", "SWEEP_MATCH"]

#: extrema within this fraction of the sweep's range count as the sweep's state
SWEEP_MATCH = 0.05


def orbit_options(study, scene):
    """(integration options, ShootingOptions) of the orbits and the branches: the
    continuation's own."""
    cont = getattr(scene, "continuation", None)
    opts = integration_options(scene, section=cont, study=study) if cont is not None \
        else scene.integration
    return opts, ShootingOptions(tol=scene.shooting.tol, max_iter=scene.shooting.max_iter)


def shoot_orbit(model, opts, shooting, p, u0, n) -> tuple:
    """A periodic attractor shot over its n periods from its settled state ``u0``:
    (converged, u0 on the orbit, qmin, qmax, stable, largest |Floquet multiplier|)."""
    sh = shoot(model, p, u0, n_periods=n, options=opts, shooting=shooting)
    mu = np.abs(sh.floquet) if sh.converged else np.zeros(0)
    return (bool(sh.converged), np.array(sh.u0), float(sh.monitor_min), float(sh.monitor_max),
            bool(sh.stable) if sh.converged else None, float(mu.max()) if mu.size else math.nan)


def known_branches(previous) -> list:
    """The branches of this run's continuation (``previous["continuation"]``), if any."""
    cont = (previous or {}).get("continuation")
    res = getattr(cont, "result", None)
    return list(getattr(res, "branches", ()) or ())


def branch_settings(study, scene) -> ContinuationOptions:
    """The ContinuationOptions of the branches continued from the census's attractors:
    within the census's range, first steps of half a grid step."""
    cfg = scene.states
    lo, hi = float(cfg.param_min), float(cfg.param_max)
    cont = getattr(scene, "continuation", None)
    grid_step = (hi - lo) / max(cfg.n_points - 1, 1)
    if cont is not None:
        steps = dict(ds=cont.ds, ds_min=cont.ds_min, ds_max=cont.ds_max)
    else:
        # first steps of half a grid step; at most a fifth of the range where the arclength
        # is balanced to the parameter (gearboxes), else the range (the state's change, not
        # the parameter's, then sets the arclength: the impact pair)
        steps = dict(ds=min(grid_step / 2, (hi - lo) / 10), ds_min=(hi - lo) * 1e-6,
                     ds_max=(hi - lo) / 5 if study.balance_arclength else hi - lo)
    steps["ds"] = min(steps["ds"], max(steps["ds_min"], grid_step / 2))
    steps["ds_max"] = max(steps["ds_max"], steps["ds"])
    return ContinuationOptions(param_min=lo, param_max=hi, max_points=cfg.branch_max_points,
                               period_doubling_branch=False, **steps)


def half_branch(model, opts, tol, options, u0, param, n, sign, scale):
    """One half-branch from an attractor's orbit (``sign``: the direction of the first
    step; ``scale``: the parameter's weight in the arclength): its Branch."""
    method = PseudoArclength(integration=opts, tol=tol, param_scale=scale)
    got = continuation(PeriodicOrbitProblem(model, u0, param, n_periods=n, direction=sign),
                       method, options)
    return got.branches[0]


def _sweep_data(sweep) -> dict | None:
    if sweep is None or sweep.result is None:
        return None
    res = sweep.result
    if isinstance(res, dict):
        return {k: np.asarray(res[k]) for k in ("param", "direction", "qmin", "qmax",
                                                 "period_n") if k in res}
    sw = getattr(res, "sweep", res)
    return {"param": sw.param, "direction": sw.direction, "qmin": sw.qmin, "qmax": sw.qmax,
            "period_n": np.where(sw.status == 0, sw.period_n, -1)}


def compare_with_sweep(study, attractors, sweep) -> dict | None:
    """Sets each attractor's ``seen_by_sweep`` (module docstring); returns the sweep's
    arrays (None: no sweep)."""
    data = _sweep_data(sweep)
    if data is None or not {"param", "qmin", "qmax", "period_n", "direction"} <= set(data):
        return None
    param = np.asarray(data["param"], float)
    qmin, qmax = np.asarray(data["qmin"], float), np.asarray(data["qmax"], float)
    pn = np.asarray(data["period_n"], int)
    ok = np.isfinite(qmin) & np.isfinite(qmax) & (pn >= 0)
    if not np.any(ok):
        return None
    span = float(np.max(qmax[ok]) - np.min(qmin[ok])) or 1.0
    direction = np.asarray(data["direction"]).astype(str)
    for a in attractors:
        seen = False
        for d in np.unique(direction):
            idx = np.flatnonzero((direction == d) & ok)
            idx = idx[np.argsort(param[idx])]
            if idx.size == 0 or not param[idx[0]] <= a.param <= param[idx[-1]]:
                continue
            j = int(np.searchsorted(param[idx], a.param))
            j0, j1 = idx[max(j - 1, 0)], idx[min(j, idx.size - 1)]
            s = 0.0 if param[j1] == param[j0] else (a.param - param[j0]) / (param[j1] - param[j0])
            near = j0 if s < 0.5 else j1
            if (pn[near] > 0) != (a.period_n > 0):
                continue
            q0 = qmin[j0] + s * (qmin[j1] - qmin[j0])
            q1 = qmax[j0] + s * (qmax[j1] - qmax[j0])
            if a.period_n == 0:        # the census's own range test (envelope vs one record)
                if shared_range(q0, q1, a.qmin, a.qmax) >= RANGE_OVERLAP:
                    seen = True
                    break
                continue
            tol = SWEEP_MATCH * span
            if abs(q0 - a.qmin) <= tol + 3 * _z(a.qmin_err) and \
                    abs(q1 - a.qmax) <= tol + 3 * _z(a.qmax_err):
                seen = True
                break
        a.seen_by_sweep = seen
    return {k: np.asarray(v) for k, v in data.items()}


def _z(x) -> float:
    return float(x) if math.isfinite(x) else 0.0

