"""Sweep work units (direction, segment) on local processes and MPI ranks: identical
arrays whatever runs them, one writer of the partial file, resuming after a SIGKILL,
failures reported per point or raised without losing the other units' points."""
from __future__ import annotations

import dataclasses
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.models.reduced import ReducedModel
from vibrogear.pipeline.executors import UnitError, backend_for, run_units
from vibrogear.analyses.sweep.sweep import PARTIAL_NAME, resumable_sweep
from vibrogear.pipeline.resume import read_items
from vibrogear.report.sweep_files import read_sweep_npz, write_sweep
from vibrogear.solvers.integrator.integrate import IntegrationOptions
from vibrogear.solvers.sequential.sweep import sweep, sweep_units
from vibrogear.config.options import SweepOptions

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
MPIRUN = shutil.which("mpirun")
HYST = dict(zeta=0.015, kappa=0.2, f_m=0.1, f_p=0.2, b_r=1.0)
GRID = np.round(np.linspace(0.6, 0.95, 6), 10)
OPTS = IntegrationOptions(rtol=1e-9, atol=1e-11)
SETTINGS = SweepOptions(transient_periods=40, record_periods=8, max_period=4, period_tol=1e-5,
                        segments=2, extra_transient_periods=40)


def _s(**kw) -> SweepOptions:
    return dataclasses.replace(SETTINGS, **kw)
ARRAYS = ("param", "direction", "index", "qmin", "qmax", "poincare", "period_n", "impacts",
          "defect", "clusters", "status", "u_end")
MODEL = impact_pair_model(**HYST)
U0 = np.array([0.5, 0.0])


def _same(a, b, names=ARRAYS):
    for name in names:
        x, y = np.asarray(getattr(a, name)), np.asarray(getattr(b, name))
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name


class Boom(ReducedModel):
    """Impact pair whose point at Omega = BAD raises (after a pause): a crashing unit."""
    BAD = 0.95

    def excitation_frequency(self, param):
        if param == self.BAD:
            time.sleep(float(os.environ.get("BOOM_SLEEP", "0")))
            raise RuntimeError("injected failure in a work unit")
        return super().excitation_frequency(param)


def boom_model():
    m = MODEL
    return Boom(m.omega2, m.damping, m.coupling, m.forcing, m.contacts, m.omega_per_param,
                m.spin_per_param, m.monitor, m.name, m.param_name, m.state_names)


@pytest.fixture(scope="module")
def serial():
    return sweep(MODEL, GRID, _s(workers=1), u0=U0, options=OPTS)


# ---------------------------------------------------------------- executor layer

def _square(unit, emit):
    for k in range(unit):
        emit((unit, k))
    return unit * unit


def test_executor_backends_and_stop():
    assert backend_for(4, 1) == "serial" and backend_for(1, None) == "serial"
    assert backend_for(4, 2) == "processes"
    for w in (1, 2):
        got = []
        res = run_units(_square, [3, 1, 2], workers=w, on_result=lambda i, it: got.append(it))
        assert res == [9, 1, 4] and sorted(got) == sorted((u, k) for u in (3, 1, 2)
                                                          for k in range(u))
        seen = []
        res = run_units(_square, [5, 5], workers=w,
                        on_result=lambda i, it: seen.append(it) or len(seen) < 3)
        assert len(seen) == 3 and None in res
    with pytest.raises(ValueError):
        run_units(_square, [1], workers=0)


def _crash(unit, emit):
    if unit == "raise":
        raise KeyError("remote boom")
    if unit == "die":
        os.kill(os.getpid(), signal.SIGKILL)
    time.sleep(0.05)
    return unit


def test_executor_errors_come_back_instead_of_hanging():
    with pytest.raises(UnitError, match="remote boom") as info:
        run_units(_crash, ["ok", "raise"], workers=2)
    assert info.value.unit == 1 and isinstance(info.value.original, KeyError)
    with pytest.raises(UnitError, match="died"):
        run_units(_crash, ["ok", "die", "ok"], workers=2)
    with pytest.raises(KeyError):
        run_units(_crash, ["raise"], workers=1)


