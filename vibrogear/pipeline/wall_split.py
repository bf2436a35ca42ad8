"""An analysis's wall time split into its parallel part (work units on processes or MPI ranks)
and its serial part (what the coordinating process does alone before, between and after them),
as ``summary.json`` reports it, and the speed-up it allows on more workers.

:class:`WallSplit` runs each parallel phase through
:func:`~vibrogear.pipeline.executors.run_units`, timing every unit where it runs; its
:meth:`~WallSplit.summary` is the summary entry's part::

    parallel_wall_s   wall of the phases that ran as work units (rank 0's clock)
    serial_wall_s     the rest of the analysis's wall time: one process alone
    serial_part       what that serial part is, in words
    workers           the workers (processes or ranks) of the parallel phases
    parallel_phases   per phase: wall_s, units, unit_work_s (the units' walls summed),
                      largest_unit_s

:func:`project` turns that into the wall time on W workers: Amdahl's law with the serial part
and the units' granularity.  Each phase is a barrier (the serial part after it needs all its
units); its units are handed out dynamically, longest first, so on W workers a phase of unit
walls t_u takes at least ``max(sum(t_u) / W, max(t_u))`` (the last unit cannot be shared) and
at most ``sum(t_u) / W + (1 - 1/W) max(t_u)`` (Graham's bound for list scheduling); with no
more units than workers, exactly ``max(t_u)``.  The
wall on one worker is ``serial + sum over phases of sum(t_u)``, so the projected speed-up is::

    S(W) = (serial + sum_p work_p) / (serial + sum_p max(work_p / W, largest_p))

(lower bound of the wall, hence the upper end of the speed-up; the upper bound of the wall
gives the lower end).  Unit walls are measured on the machine at hand: a loaded machine
inflates them all alike, which the ratio mostly cancels; it cancels no per-unit overhead of a
bigger machine (MPI messages), which this model leaves out.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

from .executors import effective_workers, run_units

__all__ = ["WallSplit", "Phase", "project", "simulate"]


@dataclass
class Phase:
    """One parallel phase as measured: its wall, its units' count, summed and largest wall."""
    name: str
    wall_s: float
    units: int
    unit_work_s: float
    largest_unit_s: float
    workers: int
    #: {part: {"units", "unit_work_s", "largest_unit_s"}} where the phase mixes kinds of unit
    parts: dict | None = None

    def as_dict(self) -> dict:
        out = {"name": self.name, "wall_s": round(self.wall_s, 4), "units": self.units,
               "unit_work_s": round(self.unit_work_s, 4),
               "largest_unit_s": round(self.largest_unit_s, 4), "workers": self.workers}
        if self.parts:
            out["parts"] = {k: {"units": v["units"], "unit_work_s": round(v["unit_work_s"], 4),
                                "largest_unit_s": round(v["largest_unit_s"], 4)}
                            for k, v in self.parts.items()}
        return out


class _Timed:
    """``fn(unit, emit)`` returning (its value, its wall seconds), where it ran."""

    def __init__(self, fn):
        self.fn = fn

    def __call__(self, unit, emit):
        t0 = time.perf_counter()
        out = self.fn(unit, emit)
        return out, time.perf_counter() - t0


class _Untimed:
    """``on_done(i, value)`` called with fn's own value out of :class:`_Timed`'s pair;
    ``added``: the units it added, in the order run_units numbers them."""

    def __init__(self, on_done):
        self.on_done, self.added = on_done, []

    def __call__(self, i, got):
        new = list(self.on_done(i, got[0]) or ())
        self.added += [u for u, _c in new]
        return new


class WallSplit:
    """The wall clock of one analysis from its creation; :meth:`run` adds a parallel phase.
    ``serial_part``: what the analysis does on one process (set or extended later with
    :meth:`describe`)."""

    def __init__(self, serial_part: str = ""):
        self.start = time.perf_counter()
        self.phases: list[Phase] = []
        self.serial_part = serial_part

    def describe(self, text: str) -> None:
        self.serial_part = text

    def run(self, name: str, fn, units, *, workers=None, kind=None, on_done=None, **kw) -> list:
        """:func:`~vibrogear.pipeline.executors.run_units` (same arguments, same return
        value: fn's values in unit order, added units included), timed as the phase
        ``name``; the units ``on_done`` adds count in this phase, timed as the others, and
        ``on_done`` gets fn's own value.  Collective under MPI, as run_units is; an empty
        list of units is no phase.  ``kind(unit) -> str`` names the part of the phase each
        unit belongs to: the phase then reports each part's units, work and largest unit
        (``parts``), and :meth:`work_by_kind` their work."""
        units = list(units)
        if not units:
            return []
        done = None if on_done is None else _Untimed(on_done)
        t0 = time.perf_counter()
        got = run_units(_Timed(fn), units, workers=workers, on_done=done, **kw)
        wall = time.perf_counter() - t0
        walls = [g[1] for g in got if g is not None]
        parts = None
        if kind is not None:
            parts = {}
            every = units + (done.added if done is not None else [])
            for u, g in zip(every, got):
                if g is not None:
                    parts.setdefault(kind(u), []).append(g[1])
        self.add(name, wall, walls, effective_workers(len(units), workers, done is not None),
                 parts=parts)
        return [None if g is None else g[0] for g in got]

    def work_by_kind(self, name: str) -> dict:
        """{part: summed unit wall} of phase ``name`` (empty without parts)."""
        for p in self.phases:
            if p.name == name:
                return {k: v["unit_work_s"] for k, v in (p.parts or {}).items()}
        return {}

    def add(self, name: str, wall_s: float, unit_walls, workers: int, parts=None) -> None:
        """Record a phase measured elsewhere (its units' walls; phases of one name add up;
        ``parts``: {part: its units' walls})."""
        unit_walls = [float(w) for w in unit_walls]
        summed = None if parts is None else {
            k: {"units": len(v), "unit_work_s": float(sum(v)),
                "largest_unit_s": float(max(v, default=0.0))} for k, v in parts.items()}
        for p in self.phases:
            if p.name == name:
                p.wall_s += float(wall_s)
                p.units += len(unit_walls)
                p.unit_work_s += sum(unit_walls)
                p.largest_unit_s = max([p.largest_unit_s, *unit_walls])
                p.workers = max(p.workers, int(workers))
                if summed and p.parts is None:
                    p.parts = {}
                for k, v in (summed or {}).items():
                    q = p.parts.setdefault(k, {"units": 0, "unit_work_s": 0.0,
                                               "largest_unit_s": 0.0})
                    q["units"] += v["units"]
                    q["unit_work_s"] += v["unit_work_s"]
                    q["largest_unit_s"] = max(q["largest_unit_s"], v["largest_unit_s"])
                return
        self.phases.append(Phase(name, float(wall_s), len(unit_walls), sum(unit_walls),
                                 max(unit_walls, default=0.0), int(workers), summed))

    def summary(self) -> dict:
        total = time.perf_counter() - self.start
        par = sum(p.wall_s for p in self.phases)
        return {"parallel_wall_s": round(par, 4), "serial_wall_s": round(max(total - par, 0.0), 4),
                "serial_part": self.serial_part,
                "workers": max((p.workers for p in self.phases), default=1),
                "parallel_phases": [p.as_dict() for p in self.phases]}


