"""Scene runner: resolves which stages a scene's analyses need and runs only those.

Each (model kind, analysis) pair maps to an analysis and its report writer, named by
``"module:function"`` strings and imported only when that analysis runs, so a scene
without FE parts never imports dolfinx or gmsh.  The contract between them is in
:mod:`vibrogear.pipeline.outcome`: the analysis computes and returns an
:class:`AnalysisOutcome`, the report writer writes files and figures from it.
"""
from __future__ import annotations

import json
import platform
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

from .version import __version__
from .config import Scene
from .analyses.invoke import invoke, load, with_needs
from .config.verbs import VERBS
from .models.scene_notes import derived_lines
from .pipeline.files import atomic_write_text, finite_json
from .pipeline.outcome import (AnalysisOutcome, NumericalFailure, RunContext, Terminated,
                               WriteFailure, is_root_process)
from .report.page.html_report import write_html_report

__all__ = ["RunContext", "ANALYSIS_TABLE", "Entry", "run_scene", "resolve", "NumericalFailure",
           "is_interrupt"]


@dataclass(frozen=True)
class Entry:
    """One (model kind, analysis): the analysis and its report writer as ``"module:function"``
    (imported only when the analysis runs); ``study``: the analysis takes the scene's
    reduced-model study (:mod:`vibrogear.analyses.study`), built once per run."""
    analysis: str
    report: str | None = None
    study: bool = False


#: (model kind, analysis) -> Entry, from the one verb registry (config/verbs.py)
ANALYSIS_TABLE: dict[tuple[str, str], Entry] = {
    (kind, name): Entry(f"vibrogear.analyses.{run.analysis}", f"vibrogear.report.{run.report}", run.study)
    for name, verb in VERBS.items() for kind, run in verb.runs.items()}


def resolve(scene: Scene) -> list[tuple[str, Entry]]:
    """The table entries this scene's analyses need, in order (nothing imported yet)."""
    kind = scene.model_kind
    plan = []
    for analysis in scene.scene.analyses:
        key = (kind, analysis)
        if key not in ANALYSIS_TABLE:
            raise NotImplementedError(f"analysis {analysis!r} is not available for a {kind} scene")
        plan.append((analysis, ANALYSIS_TABLE[key]))
    return plan


def _load_saved(name: str, kind: str, out: Path, previous) -> dict:
    """The saved results a verb reads (``Verb.reads_saved``) whose verb did not run in this
    run: {verb: outcome} with its main ``.npz`` in the output folder as a dict of arrays."""
    loaded = {}
    for dep in VERBS[name].reads_saved:
        run = VERBS[dep].runs.get(kind)
        if dep in previous or run is None:
            continue
        path = Path(out) / next(f for f in run.outputs if f.endswith(".npz"))
        if path.is_file():
            import numpy as np
            with np.load(path, allow_pickle=False) as z:
                loaded[dep] = AnalysisOutcome(summary={"loaded_from": str(path)},
                                              result={k: z[k] for k in z.files})
    return loaded


def write_summary(out: Path, summary: dict) -> None:
    if not is_root_process():
        return  # under mpirun only rank 0 writes files
    atomic_write_text(out / "summary.json", json.dumps(finite_json(summary), indent=2))


def run_scene(scene: Scene, ctx: RunContext, source: str = "", *,
              outcomes: dict | None = None) -> dict:
    """Run every analysis of ``scene`` and its report writer; write ``summary.json``
    after each; return the summary.  The reduced-model study is built once, before the
    first analysis that takes it, and handed to each explicitly.  ``outcomes``: a dict that
    receives each analysis's :class:`AnalysisOutcome` by name (:func:`vibrogear.api.run`).
    ``ctx.out`` None: a run in memory; no report writer runs and no file is written
    (summary.json, report.html, figures, partial files: none)."""
    from .models.validate import validate_scene
    validate_scene(scene)                    # before the output folder exists
    plan = resolve(scene)
    if ctx.out is None:
        return _run_plan(scene, ctx, source, plan, outcomes)
    created = not ctx.out.exists()
    ctx.out.mkdir(parents=True, exist_ok=True)
    try:
        return _run_plan(scene, ctx, source, plan, outcomes)
    except Exception:
        # an input error found while building the model: leave no empty output folder
        if created and ctx.out.is_dir() and not any(ctx.out.iterdir()):
            ctx.out.rmdir()
        raise


