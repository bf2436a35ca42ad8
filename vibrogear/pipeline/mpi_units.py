"""The MPI backend of :func:`vibrogear.pipeline.executors.run_units`: every rank computes;
rank 0 also coordinates (hands out units, receives the items) between its own items.  An
exception in ``fn`` comes back to rank 0 and is re-raised as
:class:`~vibrogear.pipeline.executors.UnitError` on every rank after an orderly shutdown;
any other aborts all ranks (``MPI.Abort``): ``mpirun`` never hangs.

**Added units** (``on_done``, see :func:`~vibrogear.pipeline.executors.run_units`): rank 0
calls ``on_done`` once a unit's ``done`` has come (MPI keeps one rank's messages in order,
so its items came first), pushes the units it returns onto the pending ones (costliest
first) and sends them as it sends the initial ones: the unit itself travels in the
message.  A rank whose queue runs dry is not told to end while any unit is pending, queued
or running (rank 0's own included): it waits for a unit or the end.  An exception in
``on_done`` interrupts every rank as a stop does; then rank 0 raises it as is and the other
ranks raise :class:`~vibrogear.pipeline.executors.UnitError` with its traceback.

**A lost rank** (killed, out of memory, a crash in compiled code).  Open MPI's ``mpirun``
ends the whole job when one rank dies (SIGTERM to the others about 1 s later, SIGKILL 1 s
after that), unless started with ``--enable-recovery``; either way every item rank 0
received is already in the caller's partial file.  Under ``--enable-recovery`` the others
go on (mpirun 4.1 then exits 0 whatever the ranks return: the run's status is in its
message and ``summary.json``):

* rank 0 notices the loss (it checks the pids of the ranks on its node while it waits and
  between its own items), never talks to that rank again, gives the units it had queued
  but not started back to the pending ones (with their costs), and names the unit it was
  computing: that unit's finished items are kept, the rest is not retried in this run (the unit may be
  what killed the rank).  Once every other unit is done, :class:`LostUnits` (exit 1) is
  raised on every live rank, naming the lost units; the same command resumes them.
* a rank that loses rank 0 (the one that writes the files) raises :class:`LostUnits` at once.

Every message to or from a rank that may die is non-blocking and polled with that check
(a blocking call on a dead rank never returns), the final result and
:func:`~vibrogear.pipeline.executors.broadcast` go point to point to the live ranks, and
once a rank is lost MPI_Finalize gets a time limit at exit (Open MPI sometimes never
returns from it then).  A rank on another node than the one watching it cannot be checked
(it counts as alive, and rank 0 would wait for its unit): use ``--enable-recovery`` with
every rank on one node.

Test hook: ``VIBROGEAR_TEST_LOSE_RANK=R:N`` makes rank ``R`` kill itself (SIGKILL) right
after it has handed over its ``N``-th item (tests/unit/test_mpi_lost_rank.py)."""
from __future__ import annotations

import heapq
import logging
import os
import time
import traceback

from .mpi_peers import (AHEAD, CHECK_S, CTRL, DATA, LOST, PEERS, RESULT, STOP,
                        mark_lost, peers, recv_root, root_lost, RootLost, send_to, lose_rank_hook,
                        wait_for, alive, bcast)
from .outcome import LostUnits
from .units_base import (UnitError, added_units, world_comm, deliver_result, run_serial, StopUnit,
                         transportable, in_unit)

__all__ = ["run_mpi", "bcast", "alive", "LostUnits"]

log = logging.getLogger(__name__)

