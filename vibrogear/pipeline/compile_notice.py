"""A line on stderr while numba compiles vibrogear's kernels (issue 23, item 5).

The integrator and the contact law are numba functions cached on disk (``cache=True``,
:mod:`vibrogear.models.numba_cache`); on a fresh machine, a fresh ``NUMBA_CACHE_DIR`` or
after an edit of a compiled module the first call compiles them, which takes tens of
seconds with nothing on the screen.  :func:`compile_notice` registers, for a run, a listener
of numba's ``"numba:compile"`` event (fired only on a cache miss: a cached function is
loaded without it) that prints, for the outermost compile of a vibrogear function (the
functions it compiles on the way, vibrogear's or numba's, print nothing)::

    compiling the integrator (first run or changed source; ~30 s, cached afterwards): vibrogear.solvers.integrator.dopri.dopri_loop
    compiled in 31.2 s

The CLI wraps the run in it unless ``--quiet``; the solvers never print.  Under ``mpirun`` only
rank 0 prints; forked workers (:func:`~vibrogear.pipeline.executors.run_units`) that
compile print their own lines.
"""
from __future__ import annotations

import sys
import time
from contextlib import contextmanager

__all__ = ["compile_notice", "CompileNotice", "ESTIMATE"]

#: the packages whose compiles are announced
_PACKAGE = "vibrogear."
#: what a cold compile of the integrator takes: ``vibrogear time configs/impact_pair.toml``
#: with an empty NUMBA_CACHE_DIR compiles dopri_loop (and all it inlines) in 33 s of CPU time
#: (numba 0.68.1; 50 s of wall time on a loaded 2-core machine)
ESTIMATE = "~30 s"


def _name(dispatcher) -> str:
    fn = getattr(dispatcher, "py_func", None)
    if fn is None:
        return ""
    return f"{getattr(fn, '__module__', '')}.{getattr(fn, '__qualname__', fn.__name__)}"


def _line(name: str) -> str:
    """The start line: the integrator with its estimate, any other function without."""
    if ".solvers.integrator." in name:
        return (f"compiling the integrator (first run or changed source; {ESTIMATE}, cached "
                f"afterwards): {name}")
    return f"compiling (first run or changed source; cached afterwards): {name}"


class CompileNotice:
    """The ``"numba:compile"`` listener (registered as a virtual subclass of
    :class:`numba.core.event.Listener`, so that this module imports numba only when used):
    prints at the start and the end of each outermost compile of a vibrogear function."""

    def __init__(self, stream=None):
        self.stream = stream
        self.depth = 0          # vibrogear compiles in progress (nested ones count)
        self.t0 = 0.0
        self.announced = []     # the functions announced (for tests and the summary)

    def _print(self, text: str) -> None:
        from .outcome import is_root_process
        if not is_root_process():
            return
        stream = self.stream if self.stream is not None else sys.stderr
        try:
            print(text, file=stream, flush=True)
        except (OSError, ValueError):       # a closed or broken stream: never fail a compile
            pass

    def on_start(self, ev) -> None:
        name = _name((ev.data or {}).get("dispatcher"))
        if not name.startswith(_PACKAGE):
            return
        self.depth += 1
        if self.depth == 1:
            self.t0 = time.perf_counter()
            self.announced.append(name)
            self._print(_line(name))

    def on_end(self, ev) -> None:
        name = _name((ev.data or {}).get("dispatcher"))
        if not name.startswith(_PACKAGE) or self.depth == 0:
            return
        self.depth -= 1
        if self.depth == 0:
            dt = time.perf_counter() - self.t0
            # the exception of a failed compile (numba 0.68's Event.is_failed is inverted)
            failed = getattr(ev, "_exc_details", None) is not None
            self._print(f"compile failed after {dt:.1f} s" if failed
                        else f"compiled in {dt:.1f} s")

    def notify(self, ev) -> None:
        if ev.is_start:
            self.on_start(ev)
        elif ev.is_end:
            self.on_end(ev)


@contextmanager
def compile_notice(quiet: bool = False, stream=None):
    """``with compile_notice(quiet): run...``: the listener registered for the block (none
    when ``quiet``); yields it (None when quiet)."""
    if quiet:
        yield None
        return
    from numba.core import event
    event.Listener.register(CompileNotice)
    with event.install_listener("numba:compile", CompileNotice(stream)) as listener:
        yield listener
