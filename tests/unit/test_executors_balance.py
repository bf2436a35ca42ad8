"""Dynamic dispatch of work units: costliest first with ``costs``, every MPI rank (rank 0
included) computes, results identical to a serial run whatever the order or backend."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from vibrogear.pipeline.executors import run_units

ROOT = Path(__file__).resolve().parents[2]
MPIRUN = shutil.which("mpirun")


def _work(unit, emit):
    emit(("start", unit))
    time.sleep(0.05 * unit)
    return unit * unit


def test_costs_order_the_dispatch_not_the_results():
    units = [1, 2, 6, 3, 5]
    serial = run_units(_work, units, workers=1)
    assert serial == [u * u for u in units]
    started = []
    res = run_units(_work, units, workers=2, costs=units,
                    on_result=lambda i, it: started.append(it[1]))
    assert res == serial                          # unit order, whatever ran first
    assert set(started[:2]) == {6, 5}             # the two costliest went first
    assert sorted(started) == sorted(units)
    with pytest.raises(ValueError, match="costs"):
        run_units(_work, units, workers=2, costs=[1.0])


MPI_SCRIPT = r"""
import json, sys, time
from mpi4py import MPI
from vibrogear.pipeline.executors import run_units
rank = MPI.COMM_WORLD.rank
def work(unit, emit):
    emit(unit)
    time.sleep(0.02 * unit)
    return [unit * unit, MPI.COMM_WORLD.rank]
units = [5, 1, 4, 2, 3, 1, 2, 5, 3, 4]
seen = []
res = run_units(work, units, costs=units, on_result=lambda i, it: seen.append(it))
stopped = run_units(work, units, on_result=lambda i, it: len(seen.append(it) or seen) < 13)
out = {"values": [r[0] for r in res], "ranks": [r[1] for r in res], "seen": len(seen),
       "stopped_none": sum(r is None for r in stopped)}
json.dump(out, open(sys.argv[1] + f"/rank{rank}.json", "w"))
"""


@pytest.mark.mpi
@pytest.mark.skipif(MPIRUN is None, reason="no mpirun")
def test_mpirun_every_rank_computes_and_results_match_serial(tmp_path):
    cmd = [MPIRUN, "-n", "2"] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    r = subprocess.run(cmd + ["--oversubscribe", sys.executable, "-c", MPI_SCRIPT, str(tmp_path)],
                       env=env, cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-3000:]
    units = [5, 1, 4, 2, 3, 1, 2, 5, 3, 4]
    outs = [json.loads((tmp_path / f"rank{k}.json").read_text()) for k in (0, 1)]
    for o in outs:                                    # every rank gets rank 0's list
        assert o["values"] == [u * u for u in units] and o["ranks"] == outs[0]["ranks"]
    assert set(outs[0]["ranks"]) == {0, 1}            # rank 0 computed units too
    assert outs[0]["seen"] >= 13 and outs[0]["stopped_none"] >= 1   # a stop ends every rank
