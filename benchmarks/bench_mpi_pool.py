"""The project's MPI task pool (pipeline/executors.py ``run_units`` with pipeline/mpi_units.py
and mpi_peers.py) against ``mpi4py.futures.MPIPoolExecutor`` (Debian's python3-mpi4py), on
the same work: the gear pair's sweep units (configs/gear_pair.toml, ``--points`` speeds per
direction in ``--segments`` pieces, both directions), the very function the sweep hands to
its pool (solvers/sequential/sweep.py ``walk_unit``).

Three ways, each started by ``mpirun`` in its own job, interleaved in every repeat so that
they see the same load:

* ``ours_2``: ``mpirun -n 2``, ``run_units``: both ranks compute (rank 0 coordinates
  between its own points);
* ``futures_2``: ``mpirun -n 2 python -m mpi4py.futures``: rank 0 is the pool's manager,
  which hands out tasks and computes none, so one rank computes;
* ``futures_3``: ``mpirun -n 3 --oversubscribe``: a manager and two computing workers, the
  same number of computing processes as ``ours_2`` with one process more than there are
  cores (2 here).

Sessions: Linux's autogroup scheduler (on here) shares the cores between sessions, not
processes, and every process started from one shell is in one session; on a machine loaded
by other jobs a job then gets one session's slice however many of its ranks compute, and a
second computing rank cannot show in the wall time (``--one-session`` measures it so:
bench_mpi_pool_one_session.json).  By default each rank runs under ``setsid -w``, in a
session of its own, and gets the slice every other job here gets, as each rank gets a core
of its own on a dedicated node; each run records its ranks' autogroups.

Each computing process builds the model and computes one short point (every compiled kernel
loaded) before the clock starts; the clock covers the pool alone: from the first unit handed
out to the last point received on rank 0.  Every way must give the same points (the largest
monitored deformation of each point equal to the last bit): the check of a fair race.

The lost-rank case is measured too (``--lost``): a computing rank SIGKILLs itself after its
first point under ``mpirun --enable-recovery``; ours finishes the other units and names the
lost one (tests/unit/test_mpi_lost_rank.py); for mpi4py.futures the run's outcome within a
time limit is recorded (exit status, whether it hung within 180 s, what the driver saw).

Run: .venv/bin/python benchmarks/bench_mpi_pool.py [--points 6] [--segments 3] [--repeats 3]
     [--lost]   (never run by the tests; several minutes on 2 cores)
Writes benchmarks/results/bench_mpi_pool.json.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

SCENE = ROOT / "configs" / "gear_pair.toml"
RESULTS = ROOT / "benchmarks" / "results"
MPIRUN = shutil.which("mpirun")
WAYS = {"ours_2": 2, "futures_2": 2, "futures_3": 3}

# ----------------------------------------------------------------- the work (every process)

_WORK = {}


def _setup(points: int, segments: int):
    """(unit function, units) of the gear pair's sweep over ``points`` speeds per direction,
    built in this process, with one period integrated (the compiled integrator loaded)."""
    import dataclasses
    from functools import partial

    import numpy as np

    from vibrogear.analyses.study import build_study, integration_options
    from vibrogear.config import load_scene
    from vibrogear.config.options import SweepOptions
    from vibrogear.solvers.sequential.sweep import walk_unit, sweep_units

    scene = load_scene(SCENE, (f"sweep.n_points={points}", f"sweep.segments={segments}"))
    study = build_study(scene)
    cfg = scene.sweep
    params = np.linspace(*cfg.param_range(), cfg.n_points)
    # the accuracy rule's options (without the rtol probe: the same in every process)
    opts = integration_options(scene, record=True, period_tol=cfg.period_tol)
    settings = SweepOptions.of(cfg)
    seed = study.start(params[0])
    kw = dict(options=opts, cluster_tol=1e-3, keep_states=False, settle=True)
    units = [(d, idx, params[list(idx)], seed, {})
             for d, idx in sweep_units(params.size, settings.directions, settings.segments)]
    # one short point before the clock: every compiled kernel a point uses is loaded
    warm = dataclasses.replace(settings, transient_periods=2, extra_transient_periods=0,
                               record_periods=settings.max_period)
    walk_unit(study.model, warm, kw, ("up", (0,), params[:1], seed, {}), lambda item: None)
    return partial(walk_unit, study.model, settings, kw), units


def _digest(records) -> str:
    """The points' largest monitored deformations, bit for bit."""
    import numpy as np

    rows = sorted((r.direction, int(r.index), float(r.qmax)) for r in records)
    h = hashlib.sha256()
    for d, i, q in rows:
        h.update(f"{d}{i}".encode() + np.float64(q).tobytes())
    return h.hexdigest()[:16]


