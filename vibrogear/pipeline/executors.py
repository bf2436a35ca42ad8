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
  shutdown; any other aborts all ranks (``MPI.Abort``): ``mpirun`` never hangs.
* **processes** (``multiprocessing``, ``fork`` context) when ``workers > 1``; default
  ``workers = min(len(units), os.cpu_count())``.  Items come back through a queue;
  an exception in a worker (or a worker that dies) stops the others and raises
  :class:`UnitError` in the parent.  Workers die with the parent (``PR_SET_PDEATHSIG``).
* **serial** when ``workers == 1`` (or one unit): same calls, in unit order.

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

__all__ = ["run_units", "UnitError", "under_mpi", "is_root", "broadcast", "backend_for",
           "default_workers", "blas_threads"]

log = logging.getLogger(__name__)


class UnitError(RuntimeError):
    """A work unit raised an exception (``unit``: its index; ``remote``: the traceback
    text from the worker; ``original``: the exception when it could be transported)."""

    def __init__(self, unit: int, remote: str, original: BaseException | None = None):
        self.unit = unit
        self.remote = remote
        self.original = original
        super().__init__(f"work unit {unit} failed:\n{remote}")


class _Stop(Exception):
    """Raised inside ``emit`` to abandon the current unit (stop requested)."""


def under_mpi() -> bool:
    """True under ``mpirun`` with more than one rank (environment only; no import)."""
    size = os.environ.get("OMPI_COMM_WORLD_SIZE", os.environ.get("PMI_SIZE", "1"))
    try:
        return int(size) > 1
    except ValueError:
        return False


def _comm():
    from mpi4py import MPI
    return MPI.COMM_WORLD


def is_root() -> bool:
    """True except on the MPI ranks other than 0."""
    return os.environ.get("OMPI_COMM_WORLD_RANK", os.environ.get("PMI_RANK", "0")) == "0"


def broadcast(value):
    """``value`` from rank 0 on every rank under MPI; ``value`` itself otherwise."""
    return _comm().bcast(value, root=0) if under_mpi() else value


def blas_threads(n: int):
    """Context manager: at most ``n`` BLAS threads in this process (threadpoolctl).  Work
    that runs in parallel processes, or many small products (the continuation's 52 x 146
    by 146 x 292), runs faster on one thread each: measured on the two-stage
    continuation, 51 s with one BLAS thread against 71-78 s with two."""
    from threadpoolctl import threadpool_limits
    return threadpool_limits(limits=int(n), user_api="blas")


def default_workers(n_units: int) -> int:
    return max(1, min(int(n_units), os.cpu_count() or 1))


def backend_for(n_units: int, workers: int | None = None) -> str:
    """'mpi', 'processes' or 'serial': what :func:`run_units` will use."""
    if under_mpi():
        return "mpi"
    w = default_workers(n_units) if workers is None else min(int(workers), max(int(n_units), 1))
    return "processes" if w > 1 else "serial"


def run_units(fn, units, *, workers: int | None = None, on_result=None, costs=None) -> list:
    """Run ``fn(unit, emit)`` for every unit; returns the list of ``fn``'s return values
    in unit order (None for units left unfinished after a stop).  ``on_result(i, item)``
    receives every emitted item in the coordinating process; returning ``False`` stops.
    An exception in ``fn`` propagates as is when serial, as :class:`UnitError` (with the
    remote traceback) from processes or ranks.  Under MPI this is collective and every
    rank gets the same list.

    Units are handed out dynamically (a free process or rank takes the next one); with
    ``costs`` (one estimate per unit, any scale) the costliest go first, so that the
    short ones fill the end (longest-processing-time order).  Serial runs keep unit
    order.  The results never depend on the order."""
    units = list(units)
    if workers is not None and int(workers) < 1:
        raise ValueError("run_units: workers must be >= 1 (or None: all cores)")
    order = list(range(len(units)))
    if costs is not None:
        costs = [float(c) for c in costs]
        if len(costs) != len(units):
            raise ValueError(f"run_units: costs has {len(costs)} entries for {len(units)} units")
        order.sort(key=lambda i: -costs[i])
    kind = backend_for(len(units), workers)
    if kind == "mpi":
        return _run_mpi(fn, units, on_result, order)
    if kind == "processes":
        w = default_workers(len(units)) if workers is None else min(int(workers), len(units))
        return _run_processes(fn, units, w, on_result, order)
    return _run_serial(fn, units, on_result)