def _run_plan(scene: Scene, ctx: RunContext, source: str, plan, outcomes=None) -> dict:
    summary: dict[str, Any] = {
        "scene": scene.scene.name, "source": source, "model": scene.model_kind,
        "analyses": list(scene.scene.analyses),
        # what the scene derives from what its author wrote (loads, engine orders, bearings)
        "derived": derived_lines(scene),
        "versions": {"vibrogear": __version__, "python": platform.python_version(),
                     **_versions()},
        "wall_time_s": {}, "results": {}, "status": "ok",
    }
    t_all = time.perf_counter()
    failure = None
    study = None
    if scene.gearbox is not None and scene.gearbox.couplings and \
            not any(entry.study for _, entry in plan):
        from .analyses.static_load import static_load     # the load path of every gearbox run
        summary["load_path"] = static_load(scene, source=source).load_path.as_dict()
    previous: dict[str, AnalysisOutcome] = {}
    for name, entry in plan:
        t0 = time.perf_counter()
        try:
            if entry.study and study is None:
                from .analyses.study import build_study
                study = build_study(scene, source)
                summary["reduced_model"] = study.title       # "name: m = 146 (21+25+100)"
                if study.load_path is not None:
                    summary["load_path"] = study.load_path.as_dict()
                summary["wall_time_s"]["model"] = time.perf_counter() - t0
                t0 = time.perf_counter()
            # analyses that read earlier outcomes take them as ``previous`` (read-only), with
            # the saved results of verbs that did not run here
            saved = {} if ctx.out is None else _load_saved(name, scene.model_kind, ctx.out,
                                                           previous)
            seen = {**saved, **previous}
            seen = with_needs(name, scene.model_kind, study, scene, ctx, seen)
            outcome = invoke(load(entry.analysis), study if entry.study else None, scene, ctx,
                             seen)
            record = outcome.record()
            if outcome.warnings:
                record["warnings"] = list(outcome.warnings)
            if entry.report is not None and ctx.writes:
                files = load(entry.report)(scene, outcome, ctx.out, MappingProxyType(previous))
                if files:
                    record["files"] = files
            for path in outcome.partial_files:      # the final files exist now
                Path(path).unlink(missing_ok=True)
            summary["results"][name] = record
            previous[name] = outcome
            if outcomes is not None:
                outcomes[name] = outcome
        except (NumericalFailure, ArithmeticError) as exc:
            # ArithmeticError: overflow, a singular or non-finite matrix (e.g. the housing's
            # HousingNumericalError), raised below the analyses; reported with the analysis name
            if not isinstance(exc, NumericalFailure):
                exc = NumericalFailure(f"{name}: {exc}")
            summary["results"][name] = {"status": "failed", "message": str(exc),
                                        **getattr(exc, "record", {})}   # LostUnits: what and how
            summary["status"] = "failed"
            failure = exc
        except (KeyboardInterrupt, SystemError) as exc:
            # Ctrl-C inside compiled (numba) code surfaces as a SystemError whose context
            # is the KeyboardInterrupt
            if not is_interrupt(exc):
                raise
            exc = _interrupt_of(exc)
            by = f"by {exc.name}" if isinstance(exc, Terminated) else "by the user (Ctrl-C)"
            summary["results"][name] = {"status": "interrupted",
                                        "message": f"stopped {by}; run the same command "
                                        "again to resume"}
            summary["status"] = "interrupted"
            summary["resume"] = RESUME_HINT
            if isinstance(exc, Terminated):
                summary["signal"] = exc.name
            failure = exc
        except Exception as exc:                # noqa: BLE001 - re-raised unless a file error
            # a full disk, an I/O error, a folder made read-only (also inside a work unit's
            # callback): the file and the reason
            err = _os_error_of(exc)
            if err is None:
                raise
            exc = WriteFailure(f"{name}: {_file_error(err)}; what finished is kept, run the "
                               "same command again once it can be written")
            summary["results"][name] = {"status": "failed", "message": str(exc)}
            summary["status"] = "failed"
            failure = exc
        summary["wall_time_s"][name] = time.perf_counter() - t0
        if study is not None and study.notes:
            summary["notes"] = list(study.notes)
        if ctx.out is not None:
            failure = _write_run_files(ctx.out, summary, failure, html=False)
        if failure is not None:
            break
    if ctx.root:
        # what the finished results say about the speeds (also after a failure: finished
        # points are never lost)
        from .analyses.findings.findings import run_findings
        findings = run_findings(scene, summary["results"],
                                _in_memory_sources(scene, previous) if ctx.out is None else None,
                                summary.get("load_path"))
        if findings is not None:
            summary["findings"] = findings
        if ctx.out is not None:
            failure = _write_overview(scene, ctx.out, findings, failure,
                                      summary.get("load_path"))
    summary["wall_time_s"]["total"] = time.perf_counter() - t_all
    if ctx.out is not None:
        failure = _write_run_files(ctx.out, summary, failure, html=True)
    if failure is not None:
        raise failure
    return summary