def _lose_after_first(emit):
    """``emit`` that SIGKILLs this process after its first item (the lost-rank case)."""
    count = [0]

    def wrapped(item):
        emit(item)
        count[0] += 1
        if count[0] == 1:
            os.kill(os.getpid(), signal.SIGKILL)
    return wrapped


def _autogroup() -> str:
    """The scheduler group of this process (Linux autogroup: one per session)."""
    try:
        return Path("/proc/self/autogroup").read_text().split()[0]
    except OSError:
        return "?"


def child_ours(points: int, segments: int, lose: bool) -> None:
    from mpi4py import MPI

    from vibrogear.pipeline.executors import run_units

    fn, units = _setup(points, segments)
    if lose:
        os.environ["VIBROGEAR_TEST_LOSE_RANK"] = "1:1"
    comm = MPI.COMM_WORLD
    comm.Barrier()
    got = []
    c0 = time.process_time()
    t0 = time.perf_counter()
    try:
        run_units(fn, units, on_result=lambda _k, rec: got.append(rec),
                  costs=[len(u[1]) for u in units])
        error = None
    except Exception as exc:            # noqa: BLE001 - the lost-rank case reports it
        error = f"{type(exc).__name__}: {exc}"
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    cpus = comm.gather(cpu, root=0) if error is None else [cpu]
    groups = comm.gather(_autogroup(), root=0) if error is None else [_autogroup()]
    if comm.rank == 0:
        print("RESULT " + json.dumps({"wall_s": wall, "points": len(got),
                                      "digest": _digest(got), "error": error,
                                      "cpu_s_per_rank": cpus, "autogroups": groups}),
              flush=True)


def _init_worker(points: int, segments: int, lose: bool) -> None:
    """mpi4py.futures' initializer: the unit function and the units, built in the worker."""
    _WORK["fn"], _WORK["units"] = _setup(points, segments)
    _WORK["lose"] = lose


def _run_unit(k: int) -> list:
    """Unit ``k`` in a worker; its points returned together (the pool's one result)."""
    unit = _WORK["units"][k]
    items = []
    emit = items.append
    if _WORK["lose"] and k == 0:
        emit = _lose_after_first(emit)
    c0 = time.process_time()
    _WORK["fn"](unit, emit)
    return items, time.process_time() - c0, _autogroup()


def child_futures(points: int, segments: int, lose: bool) -> None:
    from mpi4py.futures import MPIPoolExecutor

    from vibrogear.config import load_scene
    from vibrogear.solvers.sequential.sweep import sweep_units

    scene = load_scene(SCENE, (f"sweep.n_points={points}", f"sweep.segments={segments}"))
    n_units = len(sweep_units(points, scene.sweep.directions, segments))
    got, error = [], None
    with MPIPoolExecutor(initializer=_init_worker,
                         initargs=(points, segments, lose)) as ex:
        ex.bootup(wait=True)
        # a warm-up task per worker would not reach every worker for sure: the initializer
        # has built the model and loaded the integrator before bootup returns
        c0 = time.process_time()
        t0 = time.perf_counter()
        # the manager sends the unit's index only (the workers hold the units)
        futs = [ex.submit(_run_unit, k) for k in range(n_units)]
        worker_cpu, groups = 0.0, {_autogroup()}
        try:
            for f in futs:
                items, cpu, group = f.result()
                got.extend(items)
                worker_cpu += cpu
                groups.add(group)
        except Exception as exc:        # noqa: BLE001 - the lost-rank case reports it
            error = f"{type(exc).__name__}: {exc}"
        wall = time.perf_counter() - t0
        manager_cpu = time.process_time() - c0
    print("RESULT " + json.dumps({"wall_s": wall, "points": len(got), "digest": _digest(got),
                                  "error": error, "cpu_s_manager": manager_cpu,
                                  "cpu_s_workers": worker_cpu, "autogroups": sorted(groups)}),
          flush=True)


# ----------------------------------------------------------------- the driver

def _session_pids(sid: int) -> list[int]:
    """The processes of session ``sid`` (started by this driver)."""
    pids = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                if os.getsid(int(d.name)) == sid:
                    pids.append(int(d.name))
            except OSError:
                pass
    return pids