def test_sweep_config_segments_and_workers():
    from vibrogear.config.base import ConfigError, build
    from vibrogear.config.sections.common import SweepConfig

    base = {"omega_min": 0.5, "omega_max": 1.0}
    c = build(SweepConfig, base, "sweep")
    assert c.segments == 1 and c.workers is None
    c = build(SweepConfig, {**base, "segments": 8, "workers": 2}, "sweep")
    assert (c.segments, c.workers) == (8, 2)
    for key, bad in (("segments", 0), ("segments", 1001), ("segments", 2.5), ("workers", 0)):
        with pytest.raises(ConfigError, match=f"sweep.{key}"):
            build(SweepConfig, {**base, key: bad}, "sweep")


# ---------------------------------------------------------------- semantics

def test_units_are_independent_and_start_from_u0(serial):
    layout = sweep_units(GRID.size, ("up", "down"), 2)
    assert layout == [("up", (0, 1, 2)), ("up", (3, 4, 5)), ("down", (5, 4, 3)),
                      ("down", (2, 1, 0))]
    assert sweep_units(3, ("up",), 7) == [("up", (0,)), ("up", (1,)), ("up", (2,))]
    # the result lists the units in order, each in walk order
    assert list(zip(serial.direction, serial.index)) == [(d, i) for d, idx in layout
                                                         for i in idx]
    # every unit starts from u0: its first point equals a one-point sweep from u0, and its
    # second point a two-point sweep
    for d, idx in layout:
        alone = sweep(MODEL, GRID[list(idx[:2])], _s(directions=("up",), workers=1, segments=1), u0=U0, options=OPTS)
        rows = [k for k, (dd, i) in enumerate(zip(serial.direction, serial.index))
                if dd == d and i in idx[:2]]
        rows.sort(key=lambda k: idx.index(serial.index[k]))
        assert np.array_equal(serial.u_end[rows], alone.u_end)
        assert np.array_equal(serial.poincare[rows], alone.poincare)
    assert serial.status_code == 0


def test_two_processes_bit_identical_to_serial(serial):
    got = []
    par = sweep(MODEL, GRID, _s(workers=2), u0=U0, callback=got.append, options=OPTS)
    _same(par, serial)
    assert par.status_code == 0 and len(got) == 2 * GRID.size
    assert sorted((r.direction, r.index) for r in got) == sorted(
        zip(serial.direction.tolist(), serial.index.tolist()))


def test_failed_points_reported_per_point_other_unit_kept():
    grid = np.array([0.7, 0.0, 0.8, 0.85, 0.9, 0.95])   # 0.0: no excitation period
    r = sweep(MODEL, grid, _s(directions=("up",), workers=2, segments=2), u0=U0, options=OPTS)
    assert r.status_code == 1 and r.status.tolist() == [0, -10, 0, 0, 0, 0]
    assert "finite and > 0" in r.message[1] and np.isnan(r.qmax[1])
    # the failed point seeds nothing: its unit goes on from the last good state, and the
    # other unit is untouched
    a = sweep(MODEL, grid[[0, 2]], _s(directions=("up",), workers=1, segments=1), u0=U0, options=OPTS)
    b = sweep(MODEL, grid[3:], _s(directions=("up",), workers=1, segments=1), u0=U0, options=OPTS)
    assert np.array_equal(r.u_end[[0, 2]], a.u_end) and np.array_equal(r.qmax[[0, 2]], a.qmax)
    assert np.array_equal(r.u_end[3:], b.u_end) and np.array_equal(r.poincare[3:], b.poincare)


def test_crashing_unit_raises_and_keeps_the_other_units_points(tmp_path, monkeypatch):
    monkeypatch.setenv("BOOM_SLEEP", "2.5")      # the other unit finishes meanwhile
    with pytest.raises(UnitError, match="injected failure"):
        resumable_sweep(boom_model(), GRID, tmp_path, settings=_s(directions=("up",), workers=2),
                        u0=U0, options=OPTS)
    done = sorted((d["direction"], d["index"]) for d in read_items(tmp_path / PARTIAL_NAME))
    assert done == [("up", 0), ("up", 1), ("up", 2), ("up", 3), ("up", 4)]


# ---------------------------------------------------------------- resume after SIGKILL

