"""The parallel analyses' wall split (parallel units / serial part) and the speed-up it allows
on 16 and 64 workers, serial part and unit granularity included (docs/performance.md,
"Parallel runs: what is serial and what the split projects").

Measured here, each once, on ``--workers`` worker processes (small runs: the machine is shared):

* ``states`` on gear_pair over the issue's grid (11 speeds, 4900-5400 rpm) with ``--starts``
  starts per speed and branches on: census, orbit refinement and branches are work units;
* ``sweep`` on gear_pair, ``--sweep-points`` speeds up and down in ``--segments`` segments;
* ``map`` on gear_pair, 2 loads x ``--map-speeds`` speeds, curves off.

Each run's ``summary.json`` entry holds ``parallel_wall_s``, ``serial_wall_s`` and its phases
(units, summed and largest unit wall); :func:`vibrogear.pipeline.wall_split.project` turns
them into the wall and speed-up on W workers: serial + sum over phases of
max(work / W, largest unit) (the speed-up's upper end) and Graham's bound serial + work / W +
(1 - 1/W) largest unit (its lower end).  For the census the benchmark also projects the
issue's full case (32 starts per speed, 352 starts): the census work scaled by 352 / the
starts measured, its largest unit the longest start measured times the starts a unit holds at
W workers (:func:`~vibrogear.pipeline.executors.unit_size`), the grouping scaled with the starts,
the orbits and branches as measured (the same grid, so the same branch settings; the full
census may find more attractors to continue from).  Projections are written as such, with the
load average at each measurement.

Run: .venv/bin/python benchmarks/bench_parallel.py [--starts 3 --workers 2]
Writes benchmarks/results/bench_parallel.json.
"""
from __future__ import annotations

import argparse
import heapq
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
from vibrogear.pipeline.executors import unit_size  # noqa: E402
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


def _full_census(entry: dict, measured_starts: int, full_starts: int, batch: int,
                 longest_start: float, w: int) -> dict:
    """The measured split with the census scaled to ``full_starts`` on ``w`` workers."""
    ratio = full_starts / measured_starts
    clustering = float(entry["wall_split_s"].get("clustering", 0.0))
    phases = []
    for p in entry["parallel_phases"]:
        p = dict(p)
        if p["name"] == "census":
            p["unit_work_s"] = p["unit_work_s"] * ratio
            size = unit_size(full_starts, w, batch) if w > 1 else batch
            p["largest_unit_s"] = longest_start * size
            p["units"] = -(-full_starts // size)
        phases.append(p)
    return {"serial_wall_s": entry["serial_wall_s"] + clustering * (ratio - 1.0),
            "parallel_phases": phases}


def _list_schedule(times, workers: int) -> float:
    """Makespan of units handed out in order, each to the first worker free (run_units)."""
    free = [0.0] * workers
    heapq.heapify(free)
    for t in times:
        heapq.heappush(free, heapq.heappop(free) + t)
    return max(free)


def _simulated_full(entry: dict, point, wall, full_per_speed: int, batch: int, w: int,
                    serial: float) -> float:
    """Wall of the full census on ``w`` workers: each speed's starts resampled (fixed seed)
    from its measured starts, cut into units as the census cuts them, handed out in order
    (equal costs); the orbits and branches as :func:`project` has them; ``serial``: the
    scaled serial part."""
    rng = np.random.default_rng(0)
    speeds = sorted(set(int(i) for i in point))
    size = unit_size(full_per_speed * len(speeds), w, batch) if w > 1 else batch
    units = []
    for i in speeds:
        mine = rng.choice(wall[point == i], size=full_per_speed, replace=True)
        units += [float(np.sum(mine[a:a + size])) for a in range(0, full_per_speed, size)]
    rest = {"serial_wall_s": serial, "parallel_phases": [
        p for p in entry["parallel_phases"] if p["name"] != "census"]}
    return _list_schedule(units, w) + project(rest, w)["wall_s"][0]


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--starts", type=int, default=3, help="starts per speed (issue: 32)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--sweep-points", type=int, default=12)
    ap.add_argument("--segments", type=int, default=2)
    ap.add_argument("--map-speeds", type=int, default=4)
    ap.add_argument("--skip", nargs="*", default=(), choices=("states", "sweep", "map"))
    ap.add_argument("--out", default="/tmp/bench_parallel")
    ap.add_argument("--results", default="bench_parallel.json",
                    help="file name in benchmarks/results/ (e.g. for a 1-worker reference)")
    ap.add_argument("--reuse", action="store_true", help="states: recompute the projections "
                    "from the last run's files in --out (no new measurement)")
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
        sets = (f"states.starts={a.starts}", f"states.{w}", "states.branches=true")
        if a.reuse:
            entry = json.loads((out / "states" / "summary.json").read_text())
            old = json.loads((ROOT / "benchmarks" / "results" / a.results).read_text())
            m = {k: v for k, v in old["runs"]["states"].items() if not k.startswith("projection")}
            entry = entry["results"]["states"]
        else:
            m, entry = _run("states", sets, out / "states")
        n = int(entry["counters"]["starts_settled"])
        with np.load(out / "states" / "states.npz") as z:
            wall = np.asarray(z["start_wall_s"], float)
            point = np.asarray(z["start_point"], int)
        longest = float(np.max(wall))
        m.update(starts=n, attractors=entry["attractors"],
                 branches_continued=len(entry["branches"]),
                 wall_split_s=entry["wall_split_s"], longest_start_s=round(longest, 3),
                 projection=_projections(m, (a.workers, *PROJECT_AT)))
        full = FULL_STARTS * int(entry["points"])
        batch = int(load_scene(SCENE).states.batch)
        m["projection_full_census"] = {
            "starts": full,
            "note": "a projection, not a measurement: census work x " f"{full} / {n}, its "
                    "largest unit the longest start x the starts a unit holds, grouping "
                    "scaled, orbits and branches as measured",
            **{str(k): _projections(_full_census(entry, n, full, batch, longest, k), (k,))[str(k)]
               for k in (1, *PROJECT_AT)}}
        scaled = _full_census(entry, n, full, batch, longest, 1)["serial_wall_s"]
        one = _simulated_full(entry, point, wall, FULL_STARTS, batch, 1, scaled)
        m["projection_full_census"]["simulated"] = {
            "note": "each speed's starts resampled from its measured ones, units as the census "
                    "cuts them, handed out in order to the first free worker; orbits and "
                    "branches as in the projection",
            **{str(k): {"wall_s": round(t, 2), "speedup": round(one / t, 2)}
               for k in (1, *PROJECT_AT)
               for t in (_simulated_full(entry, point, wall, FULL_STARTS, batch, k, scaled),)}}
        res["runs"]["states"] = m
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