def _mpirun(way: str, args, *, lose: bool = False, timeout: float = 900.0) -> dict:
    n = WAYS[way]
    cmd = [MPIRUN, "-n", str(n), "--oversubscribe"]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    if lose:
        cmd.append("--enable-recovery")
    if not args.one_session and not lose:
        # every rank in a session of its own (see _autogroup); not in the lost-rank case,
        # whose processes are then simpler to end after a hang
        cmd += ["setsid", "-w"]
    py = [sys.executable] + (["-m", "mpi4py.futures"] if way.startswith("futures") else [])
    cmd += py + [str(Path(__file__).resolve()), "--child", way.split("_")[0],
                 "--points", str(args.points), "--segments", str(args.segments)]
    if lose:
        cmd.append("--lose")
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"}
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, env=env, cwd=ROOT, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        out, err = p.communicate(timeout=timeout)
        code, hung = p.returncode, False
    except subprocess.TimeoutExpired:
        # a hung job: every process of the session this driver started (mpirun and its
        # ranks, each rank in a process group of its own), by id
        for pid in _session_pids(p.pid):
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        out, err = p.communicate()
        code, hung = None, True
    job = time.perf_counter() - t0
    line = next((x for x in out.splitlines() if x.startswith("RESULT ")), None)
    rec = json.loads(line[7:]) if line else {}
    rec.update({"way": way, "ranks": n, "exit": code, "hung": hung, "job_wall_s": job,
                "load_1min_before": load0, "load_1min_after": os.getloadavg()[0]})
    if not line:
        rec["stderr_tail"] = err[-1500:]
    return rec


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=6)
    ap.add_argument("--segments", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--lost", action="store_true")
    ap.add_argument("--child", choices=("ours", "futures"))
    ap.add_argument("--lose", action="store_true")
    ap.add_argument("--one-session", action="store_true",
                    help="every rank of a job in the job's session (one autogroup)")
    args = ap.parse_args()
    if args.child == "ours":
        return child_ours(args.points, args.segments, args.lose)
    if args.child == "futures":
        return child_futures(args.points, args.segments, args.lose)
    if MPIRUN is None:
        sys.exit("bench_mpi_pool: no mpirun")
    import mpi4py

    runs = []
    for rep in range(args.repeats):
        for way in WAYS:
            rec = _mpirun(way, args)
            rec["repeat"] = rep
            runs.append(rec)
            print(f"repeat {rep} {way}: pool {rec.get('wall_s', float('nan')):.1f} s, job "
                  f"{rec['job_wall_s']:.1f} s, {rec.get('points')} points, load "
                  f"{rec['load_1min_before']:.1f}", flush=True)
    ratios = {}
    for way in ("futures_2", "futures_3"):
        per = [b["wall_s"] / a["wall_s"] for a, b in zip(
            [r for r in runs if r["way"] == "ours_2"], [r for r in runs if r["way"] == way])
            if "wall_s" in a and "wall_s" in b]
        ratios[f"{way}_over_ours_2"] = {"per_repeat": per,
                                        "median": sorted(per)[len(per) // 2] if per else None}
    digests = {r.get("digest") for r in runs}
    out = {"benchmark": "bench_mpi_pool", "scene": "configs/gear_pair.toml",
           "work": {"points_per_direction": args.points, "segments": args.segments,
                    "units": 2 * args.segments, "points": 2 * args.points},
           "sessions": "one per job (the ranks share its autogroup)" if args.one_session
           else "one per rank (each rank its own autogroup, as each other job here)",
           "machine": {"cores": os.cpu_count(), "python": platform.python_version(),
                       "mpi4py": mpi4py.__version__,
                       "note": "shared with other jobs: load_1min_* per run"},
           "runs": runs, "ratios": ratios, "same_points_everywhere": len(digests) == 1}
    if args.lost:
        out["lost_rank"] = {way: _mpirun(way, args, lose=True, timeout=180.0)
                            for way in ("ours_2", "futures_3")}
    name = "bench_mpi_pool_one_session.json" if args.one_session else "bench_mpi_pool.json"
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / name).write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps({"ratios": ratios, "same_points_everywhere": out["same_points_everywhere"],
                      "lost_rank": {k: {x: v.get(x) for x in ("exit", "hung", "points", "error")}
                                    for k, v in out.get("lost_rank", {}).items()}}, indent=2))


if __name__ == "__main__":
    main()
