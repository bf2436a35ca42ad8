"""vibrogear from Python: load a scene, change it, run its analyses, read the results.

A few nouns, verbs that return them, nothing written unless asked::

    import vibrogear as vg
    scene = vg.load("configs/gear_pair.toml")                  # a frozen, checked Scene
    scene = scene.replace({"gearbox.meshes[0].backlash": 5e-5,  # the keys of --set
                           "sweep.n_points": 6})
    run = vg.run(scene, ["sweep"])                              # in memory: writes nothing
    sweep = run.results["sweep"]                                # the result object
    sweep.arrays()["qmax"]; fig = sweep.plot()                  # numpy arrays, a Figure
    run.findings["verdict"]                                     # what the run says
    vg.run(scene, out="out/gear_pair")                          # the files the CLI writes

The command line is a thin layer over these functions (:mod:`vibrogear.cli`): ``vibrogear
run SCENE --set k=v --out DIR`` is ``run(load(SCENE, {"k": v}), out=DIR)``.
"""
from __future__ import annotations

import contextlib
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping, Sequence

from .config import ConfigError, Scene
from .pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext, is_root_process

__all__ = ["load", "run", "import_rexs", "check", "compare", "Run", "ConfigError",
           "NumericalFailure"]


def load(path: str | Path, overrides: Mapping[str, Any] | Sequence[str] | None = None) -> Scene:
    """The scene in ``path`` (a scene TOML file, or a REXS model ``.rexs`` / ``.rexsj``,
    imported first), read, overridden and checked as ``vibrogear check`` checks it.

    ``overrides``: ``{key: value}`` with the keys of ``--set`` and Python values
    (``{"sweep.n_points": 6, "gearbox.meshes[0].backlash": 5e-5}``), or ``--set`` strings
    (``["sweep.n_points=6"]``, values in TOML syntax).  A bad file, key or value raises
    :class:`ConfigError` naming the field, its expected type and allowed range."""
    from .config import load_scene
    from .models.validate import validate_scene
    if overrides is None or isinstance(overrides, Mapping):
        scene = load_scene(path, changes=dict(overrides or {}))
    elif isinstance(overrides, str):
        raise ConfigError("overrides", "expected a dict of --set keys and values or a list of "
                          f"'key=value' strings, got the string {overrides!r}")
    else:
        scene = load_scene(path, tuple(overrides))
    return validate_scene(scene)


def import_rexs(path: str | Path, *, housing: str | None = None,
                load_case: int | None = None) -> Scene:
    """The gearbox of a REXS model (``.rexs`` XML, ``.rexsj`` JSON) as a checked scene, as
    ``vibrogear import`` maps it (docs/your-gearbox.md); ``housing``: None (the casing is
    rigid ground) or ``"box"`` (a parametric box housing around the shafts); ``load_case``:
    the load case of the file's load spectrum taken as the operating point (1-based; None:
    the one with the largest duration share).  A model the mapping cannot take raises
    ConfigError listing every problem (each naming the component and attribute).  A STEP
    casing needs its clamped region: use ``vibrogear import --housing CASING.step``."""
    from .config import scene_from_dict
    from .config.rexs import import_rexs as _map, is_rexs_path
    from .models.validate import validate_scene
    if not is_rexs_path(path):
        raise ConfigError(str(path), "expected a REXS file named *.rexs (XML) or *.rexsj (JSON)")
    if housing not in (None, "box"):
        raise ConfigError("housing", f"expected None or 'box', got {housing!r} (a STEP casing: "
                          "`vibrogear import --housing CASING.step --fixed-region ...`)")
    return validate_scene(scene_from_dict(_map(path, housing=housing, load_case=load_case).data))


def check(scene: Scene, *, files: bool = False) -> Scene:
    """``scene`` checked as ``vibrogear check`` checks it beyond its fields (the gear-mesh
    geometry; every analysis available for its model; ``files``: also open a STEP housing);
    ConfigError naming the field, NotImplementedError for an analysis the model lacks."""
    from .models.validate import validate_scene
    from .runner import resolve
    validate_scene(scene, files=files)
    resolve(scene)
    return scene


def with_analyses(scene: Scene, analyses: Sequence[str] | str | None) -> Scene:
    """``scene`` running ``analyses`` (names of verbs, in order) instead of its own list."""
    if analyses is None:
        return scene
    names = [analyses] if isinstance(analyses, str) else list(analyses)
    return scene.replace({"scene.analyses": names})


