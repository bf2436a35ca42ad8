"""Work units added while :func:`run_units` runs (``on_done``): the units a finished unit
adds run on every backend, the costliest pending unit goes first (an added one included),
no worker ends while a unit that may add more is pending or running, and an exception in
``on_done`` ends every worker and reaches the caller as is."""
from __future__ import annotations

import json
import multiprocessing as mp
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from vibrogear.pipeline.executors import effective_workers, run_units
from vibrogear.pipeline.wall_split import WallSplit

ROOT = Path(__file__).resolve().parents[2]
MPIRUN = shutil.which("mpirun")

#: every value of the tree below: 1, 2, 3, each times 10, each times 100
TREE = {1, 2, 3, 10, 20, 30, 100, 200, 300}


def _identity(unit, emit):
    emit(unit)
    return unit


def _tree(workers):
    """Initial units [1, 2, 3]; a done unit v < 100 adds the unit 10 v.  Returns the
    results, the units in index order as on_done saw them added, and the items."""
    units, seen = [1, 2, 3], []

    def on_done(i, v):
        assert units[i] == v                    # fn's value for the unit of index i
        if v < 100:
            units.append(10 * v)
            return [(10 * v, v)]
        return None

    res = run_units(_identity, [1, 2, 3], workers=workers, on_done=on_done,
                    on_result=lambda i, it: seen.append((i, it)))
    return res, units, seen


@pytest.mark.timeout(120)
def test_a_unit_tree_gives_every_unit_once_on_every_backend():
    serial, units, seen = _tree(1)
    # serial: initial units in order, then the added ones in the order they were added
    assert serial == [1, 2, 3, 10, 20, 30, 100, 200, 300] == units
    assert sorted(seen) == sorted(enumerate(units))
    for w in (2, 3):
        res, units, seen = _tree(w)
        assert res == units                      # index order: the order units were added
        assert set(res) == TREE and len(res) == 9
        assert res[:3] == [1, 2, 3]
        assert sorted(seen) == sorted(enumerate(units))    # every item, to its unit's index
        # a unit's descendants come after it
        assert all(res.index(10 * v) > res.index(v) for v in res if v < 100)


def _timed_start(unit, emit):
    emit((unit, time.monotonic()))              # the system-wide clock: comparable across
    time.sleep(0.1 if unit == "trigger" else 0.03)      # the worker processes
    return unit


@pytest.mark.timeout(120)
def test_an_added_costly_unit_starts_before_the_pending_cheap_ones():
    """Two workers, a trigger unit (cost 100, first out) and 20 cheap units (cost 1): the
    trigger adds an urgent unit of cost 1000 when done.  It starts at once: after the
    trigger is done (the parent's clock in on_done) at most the one cheap unit already on
    the task queue and one the other worker takes meanwhile go ahead of it, never the cheap
    units still pending.  Start times, not the order the items arrive in: on a loaded
    machine a worker's items may come late."""
    started, done_at = {}, []

    def on_done(i, v):
        if v == "trigger":
            done_at.append(time.monotonic())
            return [("urgent", 1000.0)]
        return None

    def on_result(i, item):
        started[item[0]] = item[1]

    units = ["trigger"] + [f"cheap{k}" for k in range(20)]
    res = run_units(_timed_start, units, workers=2, costs=[100.0] + [1.0] * 20,
                    on_done=on_done, on_result=on_result)
    assert res == units + ["urgent"] and set(started) == set(res)
    (t_done,) = done_at
    t_urgent = started["urgent"]
    between = [u for u, t in started.items() if u.startswith("cheap") and t_done <= t < t_urgent]
    assert len(between) <= 2, between
    after = [u for u, t in started.items() if t > t_urgent]
    before_done = [u for u, t in started.items() if t < t_done and u != "trigger"]
    assert len(after) == 20 - len(before_done) - len(between)
    # appended behind the queue it would have started last; here most cheap units follow it
    # unless the trigger's 0.1 s let the other worker run through them all (a stalled parent)
    assert len(after) >= 1 or len(before_done) >= 17


def _sleepy(unit, emit):
    emit(os.getpid())
    time.sleep(0.2)
    return unit * 2


