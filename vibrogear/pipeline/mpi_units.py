"""The MPI backend of :func:`vibrogear.pipeline.executors.run_units`: every rank computes;
rank 0 also coordinates (hands out units, receives the items) between its own items.  An
exception in ``fn`` comes back to rank 0 and is re-raised as
:class:`~vibrogear.pipeline.executors.UnitError` on every rank after an orderly shutdown;
any other aborts all ranks (``MPI.Abort``): ``mpirun`` never hangs."""
from __future__ import annotations

import logging
import os
import time
import traceback

from .units_base import UnitError, _comm, _deliver, _run_serial, _Stop, _transportable, in_unit

__all__ = ["run_mpi"]

log = logging.getLogger(__name__)

_CTRL, _DATA, _STOP = 11, 12, 13
#: units queued at a computing rank while enough are left (no rank waits for rank 0,
#: which computes too and answers only between its own items)
_AHEAD = 2


def run_mpi(fn, units, on_result, order) -> list:
    """The MPI backend of :func:`~.executors.run_units` (see its module docstring)."""
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
            with in_unit():
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
            with in_unit():
                out = fn(unit, emit)
        except _Stop:                           # interrupted (stopping is set)
            continue
        except Exception as exc:                # noqa: BLE001 - sent back to rank 0
            comm.send(("error", i, traceback.format_exc(), _transportable(exc)), dest=0,
                      tag=_DATA)
            continue
        comm.send(("done", i, out), dest=0, tag=_DATA)
