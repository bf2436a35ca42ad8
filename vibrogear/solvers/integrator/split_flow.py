"""Orbits with the variational equations on two cores: the tangent's columns split.

The tangent Phi = [d u / d u0 | d u / d param] (n x (n + 1)) of an orbit is n + 1
independent columns riding on one trajectory: step sizes, events and saltation times
depend on the state alone.  So a second process integrates the same trajectory carrying
the upper columns while this one carries the lower ones: the same steps (checked: the
step count and the end state must agree bit for bit, else the orbit is integrated here
whole), each core half the variational work.  On the two-stage gearbox (292 states) the
variational work is ~99 % of an orbit with the monodromy (2 ms without, 0.17 s with).

Used by the continuation (every converged point needs its monodromy) when the model is
big enough to pay for the messages and a second core is free; never under ``mpirun``
(the ranks are the parallelism there) and never inside a worker process.
"""
from __future__ import annotations

import multiprocessing as mp
import os
import signal
import threading
from dataclasses import replace

import numpy as np

from ...pipeline.executors import blas_threads, under_mpi
from .integrate import Trajectory, integrate

__all__ = ["ColumnSplit", "SPLIT_MIN_STATES"]

#: split from this many states on.  One orbit with the monodromy at rtol 1e-6, whole /
#: split, measured in one run each: two-stage gearbox (292 states) 0.174 / 0.106 s,
#: single-stage (160) 71 / 50 ms, gear pair (68) 14.4 / 13.0 ms (the messages and the
#: trajectory computed twice eat most of the gain)
SPLIT_MIN_STATES = 100


def _serve(model, conn):
    """The worker: integrate the requested columns until the parent sends None or goes
    away.  Ctrl-C is the parent's to handle (it closes the pipe)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    with blas_threads(1):
        while True:
            try:
                req = conn.recv()
            except EOFError:                # the parent is gone
                break
            if req is None:
                break
            param, u0, t1, options, c0, c1, h0 = req
            try:
                tr = integrate(model, param, u0, 0.0, t1, options=options, variational=True,
                               columns=(c0, c1), first_step=h0)
                conn.send((tr.tangent_columns, tr.steps, tr.u_end, tr.status))
            except Exception as exc:        # noqa: BLE001  the parent integrates whole
                try:
                    conn.send(exc)
                except OSError:             # the parent is gone
                    break


class ColumnSplit:
    """``with ColumnSplit(model) as split: split.integrate(param, u0, t1, options)``: the
    trajectory of :func:`~.integrate.integrate` with ``variational=True``, its tangent's
    columns shared with one worker process where that pays (``active``), else integrated
    here whole.  The request goes down a pipe from this thread before the local half
    starts (a queue's feeder thread would wait for the GIL the compiled loop holds)."""

    def __init__(self, model, enabled: bool = True):
        n = model.n_states
        self.model = model
        self.active = bool(enabled and n >= SPLIT_MIN_STATES and (os.cpu_count() or 1) > 1
                           and not under_mpi() and mp.parent_process() is None)
        self.half = (n + 1) // 2
        self.proc = self.conn = None
        self.fallbacks = 0          # orbits integrated whole after the halves disagreed

    def __enter__(self):
        if self.active:
            if threading.current_thread() is threading.main_thread():
                # Python ignores SIGPIPE (a write to a dead worker's pipe raises); PETSc,
                # once the housing FE has initialised it in this process, catches it and
                # aborts: ignore it again
                signal.signal(signal.SIGPIPE, signal.SIG_IGN)
            ctx = mp.get_context("fork")
            self.conn, child = ctx.Pipe()
            self.proc = ctx.Process(target=_serve, args=(self.model, child), daemon=True)
            self.proc.start()
            child.close()
        return self

    def __exit__(self, *exc):
        self._stop()
        return False

    def _stop(self):
        if self.proc is not None:
            try:
                self.conn.send(None)
            except OSError:
                pass
            self.proc.join(timeout=5)
            if self.proc.is_alive():
                self.proc.kill()
            self.conn.close()
            self.proc = self.conn = None

    def _whole(self, param, u0, t1, options, first_step=None) -> Trajectory:
        return integrate(self.model, param, u0, 0.0, t1, options=options, variational=True,
                         first_step=first_step)

    def integrate(self, param: float, u0, t1: float, options,
                  first_step: float | None = None) -> Trajectory:
        if self.proc is None:
            return self._whole(param, u0, t1, options, first_step)
        n = self.model.n_states
        u0 = np.ascontiguousarray(u0, dtype=float)
        try:
            if not self.proc.is_alive():
                raise BrokenPipeError("the column worker has died")
            self.conn.send((param, u0, t1, options, self.half, n + 1, first_step))
        except OSError:                     # the worker is gone: the rest here, whole
            self._stop()
            self.fallbacks += 1
            return self._whole(param, u0, t1, options, first_step)
        try:
            low = integrate(self.model, param, u0, 0.0, t1, options=options,
                            variational=True, columns=(0, self.half), first_step=first_step)
        finally:
            try:
                got = self.conn.recv()      # always: the next request must find it empty
            except (EOFError, OSError) as exc:
                got = exc
                self._stop()
        if isinstance(got, Exception):
            self.fallbacks += 1
            return self._whole(param, u0, t1, options, first_step)
        cols, steps, u_end, status = got
        if steps != low.steps or status != low.status or not np.array_equal(u_end,
                                                                            low.u_end):
            self.fallbacks += 1
            return self._whole(param, u0, t1, options, first_step)
        phi = np.concatenate([low.tangent_columns, cols], axis=1)
        return replace(low, monodromy=phi[:, :n].copy(), dparam=phi[:, n].copy(),
                       tangent_columns=None)