def project(entry: dict, workers: int) -> dict:
    """The wall time and speed-up on ``workers`` workers from a summary entry's split (the
    module docstring's model): ``{"workers", "one_worker_s", "wall_s": [lower, upper],
    "speedup": [lower, upper], "amdahl_speedup"}``, where ``amdahl_speedup`` is Amdahl's law
    with the serial part alone (units infinitely fine), for comparison."""
    w = int(workers)
    if w < 1:
        raise ValueError(f"project: workers must be >= 1, got {workers}")
    serial = float(entry["serial_wall_s"])
    phases = entry.get("parallel_phases") or []
    work = sum(float(p["unit_work_s"]) for p in phases)
    lo = hi = serial
    for p in phases:
        pw, big = float(p["unit_work_s"]), float(p["largest_unit_s"])
        if int(p.get("units", w + 1)) <= w:     # a worker for every unit: the largest
            lo, hi = lo + big, hi + big
        else:
            lo, hi = lo + max(pw / w, big), hi + pw / w + (1.0 - 1.0 / w) * big
    one = serial + work
    amdahl = one / (serial + work / w) if serial + work / w > 0 else 1.0
    return {"workers": w, "one_worker_s": one, "wall_s": [lo, hi],
            "speedup": [one / hi if hi > 0 else 1.0, one / lo if lo > 0 else 1.0],
            "amdahl_speedup": amdahl}


def simulate(first, run, workers: int, *, on_result=None, on_done=None) -> dict:
    """The wall time of a run of work units on ``workers`` workers, replayed from the units'
    measured walls: a discrete-event copy of :func:`~vibrogear.pipeline.executors.run_units`'s
    dispatch (the pending unit with the highest cost first, ties in index order, each to
    the first free worker) with its ``on_done`` units, so that units that depend on others
    (the census's orbits and branches) start when they would.

    ``first``: the first units as (unit, cost); ``run(unit) -> (items, value, wall_s)``: a
    unit's emitted items, its value and its wall (measured, or computed now);
    ``on_result(i, item)`` and ``on_done(i, value) -> [(unit, cost)]`` as run_units's,
    called in simulated time.  The coordinator's own time in them (measured here with the
    real calls) delays the units they add, one call after the other (one coordinating
    process).  Returns {"wall_s", "units", "unit_work_s", "coordinator_s", "idle_s" (workers'
    idle time before the end)}."""
    import heapq
    import itertools

    w = int(workers)
    if w < 1:
        raise ValueError(f"simulate: workers must be >= 1, got {workers}")
    units, seq = [], itertools.count()
    pending: list = []                  # (release time, -cost, index) not yet released
    ready: list = []                    # (-cost, index) released
    running: list = []                  # (finish time, index)
    values: dict = {}

    def add(pairs, at):
        for u, c in pairs or ():
            i = next(seq)
            units.append(u)
            heapq.heappush(pending, (at, -float(c), i))

    add(first, 0.0)
    t = coord = work = coord_total = 0.0
    busy = 0
    while pending or ready or running:
        while pending and pending[0][0] <= t:
            _at, c, i = heapq.heappop(pending)
            heapq.heappush(ready, (c, i))
        while ready and busy < w:
            _c, i = heapq.heappop(ready)
            items, value, wall = run(units[i])
            values[i] = (items, value)
            work += float(wall)
            heapq.heappush(running, (t + float(wall), i))
            busy += 1
        nxt = [x for x in (running[0][0] if running else None,
                           pending[0][0] if pending else None) if x is not None]
        if not nxt:
            break
        t = max(t, min(nxt))
        if running and running[0][0] <= t:
            _ft, i = heapq.heappop(running)
            busy -= 1
            items, value = values.pop(i)
            t0 = time.perf_counter()
            for item in items:
                if on_result is not None:
                    on_result(i, item)
            new = on_done(i, value) if on_done is not None else None
            spent = time.perf_counter() - t0
            coord = max(coord, t) + spent
            coord_total += spent
            add(new, coord)
    return {"wall_s": t, "units": len(units), "unit_work_s": work,
            "coordinator_s": coord_total, "idle_s": max(w * t - work, 0.0)}