def _deliver(on_result, i, item) -> bool:
    return on_result is None or on_result(i, item) is not False


# ---------------------------------------------------------------- serial

def _run_serial(fn, units, on_result) -> list:
    results: list = [None] * len(units)
    for i, unit in enumerate(units):
        def emit(item, i=i):
            if not _deliver(on_result, i, item):
                raise _Stop
        try:
            results[i] = fn(unit, emit)
        except _Stop:
            break
    return results


# ---------------------------------------------------------------- processes

def _die_with_parent() -> None:
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)           # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def _transportable(exc: BaseException):
    import pickle
    try:
        return pickle.loads(pickle.dumps(exc))
    except Exception:
        return None


def _process_worker(fn, units, tasks, results, parent_pid) -> None:
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C
    _die_with_parent()
    if os.getppid() != parent_pid:
        os._exit(1)
    while True:
        i = tasks.get()
        if i is None:
            break
        results.put(("start", i, os.getpid()))

        def emit(item, i=i):
            if os.getppid() != parent_pid:
                os._exit(1)
            results.put(("item", i, item))

        try:
            out = fn(units[i], emit)
        except BaseException as exc:            # noqa: BLE001 - sent back to the parent
            results.put(("error", i, (traceback.format_exc(), _transportable(exc))))
            break
        results.put(("done", i, out))


def _run_processes(fn, units, workers, on_result, order) -> list:
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    tasks, res_q = ctx.Queue(), ctx.Queue()
    procs = [ctx.Process(target=_process_worker, args=(fn, units, tasks, res_q, os.getpid()),
                         daemon=True) for _ in range(workers)]
    results: list = [None] * len(units)
    owner: dict[int, int] = {}                  # unit -> pid while it runs
    finished = 0
    try:
        for p in procs:
            p.start()
        for i in [*order, *([None] * workers)]:
            tasks.put(i)                        # after the forks: no feeder thread yet
        while finished < len(units):
            try:
                kind, i, payload = res_q.get(timeout=0.2)
            except _queue.Empty:
                dead = [p for p in procs if p.exitcode not in (None, 0)]
                lost = [i for i, pid in owner.items() if any(p.pid == pid for p in dead)]
                if lost or (dead and all(p.exitcode is not None for p in procs)):
                    code = dead[0].exitcode
                    raise UnitError(lost[0] if lost else -1,
                                    f"worker process died (exit code {code})") from None
                continue
            if kind == "start":
                owner[i] = payload
            elif kind == "item":
                if not _deliver(on_result, i, payload):
                    break
            elif kind == "done":
                results[i] = payload
                owner.pop(i, None)
                finished += 1
            else:
                text, exc = payload
                raise UnitError(i, text, exc) from exc
    finally:
        for p in procs:
            if p.is_alive():
                p.terminate()
        for p in procs:
            p.join(timeout=5)
        for q in (tasks, res_q):
            q.cancel_join_thread()
            q.close()
    return results


# ---------------------------------------------------------------- MPI

_CTRL, _DATA, _STOP = 11, 12, 13
#: units queued at a computing rank while enough are left (no rank waits for rank 0,
#: which computes too and answers only between its own items)
_AHEAD = 2


def _run_mpi(fn, units, on_result, order) -> list:
    comm = _comm()
    try:
        if comm.size < 2:
            return _run_serial(fn, units, on_result)
        if comm.rank == 0:
            outcome = _MpiRoot(comm, fn, units, on_result, order).run()
        else:
            _mpi_worker(comm, fn)
            outcome = None
        outcome = comm.bcast(outcome, root=0)
    except BaseException:                       # noqa: BLE001 - never leave mpirun hanging
        log.critical("[rank %d] work-unit executor failed; aborting all ranks", comm.rank,
                     exc_info=True)
        comm.Abort(1)
        raise
    if outcome[0] == "error":
        _, i, text, exc = outcome
        raise UnitError(i, text, exc)
    return outcome[1]


