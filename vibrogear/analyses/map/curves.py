"""Fold (LP) and period-doubling (PD) curves of the period-1 branch in the (speed, load) plane.

What this is: bifurcation points **located on one-parameter branches at a sequence of
loads and joined**, not a two-parameter (bordered) continuation of the bifurcation
condition.  At each load the period-1 branch is continued in speed by the continuation API
(:func:`~vibrogear.solvers.periodic.continuation.continuation`, shooting + pseudo-arclength, LP and
PD located by the solver's test functions and bisection in arclength); the LP and PD points
of that branch are collected; the points of successive loads are joined per label by the
nearest speed.  Between two loads the curve is a straight line: its accuracy in load is the
load spacing.  A cusp (two folds meeting) shows as a pair of curves that ends between two
loads.

Only short windows are traced: the first load (the one nearest the scene's nominal load)
over the whole first window (the map's speed range), every later load over windows of
``margin`` rpm around the previous load's bifurcation speeds (clusters of speeds closer
than 2 x margin share a window); loads are visited outward from the first one.  Each
window starts at its upper end from the period-1 orbit there (the settled motion shot over
one period, else the orbit that continues the static equilibrium), so the period-2 branch
is never followed (``period_doubling_branch = False``) and a PD of the period-1 branch is
where the sweep's period-2 region begins or ends.  The branch enters and leaves each
window, so its folds come in pairs: a window with an odd number of LPs (a step passed over
one) is traced once more at half the step, and its message says so.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from functools import partial

import numpy as np

from ...config.options import ContinuationOptions
from ...pipeline.executors import run_units, under_mpi
from ...solvers.periodic.continuation import PeriodicOrbitProblem, PseudoArclength, continuation
from ...solvers.periodic.starting_orbit import starting_orbit
from .load_scaling import LoadScaling
from ..study import Study, integration_options, start_state

__all__ = ["Curve", "LoadBifurcations", "BifurcationCurves", "locate_bifurcations",
           "join_curves", "curves_for_map", "windows_around", "LABELS"]

LABELS = ("LP", "PD")


@dataclass(frozen=True)
class Curve:
    """One bifurcation family: ``label`` (LP / PD), the load factors, torques [N m],
    twists [rad] and speeds [rpm] of its points in increasing load."""
    label: str
    scale: np.ndarray
    torque: np.ndarray
    twist: np.ndarray
    rpm: np.ndarray


@dataclass(frozen=True)
class LoadBifurcations:
    """The LP / PD points of the period-1 branch at one load: ``points`` ((label, rpm)
    sorted by speed), the windows traced, the branch points, flows and wall time."""
    scale: float
    windows: tuple
    points: tuple
    messages: tuple
    branch_points: int
    flows: int
    wall_time: float


@dataclass(frozen=True, eq=False)
class BifurcationCurves:
    loads: tuple                    # LoadBifurcations, in increasing load
    curves: tuple                   # Curve
    torque_nominal: float
    twist_nominal: float
    wall_time: float
    method: str = ("bifurcation points located on one-parameter branches (continuation in "
                   "speed) at a sequence of loads and joined; not a two-parameter continuation")

    def summary(self) -> dict:
        return {
            "method": self.method, "wall_s": self.wall_time,
            "loads": [{"torque_N_m": ld.scale * self.torque_nominal,
                       "twist_rad": ld.scale * self.twist_nominal,
                       "windows_rpm": [list(w) for w in ld.windows],
                       "points": [{"label": lab, "rpm": p} for lab, p in ld.points],
                       "branch_points": ld.branch_points, "flows": ld.flows,
                       "wall_s": ld.wall_time, "messages": list(ld.messages)}
                      for ld in self.loads],
            "curves": [{"label": c.label, "rpm": [float(x) for x in c.rpm],
                        "torque_N_m": [float(x) for x in c.torque]} for c in self.curves],
        }


def windows_around(speeds, margin: float, bounds) -> tuple:
    """Windows [lo, hi] of ``margin`` around each cluster of ``speeds`` (speeds closer than
    2 margin share one), clipped to ``bounds``."""
    s = np.sort(np.asarray(speeds, dtype=float))
    if s.size == 0:
        return ()
    cuts = np.flatnonzero(np.diff(s) > 2.0 * margin) + 1
    out = []
    for part in np.split(s, cuts):
        lo, hi = max(bounds[0], part[0] - margin), min(bounds[1], part[-1] + margin)
        if hi > lo:
            out.append((float(lo), float(hi)))
    return tuple(out)


def _distinct(pts, tol: float = 0.1) -> tuple:
    """(label, rpm) sorted by speed, a point within ``tol`` rpm of one of the same label
    kept once (the solver can locate one PD from both sides of a turn)."""
    out: list = []
    for lab, p in sorted(pts, key=lambda x: x[1]):
        if not any(lab == q_lab and abs(p - q) < tol for q_lab, q in out):
            out.append((lab, p))
    return tuple(out)


def _trace_window(model, lo, hi, *, integration, tol, steps, transient_periods, period_tol):
    """(points [(label, rpm)], message, branch points, flows) of the period-1 branch over
    [lo, hi], started at hi."""
    u_static = start_state(model, hi, strict=False)
    u0, _, guess, how = starting_orbit(model, hi, u_static, transient_periods=transient_periods,
                                       options=integration, tol=tol,
                                       max_iter=3 * steps.get("max_corrector_iter", 8),
                                       max_period=1, period_tol=period_tol)
    if u0 is None:
        return [], f"[{lo:.6g}, {hi:.6g}] rpm: no period-1 orbit at {hi:.6g} rpm: {how}", 0, 0
    scale = (hi - lo) / max(float(np.linalg.norm(guess)), 1e-300)
    problem = PeriodicOrbitProblem(model, u0, hi, n_periods=1, direction=-1)
    method = PseudoArclength(integration=integration, tol=tol, param_scale=scale)
    options = ContinuationOptions(param_min=lo, param_max=hi, period_doubling_branch=False,
                                  **steps)
    res = continuation(problem, method, options)
    pts = [(s.label, float(s.param)) for s in res.special_points
           if s.branch == 0 and s.label in LABELS]
    n = len(res.branches[0].points) if res.branches else 0
    return pts, f"[{lo:.6g}, {hi:.6g}] rpm: {res.message}", n, int(res.counters.get("flows", 0))


def _window_unit(model, kw, window, _emit):
    """One window, with the retry of an odd number of LPs (module docstring)."""
    lo, hi = window
    steps = kw["steps"]
    p, msg, n, f = _trace_window(model, lo, hi, **kw)
    if sum(1 for lab, _ in p if lab == "LP") % 2:
        half = {**steps, "ds": 0.5 * steps["ds"], "ds_max": 0.5 * steps["ds_max"],
                "max_points": 2 * steps["max_points"]}
        p2, msg2, n2, f2 = _trace_window(model, lo, hi, **{**kw, "steps": half})
        n, f = n + n2, f + f2
        if sum(1 for lab, _ in p2 if lab == "LP") % 2 == 0:
            p, msg = p2, f"{msg2} (traced again at half the step: an odd number of LPs)"
        else:
            msg = f"{msg}; an odd number of LPs, also at half the step: a fold may be missing"
    return p, msg, n, f


def _run_windows(model, kw, windows, workers, split=None):
    """The windows of one load: work units on local processes (``workers``, None: all
    cores) or on every MPI rank (collective: every rank gets every window's result, so every
    rank places the next load's windows alike).  ``split``: a
    :class:`~vibrogear.pipeline.wall_split.WallSplit` that times them (phase ``curves``)."""
    fn = partial(_window_unit, model, kw)
    if (len(windows) == 1 or workers == 1) and not under_mpi():
        t0 = time.perf_counter()
        out = [fn(w, None) for w in windows]
        if split is not None:
            split.add("curves", time.perf_counter() - t0, [time.perf_counter() - t0], 1)
        return out
    if split is not None:
        return split.run("curves", fn, list(windows), workers=workers)
    return run_units(fn, list(windows), workers=workers)


def locate_bifurcations(model, scaling: LoadScaling, scales, first_window, *, margin: float,
                        integration, tol: float, steps: dict, transient_periods: int = 200,
                        period_tol: float = 1e-4, callback=None, workers=None,
                        split=None) -> tuple:
    """:class:`LoadBifurcations` per load factor in ``scales`` (returned in increasing
    load), visiting the loads outward from the one nearest 1 (module docstring).
    ``steps``: the :class:`~vibrogear.config.options.ContinuationSteps` fields (rpm);
    ``workers``: local processes for the windows of one load (None: all cores); under MPI
    collective (every rank calls it and gets the same result).  ``split``: a
    :class:`~vibrogear.pipeline.wall_split.WallSplit` that times the windows."""
    scales = np.sort(np.asarray(scales, dtype=float).ravel())
    k0 = int(np.argmin(np.abs(scales - 1.0)))
    bounds = (float(first_window[0]), float(first_window[1]))
    found: dict = {}
    kw = dict(integration=integration, tol=tol, steps=dict(steps),
              transient_periods=transient_periods, period_tol=period_tol)

    def visit(k, windows):
        t0 = time.perf_counter()
        m = scaling.model_at(model, scales[k])
        pts, msgs, npts, flows = [], [], 0, 0
        for p, msg, n, f in _run_windows(m, kw, windows, workers, split):
            pts += p
            msgs.append(msg)
            npts += n
            flows += f
        pts = _distinct(pts)
        found[k] = LoadBifurcations(scale=float(scales[k]), windows=tuple(windows), points=pts,
                                    messages=tuple(msgs), branch_points=npts, flows=flows,
                                    wall_time=time.perf_counter() - t0)
        if callback is not None:
            callback(found[k])
        # the next load's windows: around these points (else the same windows again)
        return windows_around([p for _, p in pts], margin, bounds) or tuple(windows)

    start = visit(k0, (bounds,))
    for order in (range(k0 + 1, scales.size), range(k0 - 1, -1, -1)):
        windows = start
        for k in order:
            windows = visit(k, windows)
    return tuple(found[k] for k in range(scales.size))


def _align(prev, new, max_jump: float) -> list:
    """Order-preserving pairs (i, j) of two sorted speed lists with the least total distance
    (a point left unpaired costs ``max_jump``; pairs farther apart are not allowed): the
    curves of one label do not cross between two loads."""
    n, m = len(prev), len(new)
    cost = np.full((n + 1, m + 1), np.inf)
    cost[0, :] = max_jump * np.arange(m + 1)
    cost[:, 0] = max_jump * np.arange(n + 1)
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            d = abs(prev[i - 1] - new[j - 1])
            pair = cost[i - 1, j - 1] + d if d <= max_jump else np.inf
            cost[i, j] = min(pair, cost[i - 1, j] + max_jump, cost[i, j - 1] + max_jump)
    pairs, i, j = [], n, m
    while i > 0 and j > 0:
        d = abs(prev[i - 1] - new[j - 1])
        if d <= max_jump and cost[i, j] == cost[i - 1, j - 1] + d:
            pairs.append((i - 1, j - 1))
            i, j = i - 1, j - 1
        elif cost[i, j] == cost[i - 1, j] + max_jump:
            i -= 1
        else:
            j -= 1
    return pairs[::-1]


def join_curves(loads, scaling: LoadScaling, max_jump: float) -> tuple:
    """Join the points of successive loads per label: the order-preserving pairing with the
    least total speed change (:func:`_align`, pairs within ``max_jump`` rpm); a point
    without a partner starts a new curve, a curve without one ends (a cusp, or the family
    left the window)."""
    curves: list = []           # [label, [(scale, rpm)], open]
    for ld in loads:
        for label in LABELS:
            speeds = sorted(p for lab, p in ld.points if lab == label)
            open_ = sorted((c for c in curves if c[0] == label and c[2]),
                           key=lambda c: c[1][-1][1])
            pairs = _align([c[1][-1][1] for c in open_], speeds, max_jump)
            for i, j in pairs:
                open_[i][1].append((ld.scale, speeds[j]))
            for i in set(range(len(open_))) - {i for i, _ in pairs}:
                open_[i][2] = False
            for j in set(range(len(speeds))) - {j for _, j in pairs}:
                curves.append([label, [(ld.scale, speeds[j])], True])
    out = []
    for label, pts, _ in curves:
        sc = np.array([p[0] for p in pts])
        out.append(Curve(label=label, scale=sc, torque=scaling.torque(sc),
                         twist=scaling.twist(sc), rpm=np.array([p[1] for p in pts])))
    return tuple(out)


def curves_for_map(study: Study, scene, scaling: LoadScaling, scales,
                   split=None) -> BifurcationCurves:
    """The curves over the loads of a [map] (its speed range is the first window); under
    MPI collective, every rank computing windows."""
    cfg = scene.map
    t0 = time.perf_counter()
    steps = dict(ds=cfg.curve_ds, ds_min=min(1e-3, cfg.curve_ds), ds_max=cfg.curve_ds_max,
                 max_points=cfg.curve_max_points)
    loads = locate_bifurcations(study.model, scaling, scales, (cfg.rpm_min, cfg.rpm_max),
                                margin=cfg.curve_margin,
                                integration=integration_options(scene, study=study),
                                tol=scene.shooting.tol, steps=steps,
                                transient_periods=cfg.curve_transient_periods,
                                period_tol=cfg.period_tol, workers=cfg.workers, split=split)
    return BifurcationCurves(loads=loads, curves=join_curves(loads, scaling, 2 * cfg.curve_margin),
                             torque_nominal=scaling.torque_nominal,
                             twist_nominal=scaling.twist_nominal,
                             wall_time=time.perf_counter() - t0)
