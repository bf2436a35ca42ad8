"""Orbits and branches of the census's attractors, and what the sweep saw of them.

* :func:`refine_orbits`: each periodic attractor is shot over its n periods from its settled
  state (:func:`~vibrogear.solvers.periodic.shooting.shoot`, the continuation's own
  shooting and tolerances): its extrema become the orbit's (located by the integrator, as
  a branch point's), its stability the Floquet multipliers'.  One work unit per attractor,
  on local processes or every MPI rank.
* :func:`continue_branches`: pseudo-arclength continuation both ways from each periodic
  attractor through which no branch found so far passes (:func:`..sweep.branches.on_branch`:
  branches of this run's continuation, then those continued here, in grid order), within
  the census's range, each half-branch a work unit (in waves: :func:`continue_branches`).
  Branches that the sweep path never reaches (isolas) appear here with their LP / PD / NS.
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
from functools import partial

import numpy as np

from ...config.options import ContinuationOptions, ShootingOptions
from ...pipeline.executors import broadcast, effective_workers, run_units
from ...solvers.periodic.continuation import PeriodicOrbitProblem, PseudoArclength, continuation
from ...solvers.periodic.shooting import shoot
from .cluster import RANGE_OVERLAP, shared_range
from ..study import integration_options
from ..sweep.branches import on_branch

__all__ = ["refine_orbits", "continue_branches", "compare_with_sweep", "SWEEP_MATCH"]

#: extrema within this fraction of the sweep's range count as the sweep's state
SWEEP_MATCH = 0.05


def _orbit_options(study, scene):
    cont = getattr(scene, "continuation", None)
    opts = integration_options(scene, section=cont, study=study) if cont is not None \
        else scene.integration
    return opts, ShootingOptions(tol=scene.shooting.tol, max_iter=scene.shooting.max_iter)


def _shoot_unit(model, opts, shooting, unit, emit):
    k, p, u0, n = unit
    sh = shoot(model, p, u0, n_periods=n, options=opts, shooting=shooting)
    mu = np.abs(sh.floquet) if sh.converged else np.zeros(0)
    emit((k, sh.converged, np.array(sh.u0), float(sh.monitor_min), float(sh.monitor_max),
          bool(sh.stable) if sh.converged else None, float(mu.max()) if mu.size else math.nan,
          sh.message))
    return k


def _run(split, name, fn, units, **kw):
    if split is None:
        return run_units(fn, units, **kw) if units else []
    return split.run(name, fn, units, **kw)


def refine_orbits(study, scene, attractors, *, workers=None, split=None, root=True) -> None:
    """Shoot every periodic attractor (module docstring); sets ``refined``, ``qmin``,
    ``qmax``, ``u0``, ``stable``, ``max_multiplier`` in place.  One work unit per attractor,
    the longest orbits (most periods) first; collective under MPI (every rank calls it, the
    ranks other than 0 with ``root`` False and no attractors).  ``split``: a
    :class:`~vibrogear.pipeline.wall_split.WallSplit` that times the units."""
    opts, shooting = _orbit_options(study, scene)
    units = None
    if root:
        units = [(k, a.param, a.u0, a.period_n) for k, a in enumerate(attractors)
                 if a.period_n > 0 and a.u0 is not None and not study.model.multi_frequency]
    units = broadcast(units)

    def on_result(_i, item):
        k, ok, u0, qmin, qmax, stable, mu, _msg = item
        a = attractors[k]
        if ok:
            a.refined, a.qmin, a.qmax, a.u0 = True, qmin, qmax, u0
            a.qmin_err = a.qmax_err = 0.0
            a.stable, a.max_multiplier = stable, mu

    _run(split, "orbits", partial(_shoot_unit, study.model, opts, shooting), units,
         workers=workers, on_result=on_result, costs=[u[3] for u in units])


def _this_run_branches(previous) -> list:
    cont = previous.get("continuation")
    res = getattr(cont, "result", None)
    return list(getattr(res, "branches", ()) or ())


def _branch_settings(study, scene):
    """(integration options, shooting options, ContinuationOptions) of the branches."""
    cfg = scene.states
    lo, hi = float(cfg.param_min), float(cfg.param_max)
    opts, shooting = _orbit_options(study, scene)
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
    options = ContinuationOptions(param_min=lo, param_max=hi, max_points=cfg.branch_max_points,
                                  period_doubling_branch=False, **steps)
    return opts, shooting, options


def _half_unit(model, opts, tol, options, unit, _emit):
    """One half-branch (u0, param, period_n, direction, parameter scale): its Branch."""
    u0, param, n, sign, scale = unit
    method = PseudoArclength(integration=opts, tol=tol, param_scale=scale)
    got = continuation(PeriodicOrbitProblem(model, u0, param, n_periods=n, direction=sign),
                       method, options)
    return got.branches[0]


def continue_branches(study, scene, attractors, previous, *, workers=None, split=None,
                      root=True) -> tuple[list, list]:
    """(branches, notes): the branches continued from attractors (module docstring).

    Each half-branch is a work unit.  Which attractors need a branch depends on the branches
    found before them (in grid order), so they go in waves: a wave is the next attractors
    that no branch found so far passes through, as many as give each worker a half-branch;
    after it, each is kept or dropped in order exactly as one after the other would (a
    dropped one's branch is work done in a worker that had nothing else to do).  With one
    worker a wave is one attractor: the serial order itself.  The branches, notes and their
    order are the same for any number of workers.  Collective under MPI (every rank calls
    it, the ranks other than 0 with ``root`` False; they get ([], []))."""
    cfg = scene.states
    lo, hi = float(cfg.param_min), float(cfg.param_max)
    if not hi > lo:
        return [], [{"note": "one grid value: no range to continue in"}]
    if study.model.multi_frequency:
        return [], [{"note": "multi-frequency forcing (no common excitation period within "
                     "the period limit): no periodic orbit to continue"}]
    opts, shooting, options = _branch_settings(study, scene)
    fn = partial(_half_unit, study.model, opts, shooting.tol, options)
    w = effective_workers(2 * max(len(attractors or ()), 1), workers)
    per_wave = max(1, (w + 1) // 2)
    known = _this_run_branches(previous) if root else []
    cands = []
    if root:
        cands = [a for a in sorted(attractors, key=lambda a: (a.param, -a.count))
                 if a.period_n > 0 and a.refined]
    found, notes, pos = [], [], 0

    def scale_of(a):
        if not study.balance_arclength:
            return 1.0
        return (hi - lo) / max(float(np.linalg.norm(a.u0)), 1e-300)

    while True:
        wave = []
        if root:
            try:
                while pos < len(cands) and len(wave) < per_wave:
                    a = cands[pos]
                    if not on_branch(known + found, a.period_n, a.param, a.qmax, 1e-3):
                        wave.append(a)
                    pos += 1
            except BaseException:
                broadcast([])               # the other ranks leave the loop, then raise
                raise
        units = broadcast([(a.u0, a.param, a.period_n, sign, scale_of(a))
                           for a in wave for sign in (-1, 1)] if root else None)
        if not units:
            break
        halves = _run(split, "branches", fn, units, workers=workers,
                      costs=[u[2] for u in units])
        if not root:
            continue
        for j, a in enumerate(wave):
            # the first of a wave passes (nothing found since it was picked); the others
            # are checked against the branches of those before them, as in turn
            if j and on_branch(known + found, a.period_n, a.param, a.qmax, 1e-3):
                continue
            item = {study.param_name: a.param, "period_n": a.period_n, "qmax": a.qmax,
                    "stable": a.stable, "halves": []}
            for br in halves[2 * j:2 * j + 2]:
                item["halves"].append({"branch": len(found), "points": len(br.points),
                                       "status": br.status.text, "message": br.message,
                                       "special_points": [
                                           {"label": p.label, study.param_name: float(p.param)}
                                           for p in br.points if p.label]})
                if br.points:
                    found.append(br)
            notes.append(item)
    return found, notes


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

