"""What an analysis receives and returns: the contract between the runner, the analyses
and the report writers.

* An analysis is ``run(scene, ctx) -> AnalysisOutcome`` (or ``run(study, scene, ctx)`` for
  the analyses of a reduced model, see :mod:`vibrogear.analyses.study`).  It computes and
  returns; it never writes the final files or draws.  ``ctx.out`` is given only for files
  that make a run resumable (partial files, see :mod:`vibrogear.pipeline.resume`).
* A report writer is ``write(scene, outcome, out, previous) -> dict | None``: it writes the
  analysis' files and figures from ``outcome.result`` (and may overlay the results of
  analyses that ran before it, ``previous``: analysis name -> outcome, read-only).
* Data passes between analyses only as these returned, frozen outcomes.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..status import Outcome, Status
from .units_base import Terminated, is_root
from .progress import Progress

__all__ = ["AnalysisOutcome", "RunContext", "NumericalFailure", "LostUnits", "Terminated",
           "WriteFailure", "is_root_process", "spine"]




class WriteFailure(RuntimeError):
    """A file could not be written (a full disk, an I/O error, a folder that became
    read-only): the message names the file and the system's reason.  Exit code 1; every
    file is written atomically, so none is left half-written, and the same command resumes."""


class NumericalFailure(RuntimeError):
    """A numerical failure that could not be recovered (exit code 1); the message says
    where and why."""


class LostUnits(NumericalFailure):
    """An MPI rank died mid-run (:mod:`vibrogear.pipeline.mpi_units`): the other ranks
    finished every other unit; the message names the units left uncomputed and says how to
    resume (exit code 1, what finished is kept).  ``record``: the same for ``summary.json``
    (``lost_ranks``, ``lost_units`` with each unit's label and rank, ``resume``)."""

    def __init__(self, message: str, record: dict | None = None):
        super().__init__(message)
        self.record = {**(record or {}), "resume": "run the same command again: finished "
                       "results are reused, the lost units are computed"}


#: True except on the MPI ranks other than 0 (only rank 0 writes files)
is_root_process = is_root


@dataclass(frozen=True, eq=False)
class AnalysisOutcome:
    """``summary``: JSON-able entries for ``summary.json``; ``result``: the frozen result
    object the report writer (and later analyses' reports) read; ``partial_files``: files
    that made the run resumable, deleted by the runner once the report has written the
    final files."""
    summary: dict
    result: Any = None
    partial_files: tuple[Path, ...] = ()
    warnings: tuple[str, ...] = field(default=())
    #: the solver's :class:`~vibrogear.status.Outcome` (``result.outcome``): the runner
    #: writes its status, message, counters, wall time and error estimate (:func:`spine`);
    #: the analysis's ``summary`` keeps only its domain entries
    solver: Outcome | None = None

    def record(self) -> dict:
        """The analysis's entry of ``summary.json``: the spine, then the domain entries; an
        analysis's own ``error_estimate`` entries join the solver's."""
        base = spine(self.solver)
        out = {**base, **self.summary}
        if isinstance(base.get("error_estimate"), dict) and \
                isinstance(self.summary.get("error_estimate"), dict):
            out["error_estimate"] = {**base["error_estimate"], **self.summary["error_estimate"]}
        return out


def spine(outcome: Outcome | None) -> dict:
    """What every analysis's summary starts with, from its solver's outcome: ``status``
    (``ok`` where the solver succeeded, ``partial`` where some points failed, else the
    status's name), ``message``, ``counters``, ``solver_wall_s`` and ``error_estimate``.
    No outcome (an analysis without an iterative solver): ``status`` ok."""
    if outcome is None:
        return {"status": "ok"}
    status = "ok" if outcome.ok else "partial" if outcome.status == Status.PARTIAL \
        else outcome.status.text
    return {"status": status, "message": outcome.message, "counters": dict(outcome.counters),
            "solver_wall_s": outcome.wall_s, "error_estimate": dict(outcome.error_estimate)}


@dataclass(frozen=True)
class RunContext:
    """Per-run settings an analysis may use: the output folder (for resume files only; None:
    a run in memory, :func:`vibrogear.api.run` without ``out``, that writes no file at all),
    whether to show progress, and whether this process writes files."""
    out: Path | None
    quiet: bool = False

    @property
    def root(self) -> bool:
        return is_root_process()

    @property
    def writes(self) -> bool:
        """Whether this process writes files (partial files included): it is the root process
        and the run has an output folder."""
        return self.out is not None and self.root

    def progress(self, total: int, label: str) -> Progress:
        return Progress(total, label, quiet=self.quiet)