def run_mpi(fn, units, on_result, costs, describe=None, on_done=None) -> list:
    """The MPI backend of :func:`~.executors.run_units` (see its module docstring);
    ``costs``: one per unit (0 where the caller gave none)."""
    comm = world_comm()
    root = None
    try:
        if comm.size < 2:
            return run_serial(fn, units, on_result, on_done)
        peers(comm)
        if comm.rank == 0:
            root = _MpiRoot(comm, fn, units, on_result, costs, describe, on_done)
            outcome = bcast(root.run(), tag=RESULT)
        else:
            try:
                _mpi_worker(comm, fn)
            except RootLost:
                raise root_lost() from None
            outcome = bcast(None, tag=RESULT)
            for r in outcome["lost_ranks"]:
                mark_lost(r)
    except LostUnits:
        raise
    except BaseException:                       # noqa: BLE001 - never leave mpirun hanging
        log.critical("[rank %d] work-unit executor failed; aborting all ranks", comm.rank,
                     exc_info=True)
        comm.Abort(1)
        raise
    if root is not None and root.done_error is not None:
        raise root.done_error                   # on_done's own exception, as is, on rank 0
    if outcome["error"] is not None:
        i, text, exc = outcome["error"]
        raise UnitError(i, text, exc)
    if outcome["lost_units"]:
        raise LostUnits(outcome["message"], {"lost_ranks": outcome["lost_ranks"],
                                             "lost_units": outcome["lost_units"]})
    return outcome["results"]


