"""Run independent work units serially, on local processes or on MPI ranks.

:func:`run_units` calls ``fn(unit, emit)`` once per unit; ``fn`` hands each partial
result (e.g. one finished sweep point) to ``emit(item)`` as soon as it has it, and the
item travels to the coordinating process, where ``on_result(unit_index, item)`` is called
at once (returning ``False`` stops all work).  Only the coordinator calls ``on_result``,
so it is the one writer of files.  The backend is chosen automatically:

* **MPI** when the program runs under ``mpirun`` with more than one rank (detected from
  ``OMPI_COMM_WORLD_SIZE`` / ``PMI_SIZE`` before :mod:`mpi4py` is imported): every rank
  computes; rank 0 also coordinates (hands out units, receives the items) between its
  own items.  Every rank must call :func:`run_units` (collective).  An exception in ``fn``
  comes back to rank 0, re-raised as :class:`UnitError` on every rank after an orderly
  shutdown; any other aborts all ranks (``MPI.Abort``): ``mpirun`` never hangs.  A rank
  that dies (under ``mpirun --enable-recovery``; Open MPI's default ends the whole job):
  the others finish every other unit, then :class:`~.outcome.LostUnits` names the units it
  left (see :mod:`.mpi_units`).
* **processes** (``multiprocessing``, ``fork`` context) when ``workers > 1``; default
  ``workers = min(len(units), os.cpu_count())`` (all cores with ``on_done``).  The parent
  keeps one unit on the task queue ahead of the workers and puts the next, the costliest
  pending, when a worker starts one; items come back through a pipe.  An exception in a
  worker (or a worker that dies) stops the others and raises :class:`UnitError` in the
  parent.  Workers die with the parent (``PR_SET_PDEATHSIG``).
* **serial** when ``workers == 1`` (or one unit without ``on_done``): same calls, in unit
  order (added units after the initial ones, in the order added); also for a
  :func:`run_units` called inside a unit that runs on a worker process or an MPI rank (e.g.
  the sweep of one evaluation of ``vibrogear optimize``): nested parallelism stays serial.

``on_done(i, value)`` (in the coordinating process, once unit ``i`` has finished) may add
units while the run goes on: a unit's result decides which further units exist (the
states census starts the refinement of an orbit as soon as its speed is done).  Workers
are ended only once no unit is pending or running.

Workers set ``OPENBLAS_NUM_THREADS=1``.  Results depend only on the units, never on the
backend or the number of workers, as long as ``fn`` is deterministic.
"""
from __future__ import annotations

import logging
import os
import queue as _queue
import signal
import time
import traceback

from .units_base import (UnitError, added_units, deliver_result, run_serial, transportable,
                         in_unit, is_root, under_mpi, inside_unit, deferred_stop,
                         raise_if_stopped)

__all__ = ["run_units", "UnitError", "under_mpi", "is_root", "broadcast", "backend_for",
           "default_workers", "effective_workers", "unit_size", "blas_threads"]

log = logging.getLogger(__name__)


def broadcast(value):
    """``value`` from rank 0 on every rank under MPI (every live rank, if one was lost);
    ``value`` itself otherwise."""
    if not under_mpi():
        return value
    from .mpi_units import bcast
    return bcast(value)


def blas_threads(n: int):
    """Context manager: at most ``n`` BLAS threads in this process (threadpoolctl).  The
    parallelism is the processes' (the continuation's second core runs the split tangent
    columns, :mod:`vibrogear.solvers.integrator.split_flow`); two BLAS threads on the continuation's
    small products (52 x 146 by 146 x 292) gained nothing: the two-stage branch 71 / 73 s
    with two / one thread, and 78 / 51 s in a second pair of runs."""
    from threadpoolctl import threadpool_limits
    return threadpool_limits(limits=int(n), user_api="blas")


def default_workers(n_units: int) -> int:
    return max(1, min(int(n_units), os.cpu_count() or 1))


def _local_workers(n_units: int, workers: int | None, dynamic: bool) -> int:
    """The local processes for ``n_units`` units: at most one per unit, unless units may
    be added while the run goes on (``dynamic``: all cores, or ``workers``)."""
    if dynamic:
        return max(1, os.cpu_count() or 1) if workers is None else int(workers)
    return default_workers(n_units) if workers is None else min(int(workers), max(int(n_units), 1))