KILLED = """
import sys, time
import numpy as np
import test_sweep_parallel as t
from vibrogear.analyses.sweep.sweep import resumable_sweep
seen = []
def stall(rec):
    seen.append(rec)
    if len(seen) >= int(sys.argv[2]):
        time.sleep(600)                      # "hangs" here until SIGKILL
resumable_sweep(t.MODEL, t.GRID, sys.argv[1], settings=t._s(workers=2), u0=t.U0, callback=stall,
                options=t.OPTS)
"""


def _env():
    path = os.pathsep.join([str(HERE), str(ROOT), os.environ.get("PYTHONPATH", "")])
    return {**os.environ, "PYTHONPATH": path, "OPENBLAS_NUM_THREADS": "1"}


def _points_in(path: Path) -> int:
    if not path.exists():
        return 0
    return sum(1 for line in path.read_text().splitlines() if '"kind":"point"' in line)


def test_sigkilled_sweep_resumes_without_recomputing(tmp_path, serial):
    n_first = 5
    part = tmp_path / PARTIAL_NAME
    proc = subprocess.Popen([sys.executable, "-c", KILLED, str(tmp_path), str(n_first)],
                            env=_env(), cwd=ROOT, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        t_end = time.monotonic() + 60
        while _points_in(part) < n_first and time.monotonic() < t_end:
            assert proc.poll() is None, proc.stderr.read().decode()[-2000:]
            time.sleep(0.02)
        time.sleep(0.3)                          # nothing more may arrive: one writer
        assert _points_in(part) == n_first
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL
    assert len(read_items(part)) == n_first and not (tmp_path / "sweep.npz").exists()
    new = []
    res, store, resumed = resumable_sweep(MODEL, GRID, tmp_path, settings=_s(workers=2), u0=U0,
                                          callback=new.append, options=OPTS)
    assert resumed == n_first and len(new) == 2 * GRID.size - n_first
    assert store.path == part and "resumed 5" in store.note
    _same(res, serial)


# ---------------------------------------------------------------- MPI

MPI_SCRIPT = """
import sys
import numpy as np
import test_sweep_parallel as t
from vibrogear.analyses.sweep.sweep import resumable_sweep
from vibrogear.report.sweep_files import write_sweep
model = t.boom_model() if sys.argv[2] == "boom" else t.MODEL
res, store, _ = resumable_sweep(model, t.GRID, sys.argv[1], settings=t.SETTINGS, u0=t.U0, options=t.OPTS)
if store is not None:                  # rank 0 writes the files, as the runner does
    write_sweep(res, sys.argv[1])
    store.path.unlink()
from mpi4py import MPI
np.save(f"{sys.argv[1]}/u_end_rank{MPI.COMM_WORLD.rank}.npy", res.u_end)
"""


def _mpirun(n):
    cmd = [MPIRUN, "-n", str(n)]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    return cmd + ["--oversubscribe"]


@pytest.mark.mpi
@pytest.mark.skipif(MPIRUN is None, reason="no mpirun")
def test_mpirun_two_ranks_identical_to_serial(tmp_path, serial):
    r = subprocess.run(_mpirun(2) + [sys.executable, "-c", MPI_SCRIPT, str(tmp_path), "ok"],
                       env=_env(), cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-3000:]
    z = read_sweep_npz(tmp_path / "sweep.npz")
    ref = read_sweep_npz(write_sweep(serial, tmp_path / "serial")["npz"])
    for k in ref:
        if k != "point_wall":
            assert np.array_equal(z[k], ref[k]), k
    for rank in (0, 1):                          # every rank returns rank 0's result
        assert np.array_equal(np.load(tmp_path / f"u_end_rank{rank}.npy"), serial.u_end)
    assert not (tmp_path / PARTIAL_NAME).exists()


@pytest.mark.system
@pytest.mark.mpi
@pytest.mark.skipif(MPIRUN is None, reason="no mpirun")
def test_mpirun_unit_exception_ends_all_ranks(tmp_path):
    r = subprocess.run(_mpirun(2) + [sys.executable, "-c", MPI_SCRIPT, str(tmp_path), "boom"],
                       env=_env(), cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode != 0 and "injected failure" in r.stderr
    assert not (tmp_path / "sweep.npz").exists()
    assert len(read_items(tmp_path / PARTIAL_NAME)) >= 1   # finished points are kept
