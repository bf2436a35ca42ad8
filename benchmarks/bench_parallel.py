"""The parallel analyses' wall split (parallel units / serial part) and the speed-up it allows
on 16 and 64 workers, serial part and unit granularity included (docs/performance.md,
"Parallel runs: what is serial and what the split projects").

Measured here, each once, on ``--workers`` worker processes:

* ``states`` on gear_pair over the issue's grid (11 speeds, 4900-5400 rpm) with ``--starts``
  starts per speed (the issue's 32 by default) and branches on, first on one worker with
  every work unit recorded (each start's wall, each orbit's and half-branch's), then on
  ``--workers`` workers for real (same result required).  The recorded units are then
  replayed on 1, ``--workers``, 16 and 64 workers (:func:`vibrogear.pipeline.wall_split.simulate`:
  run_units's dispatch, longest first, with the census's own plan adding the orbits and
  branches as their starts come in); the wall on W workers is the replay plus the run's
  serial part, and the speed-up is against the replay on one worker.  The replay on
  ``--workers`` workers is checked against the real run of that many;
* ``sweep`` on gear_pair, ``--sweep-points`` speeds up and down in ``--segments`` segments;
* ``map`` on gear_pair, 2 loads x ``--map-speeds`` speeds, curves off.

Each run's ``summary.json`` entry holds ``parallel_wall_s``, ``serial_wall_s`` and its phases
(units, summed and largest unit wall); for the sweep and the map
:func:`vibrogear.pipeline.wall_split.project` turns them into the wall and speed-up on W
workers: serial + sum over phases of max(work / W, largest unit) (the speed-up's upper end)
and Graham's bound serial + work / W + (1 - 1/W) largest unit (its lower end).  Projections
are written as such, with the load average at each measurement.

Run: .venv/bin/python benchmarks/bench_parallel.py [--starts 32 --workers 2]
Writes benchmarks/results/bench_parallel.json.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from vibrogear.config import load_scene  # noqa: E402
from vibrogear.pipeline.outcome import RunContext  # noqa: E402
from vibrogear.pipeline.wall_split import project  # noqa: E402
from vibrogear.runner import run_scene  # noqa: E402

SCENE = ROOT / "configs" / "gear_pair.toml"
FULL_STARTS = 32                 # the census: 11 speeds x 32 starts
PROJECT_AT = (16, 64)


def _load() -> float:
    return round(os.getloadavg()[0], 2)


def _run(name: str, sets, out: Path) -> dict:
    scene = load_scene(SCENE, (f'scene.analyses=["{name}"]', *sets))
    before = _load()
    t0 = time.perf_counter()
    summary = run_scene(scene, RunContext(out=out, quiet=True))
    wall = time.perf_counter() - t0
    entry = summary["results"][name]
    keys = ("parallel_wall_s", "serial_wall_s", "serial_part", "workers", "parallel_phases")
    return {"wall_s": round(summary["wall_time_s"][name], 3), "run_wall_s": round(wall, 3),
            "load_average_1min": [before, _load()], **{k: entry[k] for k in keys}}, entry


def _projections(entry: dict, workers) -> dict:
    out = {}
    for w in workers:
        p = project(entry, w)
        out[str(w)] = {"wall_s": [round(x, 2) for x in p["wall_s"]],
                       "speedup": [round(x, 2) for x in p["speedup"]],
                       "amdahl_speedup_serial_only": round(p["amdahl_speedup"], 2)}
    return out


class _Recorder:
    """``work_unit`` that keeps each unit's items, value and wall (a 1-worker run: in this
    process), keyed as :func:`_key` names them; each start's own wall is its record's."""

    def __init__(self, work_unit):
        self.work_unit, self.units = work_unit, {}

    def __call__(self, ctx, unit, emit):
        items = []

        def keep(item):
            items.append(item)
            emit(item)

        t0 = time.perf_counter()
        value = self.work_unit(ctx, unit, keep)
        wall = time.perf_counter() - t0
        if unit[0] == "start":
            for i, rec in items:
                self.units[("start", i, int(rec.index))] = ([(i, rec)], None, rec.wall_time)
        else:
            self.units[_key(unit)] = (items, value, wall)
        return value


def _key(unit):
    """A unit by what it computes (a half-branch by its start, not by its candidate's id)."""
    if unit[0] == "orbit":
        return unit[:3]
    _, _c, u0, p, n, sign, _scale = unit
    return ("half", float(p), int(n), int(sign), np.asarray(u0).tobytes())


def _replay(recorded, ctx, work_unit):
    """``run(unit)`` of :func:`~vibrogear.pipeline.wall_split.simulate`: a start unit is its
    starts' records and walls, an orbit or half-branch its recorded one; a half-branch the
    1-worker run never computed (a candidate dropped there before it was taken) is computed
    now and timed."""
    def run(unit):
        if unit[0] == "start":
            got = [recorded[("start", unit[1], int(k))] for k in unit[3]]
            return [it for g in got for it in g[0]], len(got), sum(g[2] for g in got)
        key = _key(unit)
        if key not in recorded:
            t0 = time.perf_counter()
            value = work_unit(ctx, unit, lambda _item: None)
            recorded[key] = ([], value, time.perf_counter() - t0)
            run.computed += 1
        return recorded[key]
    run.computed = 0
    return run


class _Barriers:
    """The census's plan as the code before it ran: the orbits wait for every start, the
    half-branches for every orbit (a phase each), for a replay of the same units."""

    WAIT = {"start": (), "orbit": ("start",), "half": ("start", "orbit")}

    def __init__(self, plan):
        self.plan, self.held, self.out, self.index = plan, [], {}, []

    def _pending(self, kind) -> int:
        return self.out.get(kind, 0) + sum(1 for _j, u, _c in self.held if u[0] == kind)

    def _release(self, new) -> list:
        base = len(self.plan.units) - len(new)      # the plan's indices of the new units
        self.held += [(base + k, u, c) for k, (u, c) in enumerate(new)]
        go = [e for e in self.held if all(self._pending(k) == 0 for k in self.WAIT[e[1][0]])]
        self.held = [e for e in self.held if e not in go]
        for j, u, _c in go:
            self.out[u[0]] = self.out.get(u[0], 0) + 1
            self.index.append(j)
        return [(u, c) for _j, u, c in go]

    def start(self) -> list:
        return self._release(self.plan.start())

    def on_done(self, i, value) -> list:
        j = self.index[i]
        self.out[self.plan.units[j][0]] -= 1
        return self._release(self.plan.on_done(j, value))

    def on_result(self, i, item) -> None:
        self.plan.on_result(self.index[i], item)


def _states_census(starts: int, workers: int, out: Path) -> dict:
    """The issue's census (11 speeds x ``starts``, branches on) on one worker with every
    unit recorded, on ``workers`` workers for real, and replayed on 1, ``workers``, 16 and
    64 workers (docs/performance.md)."""
    from vibrogear.analyses.states import states as states_mod
    from vibrogear.analyses.study import build_study
    from vibrogear.pipeline.wall_split import simulate

    import shutil
    shutil.rmtree(out, ignore_errors=True)      # nothing resumed: every start is measured
    sets = ('scene.analyses=["states"]', f"states.starts={starts}", "states.branches=true")
    scene1 = load_scene(SCENE, (*sets, "states.workers=1"))
    study = build_study(scene1)
    recorder = _Recorder(states_mod.work_unit)
    states_mod.work_unit = recorder
    try:
        before = _load()
        got = states_mod.run(study, scene1, RunContext(out=out / "one", quiet=True))
        one = {"load_average_1min": [before, _load()]}
    finally:
        states_mod.work_unit = recorder.work_unit
    s1 = got.summary
    one.update(wall_s=round(s1["wall_split_s"]["total_wall"], 3),
               units_wall_s=round(s1["parallel_wall_s"], 3),
               serial_wall_s=s1["serial_wall_s"], phase=s1["parallel_phases"][0],
               attractors=s1["attractors"], branches_kept=len(s1["branches"]))
    m, entry = _run("states", (*sets, f"states.workers={workers}"), out / "many")
    m["branches_kept"] = len(entry["branches"])
    same = (json.loads(json.dumps(entry["per_speed"])) == json.loads(json.dumps(s1["per_speed"]))
            and json.loads(json.dumps(entry["branches"])) == json.loads(json.dumps(s1["branches"])))
    sims, computed = {}, 0
    for w in (1, workers, *PROJECT_AT):
        plan, ctx = states_mod.census_plan(build_study(scene1), load_scene(
            SCENE, (*sets, f"states.workers={w}")))
        run = _replay(recorder.units, ctx, recorder.work_unit)
        first = plan.start()
        sim = simulate(first, run, w, on_result=plan.on_result, on_done=plan.on_done)
        computed += run.computed
        sims[w] = {"units_wall_s": round(sim["wall_s"], 3), "units": sim["units"],
                   "unit_work_s": round(sim["unit_work_s"], 3),
                   "coordinator_s": round(sim["coordinator_s"], 3),
                   "branches_kept": len(plan.notes), "same_branches": json.loads(
                       json.dumps(plan.notes)) == json.loads(json.dumps(s1["branches"]))}
    serial = float(s1["serial_wall_s"])
    t1 = serial + sims[1]["units_wall_s"]
    for w, sim in sims.items():
        sim["wall_s"] = round(serial + sim["units_wall_s"], 3)
        sim["speedup"] = round(t1 / sim["wall_s"], 2)
    before = {}
    for w in PROJECT_AT:
        plan, ctx = states_mod.census_plan(build_study(scene1), load_scene(
            SCENE, (*sets, f"states.workers={w}")))
        bar = _Barriers(plan)
        sim = simulate(bar.start(), _replay(recorder.units, ctx, recorder.work_unit), w,
                       on_result=bar.on_result, on_done=bar.on_done)
        wall = serial + sim["wall_s"]
        before[str(w)] = {"wall_s": round(wall, 3), "speedup": round(t1 / wall, 2),
                          "same_branches": json.loads(json.dumps(plan.notes)) == json.loads(
                              json.dumps(s1["branches"]))}
    return {"case": f"gear_pair states, 11 speeds x {starts} starts (4900-5400 rpm), branches "
                    "on", "one_worker": one, f"{workers}_workers": m,
            "same_result_on_both": same,
            "replayed": {"note": "a projection, not a measurement: the 1-worker run's units "
                                 "(each start's own wall, each orbit's and half-branch's) "
                                 "dispatched on W workers by a copy of run_units's rule, with "
                                 "the census's plan deciding the orbits and branches as the "
                                 "run does, plus the run's serial part; half-branches the "
                                 f"1-worker run never computed, computed here: {computed}",
                         **{str(w): v for w, v in sims.items()}},
            "replayed_in_phases": {"note": "the same units replayed with the orbits after "
                                           "every start and the branches after every orbit "
                                           "(the code before the census's one stream)",
                                   **before}}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--starts", type=int, default=FULL_STARTS, help="starts per speed")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--sweep-points", type=int, default=12)
    ap.add_argument("--segments", type=int, default=2)
    ap.add_argument("--map-speeds", type=int, default=4)
    ap.add_argument("--skip", nargs="*", default=(), choices=("states", "sweep", "map"))
    ap.add_argument("--out", default="/tmp/bench_parallel")
    ap.add_argument("--results", default="bench_parallel.json",
                    help="file name in benchmarks/results/ (e.g. for a 1-worker reference)")
    a = ap.parse_args(argv)
    out = Path(a.out)
    res = {"conditions": f"2-core machine shared with other jobs; load average (1 minute) "
                         f"before and after each run as given; {a.workers} worker processes",
           "python": platform.python_version(), "cpu_count": os.cpu_count(),
           "model": "docs/performance.md: wall(W) = serial + sum over phases of "
                    "max(work / W, largest unit) [upper end of the speed-up], Graham: serial + "
                    "work / W + (1 - 1/W) largest unit [lower end]; one worker = serial + work",
           "runs": {}}
    w = f"workers={a.workers}"
    if "states" not in a.skip:
        res["runs"]["states"] = _states_census(a.starts, a.workers, out / "states")
    if "sweep" not in a.skip:
        sets = (f"sweep.n_points={a.sweep_points}", f"sweep.segments={a.segments}",
                f"sweep.{w}")
        m, entry = _run("sweep", sets, out / "sweep")
        m["points"] = entry["points"]
        m["projection"] = _projections(m, (a.workers, *PROJECT_AT))
        res["runs"]["sweep"] = m
    if "map" not in a.skip:
        sets = (f"map.n_speeds={a.map_speeds}", "map.n_loads=2", "map.curves=false",
                f"map.{w}")
        m, entry = _run("map", sets, out / "map")
        m["points"] = entry["points"]
        m["projection"] = _projections(m, (a.workers, *PROJECT_AT))
        res["runs"]["map"] = m
    path = ROOT / "benchmarks" / "results" / a.results
    old = json.loads(path.read_text()) if path.exists() else {}
    old_runs = old.get("runs", {})
    res["runs"] = {**{k: v for k, v in old_runs.items() if k in a.skip}, **res["runs"]}
    path.write_text(json.dumps(res, indent=2))
    print(json.dumps(res, indent=2))
    return res


if __name__ == "__main__":
    main()