class _MpiRoot:
    """Rank 0: hands out units in ``order`` (one at a time, a second one ahead while more
    than one per rank is left), computes units itself between the messages it serves,
    delivers every item to ``on_result``.  ``on_result`` returning False interrupts every
    rank's unit (tag _STOP) and skips the queued ones; an error lets the units already
    handed out (at most _AHEAD per rank) finish, their items delivered; then every rank
    ends (_CTRL)."""

    def __init__(self, comm, fn, units, on_result, order):
        from collections import deque
        from mpi4py import MPI

        self.comm, self.fn, self.units, self.on_result = comm, fn, units, on_result
        self.todo, self.results = deque(order), [None] * len(units)
        self.workers = range(1, comm.size)
        self.active, self.queued = set(self.workers), {r: 0 for r in self.workers}
        self.ended: set[int] = set()            # ranks sent the final _CTRL stop
        self.stopping = self.interrupted = False   # interrupted: on_result asked to stop
        self.error, self.status, self.any_source = None, MPI.Status(), MPI.ANY_SOURCE

    def feed(self, r):
        if self.stopping or r in self.ended:
            return
        while self.todo and (self.queued[r] == 0 or (
                self.queued[r] < _AHEAD and len(self.todo) > self.comm.size)):
            i = self.todo.popleft()
            self.comm.send(("unit", i, self.units[i]), dest=r, tag=_CTRL)
            self.queued[r] += 1
        if not self.todo:
            self.ended.add(r)
            self.comm.send(("stop",), dest=r, tag=_CTRL)

    def stop(self, interrupt: bool = True):
        if self.stopping:
            return
        self.stopping, self.interrupted = True, interrupt
        self.todo.clear()
        for r in sorted(self.active):
            if interrupt:
                self.comm.send(("stop",), dest=r, tag=_STOP)
            if r not in self.ended:
                self.ended.add(r)
                self.comm.send(("stop",), dest=r, tag=_CTRL)

    def serve(self, block: bool):
        """Handle the pending messages (at least one when ``block``)."""
        while True:
            if not self.comm.iprobe(source=self.any_source, tag=_DATA, status=self.status):
                if not block:
                    return
                time.sleep(0.002)               # leave the cores to the computing ranks
                continue
            block = False
            r = self.status.Get_source()
            msg = self.comm.recv(source=r, tag=_DATA)
            kind = msg[0]
            if kind == "bye":
                self.active.discard(r)
            elif kind == "item":
                if not self.interrupted and not _deliver(self.on_result, msg[1], msg[2]):
                    self.stop()
            elif kind == "done":
                self.results[msg[1]] = msg[2]
                self.queued[r] -= 1
                self.feed(r)
            elif kind == "error":
                if self.error is None:
                    self.error = ("error", msg[1], msg[2], msg[3])
                self.stop(interrupt=False)

    def own_unit(self, i):
        def emit(item):
            if not self.interrupted and not _deliver(self.on_result, i, item):
                self.stop()
            self.serve(block=False)
            if self.interrupted:
                raise _Stop

        try:
            self.results[i] = self.fn(self.units[i], emit)
        except _Stop:
            pass
        except Exception as exc:                # noqa: BLE001 - ends every rank as a worker's
            if self.error is None:
                self.error = ("error", i, traceback.format_exc(), _transportable(exc))
            self.stop(interrupt=False)

    def run(self):
        for r in self.workers:
            self.feed(r)
        while self.active or self.todo:         # a stop empties todo
            self.serve(block=not self.todo)
            if self.todo:
                self.own_unit(self.todo.popleft())
                if not self.todo:
                    for r in self.workers:
                        self.feed(r)            # the last units are out: end the idle ranks
        return self.error if self.error is not None else ("ok", self.results)


def _mpi_worker(comm, fn) -> None:
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    stopping = False

    def interrupted() -> bool:                  # a pending interrupt (tag _STOP), received
        if comm.iprobe(source=0, tag=_STOP):
            comm.recv(source=0, tag=_STOP)
            return True
        return False

    while True:
        msg = comm.recv(source=0, tag=_CTRL)
        if msg[0] == "stop":
            while interrupted():                # nothing left unreceived
                pass
            comm.send(("bye",), dest=0, tag=_DATA)
            return
        _, i, unit = msg
        stopping = stopping or interrupted()
        if stopping:
            continue                            # a queued unit after an interrupt

        def emit(item, i=i):
            nonlocal stopping
            comm.send(("item", i, item), dest=0, tag=_DATA)
            if interrupted():
                stopping = True
                raise _Stop

        try:
            out = fn(unit, emit)
        except _Stop:                           # interrupted (stopping is set)
            continue
        except Exception as exc:                # noqa: BLE001 - sent back to rank 0
            comm.send(("error", i, traceback.format_exc(), _transportable(exc)), dest=0,
                      tag=_DATA)
            continue
        comm.send(("done", i, out), dest=0, tag=_DATA)