class _MpiRoot:
    """Rank 0: hands out the pending units costliest first (lowest index among equal
    costs; one at a time, a second one ahead while more than one per rank is left),
    computes units itself between the messages it serves, delivers every item to
    ``on_result`` and every finished unit to ``on_done``, whose added units join the
    pending ones.  ``on_result`` returning False interrupts every rank's unit (tag STOP)
    and skips the queued ones; an error lets the units already handed out (at most AHEAD
    per rank) finish, their items delivered; then every rank ends (CTRL).  With
    ``on_done`` a rank whose queue is empty is ended only once no unit is pending, queued
    or running anywhere (rank 0's own included): until then it waits for a unit.  An
    exception in ``on_done`` interrupts every rank as a stop does; rank 0 then raises it,
    the others :class:`UnitError`.  A lost rank: see the module docstring."""

    def __init__(self, comm, fn, units, on_result, costs, describe, on_done=None):
        from collections import deque
        from mpi4py import MPI

        self.comm, self.fn, self.units, self.on_result = comm, fn, list(units), on_result
        self.describe, self.on_done = describe, on_done
        self.costs = list(costs)
        self.todo = [(-c, i) for i, c in enumerate(self.costs)]    # a heap: costliest first
        heapq.heapify(self.todo)
        self.results = [None] * len(units)
        self.own: int | None = None              # the unit rank 0 computes now
        self.done_error: BaseException | None = None   # on_done's exception
        self.workers = range(1, comm.size)
        self.active = {r for r in self.workers if r not in LOST}   # not yet said "bye"
        self.queued = {r: deque() for r in self.workers}   # units sent, not finished
        self.running: dict[int, int | None] = {r: None for r in self.workers}
        self.items = [0] * len(units)            # items delivered per unit
        self.ended: set[int] = set(LOST)        # ranks sent the final CTRL stop (or gone)
        self.lost: list[tuple[int, int]] = []    # (rank, unit it was computing)
        self.stopping = self.interrupted = False   # interrupted: on_result asked to stop
        self.error, self.status, self.any_source = None, MPI.Status(), MPI.ANY_SOURCE
        self.next_check = time.monotonic() + CHECK_S

    # ------------------------------------------------------------ messages

    def to(self, r, obj, tag=CTRL) -> bool:
        if r in LOST:
            return False
        if send_to(self.comm, obj, r, tag):
            return True
        self.lose(r)
        return False

    def pop(self) -> int:
        return heapq.heappop(self.todo)[1]

    def push(self, i):
        heapq.heappush(self.todo, (-self.costs[i], i))

    def outstanding(self) -> bool:
        """A unit queued at a rank or running (rank 0's own included)."""
        return self.own is not None or any(self.queued[r] for r in self.workers)

    def feed(self, r):
        if self.stopping or r in self.ended:
            return
        while self.todo and (not self.queued[r] or (
                len(self.queued[r]) < AHEAD and len(self.todo) > self.comm.size)):
            i = self.pop()
            self.queued[r].append(i)
            if not self.to(r, ("unit", i, self.units[i])):
                return                          # lose() gave i back to todo
        # without on_done no unit can be added: a rank is told to end behind its last unit
        if not self.todo and (self.on_done is None or not self.outstanding()):
            self.ended.add(r)
            self.to(r, ("stop",))

    def feed_all(self):
        """Hand the pending units to the ranks short of work; end them all once nothing is
        pending, queued or running."""
        for r in self.workers:
            self.feed(r)

    def finished(self, i, value):
        """Unit ``i`` is done (every item of it delivered): its added units, if any."""
        self.results[i] = value
        if self.on_done is None or self.stopping:
            return
        try:
            added = added_units(self.on_done(i, value))
        except Exception as exc:                # noqa: BLE001 - every rank ends, rank 0 raises it
            self.done_error = exc
            if self.error is None:
                self.error = (i, "on_done raised for this unit:\n" + traceback.format_exc(),
                              transportable(exc))
            self.stop()
            return
        for unit, cost in added:
            self.units.append(unit)
            self.costs.append(cost)
            self.results.append(None)
            self.items.append(0)
            self.push(len(self.units) - 1)

    def stop(self, interrupt: bool = True):
        if self.stopping:
            return
        self.stopping, self.interrupted = True, interrupt
        self.todo.clear()
        for r in sorted(self.active):
            if interrupt:
                self.to(r, ("stop",), STOP)
            if r not in self.ended:
                self.ended.add(r)
                self.to(r, ("stop",))

    def deliver(self, i, item):
        self.items[i] += 1
        if not self.interrupted and not deliver_result(self.on_result, i, item):
            self.stop()

    def handle(self, r, msg):
        kind = msg[0]
        if kind == "bye":
            self.active.discard(r)
        elif kind == "start":
            self.running[r] = msg[1]
        elif kind == "item":
            self.deliver(msg[1], msg[2])
        elif kind in ("done", "error"):
            i = msg[1]
            self.running[r] = None
            if i in self.queued[r]:
                self.queued[r].remove(i)
            if kind == "done":
                self.finished(i, msg[2])
                self.feed(r)
                if self.on_done is not None:
                    self.feed_all()             # units added, or the last one done
            else:
                if self.error is None:
                    self.error = (i, msg[2], msg[3])
                self.stop(interrupt=False)

    def receive(self, source) -> bool:
        """Receive and handle one message from ``source`` (a rank or ANY_SOURCE) if there
        is one; False if none (or its sender died while it came)."""
        m = self.comm.improbe(source=source, tag=DATA, status=self.status)
        if m is None:
            return False
        r = self.status.Get_source()
        ok, msg = wait_for(m.irecv(), r)
        if not ok:
            self.lose(r)
            return False
        self.handle(r, msg)
        return True

    def serve(self, block: bool):
        """Handle the pending messages (at least one, or a lost rank, when ``block``)."""
        while True:
            if self.receive(self.any_source):
                block = False
                continue
            if self.watch() or not block:
                return
            time.sleep(0.002)                   # leave the cores to the computing ranks

    # ------------------------------------------------------------ lost ranks

    def watch(self) -> bool:
        """Check (every CHECK_S) that the ranks still working are alive; True if one was
        lost now."""
        now = time.monotonic()
        if now < self.next_check:
            return False
        self.next_check = now + CHECK_S
        gone = [r for r in sorted(self.active) if not alive(r)]
        for r in gone:
            self.lose(r)
        return bool(gone)

    def lose(self, r):
        """Rank ``r`` is gone: its running unit is lost, its queued ones go back to todo."""
        if r in LOST:
            return
        mark_lost(r)
        self.active.discard(r)
        self.ended.add(r)
        while self.receive(r):                  # what it sent before it died counts
            pass
        i = self.running[r]
        if i is not None and i in self.queued[r]:
            self.queued[r].remove(i)
            self.lost.append((r, i))
        if not self.stopping:
            for j in self.queued[r]:
                self.push(j)                    # back to pending, with its cost
        self.queued[r].clear()
        host, pid = PEERS[r]
        log.error("rank %d (pid %s on %s) was lost%s; the other ranks go on", r, pid, host,
                  f" while computing work unit {i}" if i is not None else "")

    def label(self, i) -> str:
        text = f"work unit {i} of {len(self.units)}"
        if self.describe is not None:
            try:
                text = f"{self.describe(self.units[i])} ({text})"
            except Exception:                   # noqa: BLE001 - a label never fails a run
                pass
        return text

    def lost_report(self) -> tuple[list, str]:
        units = [{"unit": i, "rank": r, "host": PEERS[r][0], "pid": PEERS[r][1],
                  "label": self.label(i), "items_kept": self.items[i]} for r, i in self.lost]
        ranks = sorted({r for r, _ in self.lost})
        parts = [f"{u['label']} on rank {u['rank']} (results of it kept: {u['items_kept']})"
                 for u in units]
        msg = (f"MPI rank{'s' if len(ranks) > 1 else ''} {', '.join(map(str, ranks))} "
               f"{'were' if len(ranks) > 1 else 'was'} lost mid-run; the other ranks finished "
               f"every other unit. Not computed: {'; '.join(parts)}. Run the same command "
               "again to compute them: finished results are reused")
        return units, msg

    # ------------------------------------------------------------ rank 0's run

    def own_unit(self, i):
        def emit(item):
            self.deliver(i, item)
            lose_rank_hook(0)
            self.serve(block=False)
            if self.interrupted:
                raise StopUnit

        self.own = i
        try:
            with in_unit():
                value = self.fn(self.units[i], emit)
        except StopUnit:
            return
        except Exception as exc:                # noqa: BLE001 - ends every rank as a worker's
            if self.error is None:
                self.error = (i, traceback.format_exc(), transportable(exc))
            self.stop(interrupt=False)
            return
        finally:
            self.own = None
        self.finished(i, value)

    def run(self) -> dict:
        self.feed_all()
        while self.active or self.todo:         # a stop empties todo
            self.serve(block=not self.todo)
            if self.on_done is not None:
                self.feed_all()                 # after a lost rank too: end the waiting ones
            if self.todo:
                self.own_unit(self.pop())
                if not self.todo or self.on_done is not None:
                    self.feed_all()             # the last units are out: end the idle ranks
        lost_units, message = self.lost_report() if self.lost and not self.interrupted \
            else ([], "")
        return {"results": self.results, "error": self.error, "lost_units": lost_units,
                "message": message, "lost_ranks": sorted(LOST)}


def _mpi_worker(comm, fn) -> None:
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    stopping = False

    def send(msg) -> None:
        if not send_to(comm, msg, 0, DATA):
            raise RootLost

    def interrupted() -> bool:                  # a pending interrupt (tag STOP), received
        if comm.iprobe(source=0, tag=STOP):
            comm.recv(source=0, tag=STOP)
            return True
        return False

    while True:
        msg = recv_root(comm, CTRL)
        if msg[0] == "stop":
            while interrupted():                # nothing left unreceived
                pass
            send(("bye",))
            return
        _, i, unit = msg
        stopping = stopping or interrupted()
        if stopping:
            continue                            # a queued unit after an interrupt
        send(("start", i))

        def emit(item, i=i):
            nonlocal stopping
            send(("item", i, item))
            lose_rank_hook(comm.rank)
            if interrupted():
                stopping = True
                raise StopUnit

        try:
            with in_unit():
                out = fn(unit, emit)
        except StopUnit:                           # interrupted (stopping is set)
            continue
        except Exception as exc:                # noqa: BLE001 - sent back to rank 0
            send(("error", i, traceback.format_exc(), transportable(exc)))
            continue
        send(("done", i, out))
