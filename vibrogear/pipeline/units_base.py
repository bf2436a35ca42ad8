"""What both backends of :func:`vibrogear.pipeline.executors.run_units` share: the error a
failed unit raises, the stop signal of ``emit``, the serial run, the MPI communicator and the
transport of an exception between processes.  Its own module so that
:mod:`.mpi_units` (the MPI backend) and :mod:`.executors` (the dispatcher and the process
backend) import it and not each other."""
from __future__ import annotations

import os
from contextlib import contextmanager

__all__ = ["UnitError", "in_unit", "inside_unit", "Terminated", "request_stop", "raise_if_stopped",
           "under_mpi", "is_root",
           "deferred_stop", "stop_deferred"]

#: units of a parallel run_units (a worker process or an MPI rank) running in this process
_DEPTH = [0]


@contextmanager
def in_unit():
    """Marks a unit running on a worker process or MPI rank: a run_units called inside it
    (a sweep inside an optimiser's evaluation) runs serially there (a daemonic worker cannot
    start processes; the MPI ranks are busy with the outer units)."""
    _DEPTH[0] += 1
    try:
        yield
    finally:
        _DEPTH[0] -= 1


def inside_unit() -> bool:
    return _DEPTH[0] > 0


class UnitError(RuntimeError):
    """A work unit raised an exception (``unit``: its index; ``remote``: the traceback
    text from the worker; ``original``: the exception when it could be transported)."""

    def __init__(self, unit: int, remote: str, original: BaseException | None = None):
        self.unit = unit
        self.remote = remote
        self.original = original
        super().__init__(f"work unit {unit} failed:\n{remote}")


class StopUnit(Exception):
    """Raised inside ``emit`` to abandon the current unit (stop requested)."""


def world_comm():
    from mpi4py import MPI
    return MPI.COMM_WORLD


def deliver_result(on_result, i, item) -> bool:
    return on_result is None or on_result(i, item) is not False


def added_units(ret) -> list[tuple[object, float]]:
    """The units that ``on_done`` returned (None, or an iterable of ``(unit, cost)`` pairs)
    as a list of (unit, cost as a float)."""
    if ret is None:
        return []
    out = []
    for pair in ret:
        try:
            unit, cost = pair
        except (TypeError, ValueError):
            raise TypeError("run_units: on_done must return None or (unit, cost) pairs, "
                            f"got the entry {pair!r}") from None
        out.append((unit, float(cost)))
    return out


def run_serial(fn, units, on_result, on_done=None) -> list:
    """Every unit in turn, in index order; the units ``on_done`` adds follow, in the order
    they were added.  A stop (``on_result`` returning False) leaves the rest undone (None)."""
    units = list(units)
    results: list = []
    i = 0
    while i < len(units):
        def emit(item, i=i):
            if not deliver_result(on_result, i, item):
                raise StopUnit
        try:
            results.append(fn(units[i], emit))
        except StopUnit:
            break
        if on_done is not None:
            units.extend(unit for unit, _ in added_units(on_done(i, results[i])))
        i += 1
    return results + [None] * (len(units) - len(results))


def transportable(exc: BaseException):
    import pickle
    try:
        return pickle.loads(pickle.dumps(exc))
    except Exception:
        return None


# ---------------------------------------------------------------- stop signals

class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP (``kill``, ``docker stop``, SLURM, a closed terminal), raised by the
    command line's handler and handled exactly as Ctrl-C: what finished is kept, the run
    says how to resume; the exit code is 128 + the signal number."""

    def __init__(self, signum: int):
        import signal
        self.signum = int(signum)
        self.name = signal.Signals(self.signum).name
        super().__init__(self.name)


#: signals received and not yet acted on (see :func:`request_stop`)
_PENDING: list[int] = []


def request_stop(signum: int) -> None:
    """Record a stop signal that arrived inside :func:`deferred_stop` (worker processes
    being forked: a raise there lands in an at-fork hook, where Python prints it and drops
    it; elsewhere the handler raises :class:`Terminated` at once); the loops that wait on
    workers call :func:`raise_if_stopped`, so the signal is never lost."""
    _PENDING.append(int(signum))


#: > 0 while worker processes are forked: a handler must not raise there (see request_stop)
_DEFER: list[int] = [0]


@contextmanager
def deferred_stop():
    """A stop signal inside this block is only recorded; the caller acts on it after."""
    _DEFER[0] += 1
    try:
        yield
    finally:
        _DEFER[0] -= 1


def stop_deferred() -> bool:
    return _DEFER[0] > 0


def raise_if_stopped() -> None:
    """Raise :class:`Terminated` for a recorded stop signal (once: the record is cleared)."""
    if _PENDING:
        signum = _PENDING[0]
        _PENDING.clear()
        raise Terminated(signum)


def under_mpi() -> bool:
    """True under ``mpirun`` with more than one rank (environment only; no import)."""
    size = os.environ.get("OMPI_COMM_WORLD_SIZE", os.environ.get("PMI_SIZE", "1"))
    try:
        return int(size) > 1
    except ValueError:
        return False


def is_root() -> bool:
    """True except on the MPI ranks other than 0."""
    return os.environ.get("OMPI_COMM_WORLD_RANK", os.environ.get("PMI_RANK", "0")) == "0"