@dataclass(frozen=True, eq=False)
class Run:
    """What :func:`run` returns.

    ``scene``: the scene that ran.
    ``results``: analysis name -> its result object (``run.results["sweep"]``: the sweep's,
    with ``arrays()``, ``plot()`` and its fields documented by ``help()``); an analysis
    without a result object maps to its summary entry (a dict).
    ``summary``: the run's summary, the dict ``summary.json`` holds (scene,
    analyses, per-analysis ``results`` with status and counters, ``wall_time_s``,
    ``findings``).
    ``out``: the output folder written (None: a run in memory, nothing written).
    ``outcomes``: analysis name -> :class:`~vibrogear.pipeline.outcome.AnalysisOutcome`
    (summary entry, result, solver outcome, warnings)."""
    scene: Scene
    results: Mapping[str, Any]
    summary: dict
    out: Path | None = None
    outcomes: Mapping[str, AnalysisOutcome] = field(default_factory=dict, repr=False)

    @property
    def findings(self) -> dict | None:
        """What the finished results say about the speeds (``summary["findings"]``: verdict,
        bands, events; docs/findings.md); None where the analyses judge no speed range
        (modes, optimize, ...)."""
        return self.summary.get("findings")

    @property
    def status(self) -> str:
        """``ok``, ``failed`` or ``interrupted``: the run as a whole."""
        return self.summary.get("status", "ok")

    def __repr__(self) -> str:
        where = f", out={str(self.out)!r}" if self.out is not None else " (in memory)"
        return (f"Run(scene={self.scene.scene.name!r}, analyses={list(self.results)}, "
                f"status={self.status!r}{where})")


def run(scene: Scene, analyses: Sequence[str] | str | None = None, out: str | Path | None = None,
        *, quiet: bool = True, wait: bool = False, source: str = "") -> Run:
    """Run the analyses of ``scene`` (``analyses``: these verbs instead of the scene's list)
    and return a :class:`Run`.

    ``out=None``: computed in memory; nothing is written (no output folder, no partial
    file, no figure; the housing's mesh and modes may still come from or go to the cache,
    ``vibrogear cache info``).  ``out=DIR``: writes what ``vibrogear run --out DIR`` writes
    (every file of each analysis, ``summary.json``, ``report.html``), under the folder's run
    lock (``wait``: wait for another run holding it, else ConfigError naming it), and a run
    into a folder resumes what an interrupted run there finished.

    ``quiet``: no progress bars and no compile notice on stderr.  Raises
    :class:`ConfigError` (bad input, before anything is computed or written),
    :class:`NumericalFailure` (an analysis failed; with ``out`` what finished is written),
    KeyboardInterrupt (with ``out``: the same call resumes)."""
    from .pipeline.compile_notice import compile_notice
    from .pipeline.files import check_output_dir
    from .runner import run_scene

    scene = check(with_analyses(scene, analyses))
    folder = None if out is None else check_output_dir(out)
    ctx = RunContext(out=folder, quiet=quiet)
    outcomes: dict[str, AnalysisOutcome] = {}
    if folder is None:
        lock = contextlib.nullcontext()
    else:
        from .pipeline.run_lock import RunLock
        lock = RunLock(folder, wait=wait, enabled=is_root_process())
    # compile_notice: a line on stderr while numba compiles (cold cache), unless quiet
    with lock, compile_notice(quiet):
        summary = run_scene(scene, ctx, source=source, outcomes=outcomes)
    results = {name: o.result if o.result is not None else summary["results"].get(name, o.summary)
               for name, o in outcomes.items()}
    return Run(scene=scene, results=MappingProxyType(results), summary=summary, out=folder,
               outcomes=MappingProxyType(outcomes))


def compare(run_a: "Run | str | Path", run_b: "Run | str | Path") -> dict:
    """Two runs' findings side by side (what ``vibrogear compare`` prints): bands added,
    removed and moved, kv peaks, rattle levels, verdicts and windows.  Each run is a
    :class:`Run` (in memory or written) or a run folder holding ``summary.json``;
    ValueError where one has no findings."""
    from .analyses.findings.compare import compare_findings, read_findings

    def findings(r):
        if isinstance(r, Run):
            if not r.findings:
                raise ValueError(f"{r!r}: no findings (run a sweep, map, run-up or states)")
            return {**r.findings, "scene": r.scene.scene.name,
                    "folder": str(r.out) if r.out is not None else "(in memory)"}
        return read_findings(r)
    return compare_findings(findings(run_a), findings(run_b))
