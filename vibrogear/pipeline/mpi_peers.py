"""Rank liveness and loss-tolerant messaging for the MPI backend (:mod:`.mpi_units`): the
(host, pid) of every rank, a check that a rank on this node is alive, non-blocking sends and
receives polled with that check (a blocking call on a dead rank never returns), the
point-to-point broadcast to the live ranks, MPI_Finalize with a time limit once a rank was
lost, and the test hook that loses a rank on purpose (see :mod:`.mpi_units`)."""
from __future__ import annotations

import os
import signal
import socket
import time

from .outcome import LostUnits
from .units_base import world_comm

__all__ = ["alive", "bcast"]

CTRL, DATA, STOP, RESULT, _BCAST = 11, 12, 13, 14, 15
#: units queued at a computing rank while enough are left (no rank waits for rank 0,
#: which computes too and answers only between its own items)
AHEAD = 2
#: seconds between two liveness checks of a peer while waiting on it
CHECK_S = 0.2

#: (host, pid) of every rank, gathered at the first run_mpi (one collective, then none)
PEERS: list = []
#: ranks known to be gone (rank 0 tells the live ranks with each run's result)
LOST: set = set()


#: seconds MPI_Finalize may take once a rank was lost (Open MPI 4.1 sometimes never returns
#: from it then: about 1 run in 12 of tests/unit/test_mpi_lost_rank.py's executor script)
_FINALIZE_S = 20.0
_FINALIZE_GUARD: list = []


def mark_lost(rank: int) -> None:
    """Record a lost rank; the first time, finalize MPI at exit with a time limit: past it,
    the process ends with exit code 1 (what a run that lost a rank exits with anyway)."""
    LOST.add(rank)
    if _FINALIZE_GUARD:
        return
    import atexit
    _FINALIZE_GUARD.append(open(os.devnull, "w"))      # noqa: SIM115 - open until exit
    atexit.register(_bounded_finalize)


def _bounded_finalize() -> None:
    import faulthandler
    from mpi4py import MPI
    if MPI.Is_finalized():
        return
    # a C watchdog thread: it needs no GIL and ends the process with _exit(1)
    faulthandler.dump_traceback_later(_FINALIZE_S, exit=True, file=_FINALIZE_GUARD[0])
    try:
        MPI.Finalize()
    finally:
        faulthandler.cancel_dump_traceback_later()


class RootLost(BaseException):
    """Rank 0 is gone (raised on the other ranks; a BaseException, so that no ``except
    Exception`` inside a unit swallows it)."""


def peers(comm) -> list:
    if not PEERS:
        PEERS.extend(comm.allgather((socket.gethostname(), os.getpid())))
    return PEERS


def alive(rank: int) -> bool:
    """False once ``rank`` is known to be gone: lost earlier, or a rank on this node whose
    process no longer runs.  A rank on another node counts as alive (it cannot be seen)."""
    if rank in LOST:
        return False
    if not PEERS:
        return True
    host, pid = PEERS[rank]
    if host != PEERS[world_comm().rank][0]:
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as fh:
            return fh.read().rsplit(")", 1)[-1].split()[0] not in ("Z", "X")   # a zombie
    except FileNotFoundError:
        return False
    except (OSError, IndexError):
        return True


def _poll(test, peer) -> tuple[bool, object]:
    """Call ``test()`` -> (done, value) with a growing pause (0.2 -> 20 ms) until it is done:
    (True, value), or (False, None) once ``peer`` is gone (its pid checked every
    :data:`CHECK_S`)."""
    delay, check = 0.0002, time.monotonic() + CHECK_S
    while True:
        done, value = test()
        if done:
            return True, value
        now = time.monotonic()
        if now >= check:
            if not alive(peer):
                return False, None
            check = now + CHECK_S
        time.sleep(delay)
        delay = min(2 * delay, 0.02)


def wait_for(req, peer) -> tuple[bool, object]:
    """Complete ``req`` (a send to or a receive from ``peer``): (True, value), or
    (False, None) once ``peer`` is gone (the request is then abandoned)."""
    return _poll(req.test, peer)


def send_to(comm, obj, dest: int, tag: int) -> bool:
    """Send ``obj``; False if ``dest`` is gone (then nothing more is sent to it)."""
    return alive(dest) and wait_for(comm.isend(obj, dest=dest, tag=tag), dest)[0]


def recv_root(comm, tag: int):
    """The next message from rank 0 with ``tag``; :class:`RootLost` if rank 0 is gone."""
    def probe():
        m = comm.improbe(source=0, tag=tag)
        return m is not None, m

    ok, m = _poll(probe, 0)
    if ok:
        ok, obj = wait_for(m.irecv(), 0)
        if ok:
            return obj
    raise RootLost


def root_lost() -> LostUnits:
    mark_lost(0)
    host, pid = PEERS[0] if PEERS else ("?", "?")
    return LostUnits(f"rank 0 (pid {pid} on {host}), which writes the files, was lost; every "
                     "item it received is in the partial file: run the same command again to "
                     "compute the rest", {"lost_ranks": [0]})


_HOOK = [0]                                     # items handed over (the test hook's count)


def lose_rank_hook(rank: int) -> None:
    """``VIBROGEAR_TEST_LOSE_RANK=R:N``: rank R dies (SIGKILL) after its N-th item."""
    spec = os.environ.get("VIBROGEAR_TEST_LOSE_RANK")
    if not spec:
        return
    r, n = (int(v) for v in spec.split(":"))
    _HOOK[0] += 1
    if r == rank and _HOOK[0] >= n:
        os.kill(os.getpid(), signal.SIGKILL)


def bcast(value, tag: int = _BCAST):
    """``value`` from rank 0 on every live rank, point to point (a dead rank is skipped
    instead of blocking everyone, as a collective ``bcast`` would); ``tag``: the message
    tag (the executor's final outcome has its own)."""
    comm = world_comm()
    if comm.size < 2:
        return value
    peers(comm)
    if comm.rank == 0:
        for r in range(1, comm.size):
            if r not in LOST and not send_to(comm, value, r, tag):
                mark_lost(r)
        return value
    try:
        return recv_root(comm, tag)
    except RootLost:
        raise root_lost() from None