@pytest.mark.timeout(120)
def test_workers_wait_for_the_units_a_running_unit_adds():
    """One initial unit on three workers: the other two wait (they are not ended) and the
    three units it adds run on the three workers at once."""
    pids: dict[int, int] = {}

    def on_done(i, v):
        return [(u, 0.0) for u in (5, 6, 7)] if i == 0 else None

    assert effective_workers(1, 3, dynamic=True) == 3 and effective_workers(1, 3) == 1
    res = run_units(_sleepy, [4], workers=3, on_done=on_done,
                    on_result=lambda i, pid: pids.setdefault(i, pid))
    assert res == [8, 10, 12, 14]
    assert sorted(pids) == [0, 1, 2, 3]
    assert len({pids[1], pids[2], pids[3]}) == 3  # three workers alive for the added units


class _Boom(ValueError):
    pass


def _slow(unit, emit):
    emit(unit)
    time.sleep(unit)
    return unit


@pytest.mark.timeout(60)
def test_an_exception_in_on_done_ends_the_workers_and_is_raised_as_is():
    def on_done(i, v):
        raise _Boom(f"no follow-up for {v}")

    t0 = time.perf_counter()
    with pytest.raises(_Boom, match="no follow-up for 0.05"):
        run_units(_slow, [0.05, 5.0, 5.0], workers=3, on_done=on_done)
    assert time.perf_counter() - t0 < 4.5         # the 5 s units were not waited for
    assert mp.active_children() == []             # every worker is gone
    with pytest.raises(_Boom):                    # serial: the same exception
        run_units(_slow, [0.0, 0.0], workers=1, on_done=on_done)
    with pytest.raises(TypeError, match="on_done must return"):
        run_units(_slow, [0.0, 0.0], workers=2, on_done=lambda i, v: [v])
    assert mp.active_children() == []


@pytest.mark.timeout(60)
def test_no_on_done_after_a_stop():
    done = []

    def on_done(i, v):
        done.append(i)
        return [(v, 0.0)]                         # endless without the stop

    res = run_units(_identity, [1, 2], workers=2, on_done=on_done,
                    on_result=lambda i, it: i < 5)
    # a unit emits before it is done: the stop (the item of unit 5 or later) comes before
    # any of those units is done; the units done before it have their results (which of
    # them ran first depends on the timing: a worker may sit on unit 1 meanwhile)
    assert len(done) <= 5 and all(i < 5 for i in done) and len(res) == 2 + len(done)
    assert all(res[i] is not None for i in done) and all(r is None for r in res[6:])
    assert run_units(_identity, [1, 2], workers=1, on_done=on_done,
                     on_result=lambda i, it: i < 1) == [1, None, None]


@pytest.mark.timeout(60)
def test_wall_split_counts_added_units_and_hands_on_done_fns_own_value():
    got = []

    def on_done(i, v):
        got.append(v)
        return [(v + 0.05, 0.0)] if v < 0.1 else None

    split = WallSplit("nothing")
    res = split.run("phase", _slow, [0.05], workers=2, on_done=on_done)
    assert res == got == [0.05, pytest.approx(0.1)]   # fn's values, not (value, wall)
    (ph,) = split.summary()["parallel_phases"]
    assert ph["units"] == 2 and ph["workers"] == 2
    assert ph["unit_work_s"] >= 0.15 and ph["largest_unit_s"] >= 0.1


# ------------------------------------------------------------------ MPI

MPI_SCRIPT = r"""
import json, sys, time
from mpi4py import MPI
from vibrogear.pipeline.executors import run_units, broadcast
from vibrogear.pipeline.units_base import UnitError
rank = MPI.COMM_WORLD.rank
def work(unit, emit):
    emit(unit)
    time.sleep(0.01)
    return unit
added = [1, 2, 3]
def on_done(i, v):
    assert added[i] == v
    if v < 100:
        added.append(10 * v)
        return [(10 * v, v)]
tree = run_units(work, [1, 2, 3], on_done=on_done)
single_added = [4]
def one(i, v):
    if i == 0:
        single_added.extend([5, 6, 7])
        return [(5, 0), (6, 0), (7, 0)]
single = run_units(work, [4], on_done=one)
class Boom(ValueError):
    pass
def boom(i, v):
    raise Boom("no follow-up for %s" % v)
try:
    run_units(work, [0.5, 1.0, 1.5, 2.0], on_done=boom)
    err = None
except UnitError as exc:
    err = ["UnitError", exc.unit, "no follow-up" in exc.remote]
except Boom as exc:
    err = ["Boom", str(exc)]
out = {"tree": tree, "added": broadcast(added), "single": single,
       "single_added": broadcast(single_added), "error": err}
json.dump(out, open(sys.argv[1] + f"/rank{rank}.json", "w"))
"""


