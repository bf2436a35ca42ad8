"""What both backends of :func:`vibrogear.pipeline.executors.run_units` share: the error a
failed unit raises, the stop signal of ``emit``, the serial run, the MPI communicator and the
transport of an exception between processes.  Its own module so that
:mod:`.mpi_units` (the MPI backend) and :mod:`.executors` (the dispatcher and the process
backend) import it and not each other."""
from __future__ import annotations

__all__ = ["UnitError"]


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


def _comm():
    from mpi4py import MPI
    return MPI.COMM_WORLD


def _deliver(on_result, i, item) -> bool:
    return on_result is None or on_result(i, item) is not False


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


def _transportable(exc: BaseException):
    import pickle
    try:
        return pickle.loads(pickle.dumps(exc))
    except Exception:
        return None
