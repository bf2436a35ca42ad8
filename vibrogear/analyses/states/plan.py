"""The census's work as one stream of units: the starts, each periodic attractor's orbit and
the branches continued from them start as soon as what they need is there, not after the
whole census (the scheduling rule and what it gives: docs/states.md, "One stream of units").

:class:`CensusPlan` is the coordinator's side (rank 0 under MPI, the parent process
otherwise).  It hands :func:`~vibrogear.pipeline.executors.run_units` its first units and
answers each finished unit with the units it made possible (``on_done``):

1. **Starts** (``("start", i, param, starts, scales)``): one grid value and a batch of its
   starts.  Once every unit of a grid value's round is in, the value is grouped
   (:func:`~.cluster.cluster_point`); with ``basin_tol`` it either stops there or gets its
   next round of starts (each value's rounds run on their own: the outcome is the same as
   rounds in step for all values, since a value's decision reads its own starts only).
2. **Orbits** (``("orbit", i, j, param, u0, n)``): each periodic attractor of a grouped
   value, shot over its n periods (its exact extrema, its Floquet multipliers).
3. **Half-branches** (``("half", c, u0, param, n, sign, scale)``): once every grid value up
   to an attractor's (in grid order) is grouped and shot, the attractor is a candidate;
   candidates are taken in grid order, each one that no branch known so far passes through
   (this run's continuation, then those kept here) gets two half-branch units.  At most
   ``per_wave`` candidates are out at a time (half the workers: each has two halves).  When
   a candidate's halves are back and every candidate before it is settled, it is kept unless
   a branch kept before it passes through it (its halves were then work done early, on a
   worker that had nothing else to do).  So the kept branches, their notes and their order
   are those of one candidate after the other, for any number of workers and any timing.

Urgency sets the dispatch: orbits first (they free candidates), then half-branches (the
longest units), then starts in grid order (the first grid values are grouped first).  The
units' results never depend on where or when they ran.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ...config.options import SweepOptions
from ...pipeline.executors import effective_workers, unit_size
from ...solvers.sequential.record_json import record_to_json
from ...solvers.sequential.sweep_point import run_point
from ..sweep.branches import on_branch
from .branches import half_branch, shoot_orbit
from .cluster import cluster_point, interval_widths
from .starts import draw_start

__all__ = ["CensusPlan", "work_unit", "unit_kind", "UnitContext"]

#: dispatch urgency (run_units costs: higher first); starts add their grid position below
_ORBIT, _HALF = 3e9, 2e9


@dataclass(frozen=True)
class UnitContext:
    """What every unit needs, fixed for the run (travels to the workers with ``work_unit``)."""
    model: object
    settings: SweepOptions          # the settled start's sweep settings
    options: object                 # integration options of a start
    seed: int
    orbit_options: object           # integration options of an orbit / a branch
    shooting: object                # ShootingOptions
    continuation: object | None     # ContinuationOptions of the branches (None: no branches)


def work_unit(ctx: UnitContext, unit, emit):
    """Run one unit (module docstring) where it was handed out."""
    kind = unit[0]
    if kind == "start":
        _, i, p, ks, scales = unit
        for k in ks:
            u = draw_start(scales, ctx.model, ctx.seed, i, k)
            rec = run_point(ctx.model, float(p), u, "start", int(k), ctx.settings,
                            options=ctx.options, keep_states=True)
            emit((int(i), _compact(rec)))
        return len(ks)
    if kind == "orbit":
        _, _i, _j, p, u0, n = unit
        return shoot_orbit(ctx.model, ctx.orbit_options, ctx.shooting, p, u0, n)
    if kind == "half":
        _, _c, u0, p, n, sign, scale = unit
        return half_branch(ctx.model, ctx.orbit_options, ctx.shooting.tol, ctx.continuation,
                           u0, p, n, sign, scale)
    raise ValueError(f"unknown work unit {kind!r}")


def unit_kind(unit) -> str:
    """The phase a unit belongs to in the wall split: census, orbits or branches."""
    return {"start": "census", "orbit": "orbits", "half": "branches"}[unit[0]]


def _compact(rec):
    """A settled start as kept: the cycle (last n stroboscopic states) of a periodic one,
    no states otherwise."""
    import dataclasses
    n = int(rec.period_n)
    st = rec.states
    keep = np.array(st[-n:], dtype=float) if (n > 0 and st is not None) else None
    return dataclasses.replace(rec, states=keep)


class CensusPlan:
    """The coordinator of one census (module docstring).  ``done``: {(i, k): record} settled
    before (resumed); ``store``: the partial file each new record is appended to;
    ``progress(i, record)``: called per new record; ``known``: branches of this run's
    continuation; ``workers``: as the section says (None: all cores)."""

    def __init__(self, study, cfg, params, scales, ctx: UnitContext, *, done=None, store=None,
                 progress=None, known=(), workers=None):
        self.study, self.cfg, self.ctx = study, cfg, ctx
        self.params = np.asarray(params, float)
        self.scales = scales
        self.done = dict(done or {})
        self.store, self.progress = store, progress
        self.known = list(known)
        P = len(self.params)
        self.order = [int(i) for i in np.argsort(self.params, kind="stable")]
        self.rank = {i: r for r, i in enumerate(self.order)}
        self.round_size = cfg.batch if cfg.basin_tol is not None else cfg.starts
        self.upto = [0] * P                  # starts asked for so far, per grid value
        self.rounds = [0] * P
        self.open = [0] * P                  # a value's units not yet back (census, orbits)
        self.early: list[tuple[int, int]] = []   # (round, grid index) stopped early
        #: per grid value, once grouped: (attractors, starts settled, starts failed)
        self.attractors: list[tuple | None] = [None] * P
        self.ready = [False] * P             # grouped and shot
        self.frontier = 0                    # values ready in grid order (self.order)
        self.candidates: list = []           # (attractor) in grid order, not yet taken
        self.out: list[dict] = []            # taken candidates, not yet settled, in order
        self.found, self.notes = [], []
        self.taken = 0                       # candidates taken so far (their ids)
        self.units: list = []                # every unit handed out, by run_units index
        self.clustering_s = 0.0
        self.new = 0
        self.w = effective_workers(1 << 20, workers)
        self.per_wave = max(1, (self.w + 1) // 2)
        self.size = None
        lo, hi = float(cfg.param_min), float(cfg.param_max)
        self.branches_on = bool(cfg.branches) and ctx.continuation is not None and hi > lo
        if cfg.branches and not hi > lo:
            self.notes.append({"note": "one grid value: no range to continue in"})
        elif cfg.branches and study.model.multi_frequency:
            self.notes.append({"note": "multi-frequency forcing (no common excitation period "
                               "within the period limit): no periodic orbit to continue"})
        self.scale_range = hi - lo

    # ------------------------------------------------------------ units

    def _add(self, new: list) -> list:
        self.units += [u for u, _c in new]
        return new

    def start(self) -> list:
        """The first units as (unit, cost); values already settled (resumed) are grouped
        now."""
        todo = {i: self._next_round(i) for i in range(len(self.params))}
        n_todo = sum(len(v) for v in todo.values())
        self.size = self.cfg.batch if self.w == 1 else unit_size(n_todo, self.w, self.cfg.batch)
        new = []
        for i in self.order:
            new += self._start_units(i, todo[i]) if todo[i] else self._round_done(i)
        return self._add(new)

    def _next_round(self, i) -> list[int]:
        """The next round's starts of grid value i not settled yet (ks)."""
        lo = self.upto[i]
        self.upto[i] = min(lo + self.round_size, self.cfg.starts)
        self.rounds[i] += 1
        return [k for k in range(self.upto[i]) if (i, k) not in self.done]

    def _start_units(self, i, ks) -> list:
        cost = float(len(self.params) - self.rank[i])
        out = [(("start", i, float(self.params[i]), tuple(ks[a:a + self.size]), self.scales[i]),
                cost) for a in range(0, len(ks), self.size)]
        self.open[i] += len(out)
        self.new += len(ks)
        return out

    def on_result(self, _u, item) -> None:
        """A settled start (grid index, record) as it arrives."""
        i, rec = item
        self.done[(i, int(rec.index))] = rec
        if self.store is not None:
            self.store.append({"point": i, **record_to_json(rec)})
        if self.progress is not None:
            self.progress(i, rec)

    def on_done(self, u, value) -> list:
        """A finished unit; returns the units it made possible, as (unit, cost)."""
        unit = self.units[u]
        kind, i = unit[0], unit[1]
        if kind == "start":
            self.open[i] -= 1
            return self._add(self._round_done(i) if self.open[i] == 0 else [])
        if kind == "orbit":
            self._orbit_back(unit, value)
            self.open[i] -= 1
            if self.open[i] == 0:
                self.ready[i] = True
            return self._add(self._advance())
        cand = self.out[[c["id"] for c in self.out].index(unit[1])]
        cand["halves"][0 if unit[5] < 0 else 1] = value
        return self._add(self._settle())

    def _records(self, i, upto=None):
        return [r for (j, k), r in sorted(self.done.items()) if j == i
                and (upto is None or k < upto)]

    def _round_done(self, i) -> list:
        """Every unit of grid value i's round is back: its next round, or its grouping and
        its orbits' units."""
        cfg = self.cfg
        if self.upto[i] < cfg.starts:           # rounds (basin_tol): narrow enough yet?
            t0 = time.perf_counter()
            atts, _, _ = cluster_point(self._records(i, self.upto[i]), i, self.params[i],
                                       n_modes=self.study.model.n_modes,
                                       cluster_tol=cfg.cluster_tol, stat_tol=cfg.stat_tol)
            self.clustering_s += time.perf_counter() - t0
            if interval_widths(atts) >= cfg.basin_tol:
                ks = self._next_round(i)
                if ks:
                    return self._start_units(i, ks)
                return self._round_done(i)
            self.early.append((self.rounds[i], i))
        t0 = time.perf_counter()
        self.attractors[i] = cluster_point(self._records(i), i, self.params[i],
                                           n_modes=self.study.model.n_modes,
                                           cluster_tol=cfg.cluster_tol, stat_tol=cfg.stat_tol)
        self.clustering_s += time.perf_counter() - t0
        out = []
        if not self.study.model.multi_frequency:
            for j, a in enumerate(self.attractors[i][0]):
                if a.period_n > 0 and a.u0 is not None:
                    out.append((("orbit", i, j, a.param, a.u0, a.period_n), _ORBIT + a.period_n))
        self.open[i] += len(out)
        if not out:
            self.ready[i] = True
            return self._advance()
        return out

    def _orbit_back(self, unit, item) -> None:
        _, i, j, *_ = unit
        ok, u0, qmin, qmax, stable, mu = item
        if ok:
            a = self.attractors[i][0][j]
            a.refined, a.qmin, a.qmax, a.u0 = True, qmin, qmax, u0
            a.qmin_err = a.qmax_err = 0.0
            a.stable, a.max_multiplier = stable, mu

    # ------------------------------------------------------------ branches

    def _advance(self) -> list:
        """Grid values ready in grid order add their periodic attractors as candidates."""
        while self.frontier < len(self.order) and self.ready[self.order[self.frontier]]:
            i = self.order[self.frontier]
            self.frontier += 1
            if self.branches_on:
                self.candidates += [a for a in sorted(self.attractors[i][0],
                                                      key=lambda a: -a.count)
                                    if a.period_n > 0 and a.refined]
        return self._take()

    def _passes(self, a) -> bool:
        return on_branch(self.known + self.found, a.period_n, a.param, a.qmax, 1e-3)

    def _take(self) -> list:
        """Candidates in grid order, up to ``per_wave`` out at a time: two half units each,
        skipping those a branch kept so far passes through."""
        new = []
        while self.candidates and len(self.out) < self.per_wave:
            a = self.candidates.pop(0)
            if self._passes(a):
                continue
            cid, self.taken = self.taken, self.taken + 1
            self.out.append({"id": cid, "attractor": a, "halves": [None, None]})
            scale = self.scale_range / max(float(np.linalg.norm(a.u0)), 1e-300) \
                if self.study.balance_arclength else 1.0
            for sign in (-1, 1):
                new.append((("half", cid, a.u0, a.param, a.period_n, sign, scale),
                            _HALF + a.period_n))
        return new

    def _settle(self) -> list:
        """Candidates whose halves are back, in order: kept unless a branch kept before
        passes through (module docstring)."""
        name = self.study.param_name
        while self.out and all(h is not None for h in self.out[0]["halves"]):
            cand = self.out.pop(0)
            a = cand["attractor"]
            if self._passes(a):
                continue
            item = {name: a.param, "period_n": a.period_n, "qmax": a.qmax, "stable": a.stable,
                    "halves": []}
            for br in cand["halves"]:
                item["halves"].append({"branch": len(self.found), "points": len(br.points),
                                       "status": br.status.text, "message": br.message,
                                       "special_points": [
                                           {"label": p.label, name: float(p.param)}
                                           for p in br.points if p.label]})
                if br.points:
                    self.found.append(br)
            self.notes.append(item)
        return self._take()

    # ------------------------------------------------------------ the end

    def finished(self) -> bool:
        return all(self.ready) and not self.candidates and not self.out

    def census_info(self) -> dict:
        """{"rounds", "new", "stopped_early"} as the summary reports them."""
        return {"rounds": max(self.rounds, default=0), "new": self.new,
                "stopped_early": [i for _r, i in sorted(self.early)]}

    def by_point(self) -> dict:
        return {i: self._records(i) for i in range(len(self.params))}
