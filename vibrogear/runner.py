"""Scene runner: resolves which stages a scene's analyses need and runs only those.

Each (model kind, analysis) pair maps to a function ``fn(scene, ctx) -> dict`` named by
a ``"module:function"`` string and imported only when that analysis runs, so a scene
without FE parts never imports dolfinx or gmsh.
"""
from __future__ import annotations

import dataclasses
import importlib
import json
import math
import os
import platform
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from . import __version__
from .config import Scene
from .pipeline.progress import Progress

__all__ = ["RunContext", "ANALYSIS_TABLE", "run_scene", "resolve", "NumericalFailure"]

ANALYSIS_TABLE: dict[tuple[str, str], str] = {
    ("impact_pair", "time_response"): "vibrogear.analyses.impact:run_time_response",
    ("impact_pair", "sweep"): "vibrogear.analyses.impact:run_sweep",
    ("impact_pair", "continuation"): "vibrogear.analyses.impact:run_continuation",
    ("impact_pair", "report"): "vibrogear.analyses.impact_report:run_report",
    ("impact_pair", "critical_damping"): "vibrogear.analyses.critical_damping:run_critical_damping",
    ("gearbox", "modes"): "vibrogear.analyses.gearbox:run_modes",
    ("gearbox", "time_response"): "vibrogear.analyses.gearbox:run_time_response",
    ("gearbox", "sweep"): "vibrogear.analyses.gearbox:run_sweep",
    ("gearbox", "continuation"): "vibrogear.analyses.gearbox:run_continuation",
    ("gearbox", "reduction_accuracy"): "vibrogear.analyses.reduction_accuracy:run_reduction_accuracy",
    ("rotor", "modes"): "vibrogear.analyses.rotor:run_modes",
    ("rotor", "campbell"): "vibrogear.analyses.rotor:run_campbell",
    ("housing", "modes"): "vibrogear.analyses.housing:run_modes",
    ("housing", "housing_sweep"): "vibrogear.analyses.housing_sweep:run_sweep",
    ("housing", "housing_convergence"): "vibrogear.analyses.housing_study:run_convergence",
}


class NumericalFailure(RuntimeError):
    """A numerical failure that could not be recovered (exit code 1)."""


@dataclass
class RunContext:
    out: Path
    quiet: bool = False
    results: dict[str, Any] = dataclasses.field(default_factory=dict)

    def progress(self, total: int, label: str) -> Progress:
        return Progress(total, label, quiet=self.quiet)


def resolve(scene: Scene) -> list[tuple[str, Callable]]:
    """The analysis functions this scene needs, imported lazily, in order."""
    kind = scene.model_kind
    plan = []
    for analysis in scene.scene.analyses:
        key = (kind, analysis)
        if key not in ANALYSIS_TABLE:
            raise NotImplementedError(f"analysis {analysis!r} is not available for a {kind} scene")
        module, func = ANALYSIS_TABLE[key].split(":")
        plan.append((analysis, getattr(importlib.import_module(module), func)))
    return plan


def _finite_json(obj: Any) -> Any:
    """Replace non-finite floats by None so summary.json never holds NaN/inf."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k): _finite_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite_json(v) for v in obj]
    if hasattr(obj, "item") and hasattr(obj, "dtype"):
        return _finite_json(obj.item())
    return obj


def write_summary(out: Path, summary: dict) -> None:
    if os.environ.get("OMPI_COMM_WORLD_RANK", os.environ.get("PMI_RANK", "0")) != "0":
        return  # under mpirun only rank 0 writes files
    tmp = out / "summary.json.tmp"
    tmp.write_text(json.dumps(_finite_json(summary), indent=2, sort_keys=False))
    tmp.replace(out / "summary.json")


def run_scene(scene: Scene, ctx: RunContext, source: str = "") -> dict:
    """Run every analysis of ``scene``; write ``summary.json``; return the summary."""
    plan = resolve(scene)
    ctx.out.mkdir(parents=True, exist_ok=True)
    summary: dict[str, Any] = {
        "scene": scene.scene.name, "source": source, "model": scene.model_kind,
        "analyses": list(scene.scene.analyses),
        "versions": {"vibrogear": __version__, "python": platform.python_version(),
                     **_versions()},
        "wall_time_s": {}, "results": {}, "status": "ok",
    }
    t_all = time.perf_counter()
    failure = None
    for name, fn in plan:
        t0 = time.perf_counter()
        try:
            summary["results"][name] = fn(scene, ctx)
        except NumericalFailure as exc:
            summary["results"][name] = {"status": "failed", "message": str(exc)}
            summary["status"] = "failed"
            failure = exc
        summary["wall_time_s"][name] = time.perf_counter() - t0
        write_summary(ctx.out, summary)
        if failure is not None:
            break
    summary["wall_time_s"]["total"] = time.perf_counter() - t_all
    write_summary(ctx.out, summary)
    if failure is not None:
        raise failure
    return summary


def _versions() -> dict[str, str]:
    out = {}
    for name in ("numpy", "scipy", "numba", "dolfinx", "gmsh"):
        mod = sys.modules.get(name)
        if mod is not None:
            out[name] = str(getattr(mod, "__version__", "?"))
    return out