def effective_workers(n_units: int, workers: int | None = None, dynamic: bool = False) -> int:
    """How many processes or ranks compute ``n_units`` units: the MPI ranks, the local
    processes (at most one per unit, unless ``dynamic``: units added while the run goes on,
    see :func:`run_units`'s ``on_done``) or 1 (serial, or a run_units inside a unit)."""
    kind = backend_for(n_units, workers, dynamic)
    if kind == "mpi":
        size = os.environ.get("OMPI_COMM_WORLD_SIZE", os.environ.get("PMI_SIZE", "1"))
        return max(1, int(size))
    if kind == "processes":
        return _local_workers(n_units, workers, dynamic)
    return 1


def unit_size(n_items: int, workers: int, cap: int, per_worker: int = 16) -> int:
    """Items per work unit for ``n_items`` independent items of similar cost on ``workers``
    workers: at most ``cap``, and small enough that each worker gets about ``per_worker``
    units, so that the last units to finish leave the others idle for a fraction
    1 / per_worker of the run at most (at least 1)."""
    n, w = max(int(n_items), 1), max(int(workers), 1)
    return max(1, min(int(cap), -(-n // (w * int(per_worker)))))


def backend_for(n_units: int, workers: int | None = None, dynamic: bool = False) -> str:
    """'mpi', 'processes' or 'serial': what :func:`run_units` will use (``dynamic``: with
    ``on_done``, which may add units)."""
    if inside_unit():
        return "serial"
    if under_mpi():
        return "mpi"
    return "processes" if _local_workers(n_units, workers, dynamic) > 1 else "serial"


def run_units(fn, units, *, workers: int | None = None, on_result=None, costs=None,
              describe=None, on_done=None) -> list:
    """Run ``fn(unit, emit)`` for every unit; returns the list of ``fn``'s return values
    in unit order (None for units left unfinished after a stop).  ``on_result(i, item)``
    receives every emitted item in the coordinating process; returning ``False`` stops.
    An exception in ``fn`` propagates as is when serial, as :class:`UnitError` (with the
    remote traceback) from processes or ranks.  Under MPI this is collective and every
    rank gets the same list.

    Units are handed out dynamically (a free process or rank takes the next one); with
    ``costs`` (one estimate per unit, any scale) the costliest go first, so that the
    short ones fill the end (longest-processing-time order); ties, and units without
    costs, go in index order.  Serial runs keep unit order.  The results never depend on
    the order.  ``describe(unit) -> str`` names a unit for the user (e.g. its parameter
    values) where one is reported lost with its MPI rank (:class:`~.outcome.LostUnits`);
    without it, units are named by their index.

    **Units added while the run goes on.**  ``on_done(i, value)`` is called in the
    coordinating process (the caller; rank 0 under MPI) once unit ``i`` has finished and
    every item it emitted has gone to ``on_result``, with ``fn``'s return value.  It
    returns None or an iterable of ``(unit, cost)`` pairs: each becomes a new unit, with
    the next index (``len(units)``, then one more for each, in the order returned), handed
    out as the others are: a free worker takes the pending unit of highest cost (lowest
    index among equal costs; initial units without ``costs`` count as cost 0), so an added
    unit of high cost goes ahead of the initial ones still waiting.  Serial runs take the
    added units after the initial ones, in the order added.  No worker is ended while a
    unit that might add more is queued or running.  The returned list covers every unit,
    added ones included.  Added units travel to the workers (pickled), the initial ones do
    not on local processes.  After a stop or a unit's error ``on_done`` is not called
    again; an exception raised by ``on_done`` ends every worker and is then raised as is
    in the coordinating process (under MPI the other ranks raise :class:`UnitError` with
    its traceback).  With ``on_done`` and ``workers=None`` the processes backend starts one
    process per core (the number of units is not known in advance)."""
    units = list(units)
    if workers is not None and int(workers) < 1:
        raise ValueError("run_units: workers must be >= 1 (or None: all cores)")
    if costs is not None:
        costs = [float(c) for c in costs]
        if len(costs) != len(units):
            raise ValueError(f"run_units: costs has {len(costs)} entries for {len(units)} units")
    else:
        costs = [0.0] * len(units)
    if not units:
        return []
    dynamic = on_done is not None
    kind = backend_for(len(units), workers, dynamic)
    if kind == "mpi":
        from .mpi_units import run_mpi
        return run_mpi(fn, units, on_result, costs, describe, on_done)
    if kind == "processes":
        return _run_processes(fn, units, _local_workers(len(units), workers, dynamic),
                              on_result, costs, on_done)
    return run_serial(fn, units, on_result, on_done)


# ---------------------------------------------------------------- processes

def _die_with_parent() -> None:
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)           # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def _process_worker(fn, units, tasks, results, parent_pid) -> None:
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C
    for sig in (signal.SIGTERM, signal.SIGHUP):   # the parent's handlers (cli.py) are not
        signal.signal(sig, signal.SIG_DFL)        # a worker's: terminate() just ends it
    _die_with_parent()
    if os.getppid() != parent_pid:
        os._exit(1)
    while True:
        task = tasks.get()
        if task is None:
            break
        i, unit = task if isinstance(task, tuple) else (task, units[task])  # added: (i, unit)
        results.put(("start", i, os.getpid()))

        def emit(item, i=i):
            if os.getppid() != parent_pid:
                os._exit(1)
            results.put(("item", i, item))

        try:
            with in_unit():
                out = fn(unit, emit)
        except BaseException as exc:            # noqa: BLE001 - sent back to the parent
            results.put(("error", i, (traceback.format_exc(), transportable(exc))))
            break
        results.put(("done", i, out))


#: tasks put on the processes' queue and not yet started: the queue is fed on demand, so that
#: the costliest pending unit (an added one included) is the next a free worker takes.  The
#: workers' messages go through a pipe written at once (a SimpleQueue): through a
#: multiprocessing Queue, whose feeder thread needs the GIL, a unit's "start" arrived only
#: when the unit ended, and with one task ahead 200 units of 1 ms on 2 workers took 0.22 s
#: instead of 0.11 s.  The tasks keep a Queue: the parent never blocks on a put (an added unit
#: may be larger than the pipe's buffer while every worker is busy).
_AHEAD = 1


def _run_processes(fn, units, workers, on_result, costs, on_done=None) -> list:
    import heapq
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    tasks, res_q = ctx.Queue(), ctx.SimpleQueue()
    n0 = len(units)
    procs = [ctx.Process(target=_process_worker, args=(fn, units, tasks, res_q, os.getpid()),
                         daemon=True) for _ in range(workers)]
    units = list(units)                         # the parent's copy grows with added units
    results: list = [None] * n0
    pending = [(-c, i) for i, c in enumerate(costs)]
    heapq.heapify(pending)
    owner: dict[int, int] = {}                  # unit -> pid while it runs
    waiting = 0                                 # put on the queue, not yet started
    finished, ended = 0, False

    def top_up():
        nonlocal waiting
        while pending and waiting < _AHEAD:
            _, i = heapq.heappop(pending)
            tasks.put(i if i < n0 else (i, units[i]))
            waiting += 1

    try:
        with deferred_stop():                   # no raise inside the fork's hooks
            for p in procs:
                p.start()
        top_up()                                # after the forks: no feeder thread yet
        while finished < len(units):
            raise_if_stopped()                  # a signal swallowed while the workers forked
            try:
                if not res_q._reader.poll(0.2):  # SimpleQueue.get has no timeout
                    raise _queue.Empty
                kind, i, payload = res_q.get()
            except _queue.Empty:
                raise_if_stopped()              # workers ended by the stop signal
                dead = [p for p in procs if p.exitcode not in (None, 0)]
                lost = [i for i, pid in owner.items() if any(p.pid == pid for p in dead)]
                live = {p.pid for p in procs if p.exitcode is None}
                # a dead worker took a queued unit it never started: nothing moves on
                stuck = waiting > 0 and not any(pid in live for pid in owner.values())
                if lost or (dead and (stuck or all(p.exitcode is not None for p in procs))):
                    code = dead[0].exitcode
                    raise UnitError(lost[0] if lost else -1,
                                    f"worker process died (exit code {code})") from None
                continue
            if kind == "start":
                owner[i] = payload
                waiting -= 1
                top_up()
            elif kind == "item":
                if not deliver_result(on_result, i, payload):
                    break
            elif kind == "done":
                results[i] = payload
                owner.pop(i, None)
                finished += 1
                if on_done is not None:
                    for unit, cost in added_units(on_done(i, payload)):
                        units.append(unit)
                        results.append(None)
                        heapq.heappush(pending, (-cost, len(units) - 1))
                    top_up()
            else:
                text, exc = payload
                raise UnitError(i, text, exc) from exc
        else:
            for _ in procs:                     # nothing pending or running: end them all
                tasks.put(None)
            ended = True
    finally:
        if ended:
            deadline = time.monotonic() + 2.0
            for p in procs:
                p.join(timeout=max(deadline - time.monotonic(), 0.0))
        for p in procs:
            if p.is_alive():
                p.terminate()
        for p in procs:
            p.join(timeout=2)
            if p.is_alive():    # SIGTERM came before the worker took the default action
                p.kill()        # (its fork inherited a handler that only records a stop)
                p.join(timeout=5)
        tasks.cancel_join_thread()
        tasks.close()
        res_q.close()
    return results