@pytest.mark.mpi
@pytest.mark.skipif(MPIRUN is None, reason="no mpirun")
@pytest.mark.timeout(180)
def test_mpirun_adds_units_on_every_rank_and_ends_both_on_an_on_done_error(tmp_path):
    cmd = [MPIRUN, "-n", "2", "--oversubscribe"] + (
        ["--allow-run-as-root"] if os.geteuid() == 0 else [])
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    r = subprocess.run(cmd + [sys.executable, "-c", MPI_SCRIPT, str(tmp_path)], env=env,
                       cwd=ROOT, capture_output=True, text=True, timeout=150)
    assert r.returncode == 0, r.stderr[-3000:]
    outs = [json.loads((tmp_path / f"rank{k}.json").read_text()) for k in (0, 1)]
    for o in outs:
        assert o["tree"] == o["added"] == outs[0]["tree"]    # the same list on every rank
        assert set(o["tree"]) == TREE and len(o["tree"]) == 9
        assert o["single"] == o["single_added"] == [4, 5, 6, 7]
    kind, text = outs[0]["error"]                 # rank 0: the original exception
    assert kind == "Boom" and text.startswith("no follow-up for ")
    first = [0.5, 1.0, 1.5, 2.0].index(float(text.split()[-1]))   # the first unit done
    assert outs[1]["error"] == ["UnitError", first, True]  # rank 1: its traceback


LOST_SCRIPT = r"""
import json, os, sys, time
from mpi4py import MPI
from vibrogear.pipeline.executors import run_units
from vibrogear.pipeline.outcome import LostUnits
rank = MPI.COMM_WORLD.rank
def work(unit, emit):
    for k in range(3):
        time.sleep(0.02)
        emit((unit, k, rank))
    return unit
seen = []
def on_done(i, v):
    return [(u, 0) for u in range(1, 8)] if i == 0 else None
try:
    run_units(work, [0], on_result=lambda i, it: seen.append(it), on_done=on_done,
              describe=lambda u: f"unit #{u}")
    out = {"lost": None}
except LostUnits as exc:
    out = {"lost": str(exc), "record": exc.record}
out.update(seen=seen)
json.dump(out, open(os.path.join(sys.argv[1], f"rank{rank}.json"), "w"))
"""


@pytest.mark.mpi
@pytest.mark.skipif(MPIRUN is None, reason="no mpirun")
@pytest.mark.timeout(180)
def test_mpirun_a_rank_lost_on_an_added_unit_is_named_and_the_rest_finish(tmp_path):
    """Rank 1 computes the initial unit (3 items), whose on_done adds units 1..7; it dies
    after its 4th item, the first of an added unit: that unit is named (by describe), the
    others, its queued one included, are finished by rank 0."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1",
           "VIBROGEAR_TEST_LOSE_RANK": "1:4"}
    cmd = [MPIRUN, "-n", "2", "--oversubscribe", "--enable-recovery"] + (
        ["--allow-run-as-root"] if os.geteuid() == 0 else [])
    r = subprocess.run(cmd + [sys.executable, "-c", LOST_SCRIPT, str(tmp_path)], env=env,
                       cwd=ROOT, capture_output=True, text=True, timeout=150)
    assert not (tmp_path / "rank1.json").exists(), r.stderr[-3000:]     # it was killed
    out = json.loads((tmp_path / "rank0.json").read_text())
    (unit,) = out["record"]["lost_units"]
    assert unit["rank"] == 1 and unit["items_kept"] == 1 and 1 <= unit["unit"] <= 7
    assert f"unit #{unit['unit']}" in out["lost"] and "of 8" in out["lost"]
    got = {(u, k) for u, k, _ in out["seen"]}
    assert len(got) == len(out["seen"])           # nothing delivered twice
    assert got == {(u, k) for u in range(8) for k in range(3) if u != unit["unit"]} \
        | {(unit["unit"], 0)}
    assert {u for u, _, rk in out["seen"] if rk == 1} == {0, unit["unit"]}