def _in_memory_sources(scene: Scene, outcomes: dict) -> dict:
    """{file name: arrays} of a run in memory: the findings' source files
    (``analyses.findings.SOURCE_FILES``) as the report writers would have written them: a
    ``.npz`` as its result's ``arrays()``, ``erp.csv`` (nvh with a housing) as the columns
    rpm, erp_w, erp_db."""
    import numpy as np

    from .analyses.findings.findings import SOURCE_FILES
    found = {}
    for name, outcome in outcomes.items():
        run, result = VERBS[name].runs.get(scene.model_kind), outcome.result
        if run is None or result is None:
            continue
        for f in run.outputs:
            if f not in SOURCE_FILES:
                continue
            if f.endswith(".npz") and hasattr(result, "arrays"):
                found[f] = result.arrays()
            elif f == "erp.csv" and getattr(result, "erp_w", None) is not None:
                found[f] = {k: np.asarray(getattr(result, k), float)
                            for k in ("rpm", "erp_w", "erp_db")}
    return found


def _write_run_files(out: Path, summary: dict, failure, *, html: bool):
    """summary.json (and report.html, also after a failure); a write error becomes the
    run's failure unless it already has one (which is then the message that matters)."""
    try:
        write_summary(out, summary)
        if html:
            write_html_report(out, summary)
    except OSError as exc:
        if failure is None:
            failure = WriteFailure(_file_error(exc))
    return failure


def _write_overview(scene: Scene, out: Path, findings, failure, load_path=None):
    """The figures the report opens on: the speed-band chart of the findings and the
    drawing of the gearbox."""
    from .report.writers.findings import BAND_CHART, plot_band_chart
    try:
        chart = Path(out) / BAND_CHART
        if findings is None or plot_band_chart(findings, chart) is None:
            chart.unlink(missing_ok=True)        # never an old run's chart
        if scene.gearbox is not None:
            from .report.plots.gearbox_drawing import draw_gearbox
            draw_gearbox(scene, Path(out) / "gearbox.png", load_path)
    except OSError as exc:
        if failure is None:
            failure = WriteFailure(_file_error(exc))
    return failure


def _os_error_of(exc: BaseException) -> OSError | None:
    """The OSError in ``exc``'s chain (None: not a file error)."""
    return _in_chain(exc, OSError)


def _file_error(err: OSError) -> str:
    import errno
    where = err.filename or "a file"
    verb = "could not write" if err.errno in (errno.ENOSPC, errno.EIO, errno.EROFS, errno.EACCES,
                                              errno.EPERM, errno.EDQUOT) else "file error on"
    return f"{verb} {where}: {err.strerror or err}"


#: what an interrupted run says about resuming (summary.json and the command line)
RESUME_HINT = ("finished results and partial files are kept; run the same command again to "
               "resume: points computed with the same physics, grid, options and version are "
               "reused")


def _in_chain(exc: BaseException | None, kind: type):
    """The first exception of type ``kind`` in ``exc``'s cause / context chain, or None."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, kind):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


def _interrupt_of(exc: BaseException) -> KeyboardInterrupt:
    """The KeyboardInterrupt (or :class:`Terminated`) in ``exc``'s chain."""
    return _in_chain(exc, KeyboardInterrupt) or KeyboardInterrupt()


def is_interrupt(exc: BaseException) -> bool:
    """Whether ``exc`` is, or was caused by, a KeyboardInterrupt (Ctrl-C)."""
    return _in_chain(exc, KeyboardInterrupt) is not None


def _versions() -> dict[str, str]:
    out = {}
    for name in ("numpy", "scipy", "numba", "dolfinx", "gmsh"):
        mod = sys.modules.get(name)
        if mod is not None:
            out[name] = str(getattr(mod, "__version__", "?"))
    return out
