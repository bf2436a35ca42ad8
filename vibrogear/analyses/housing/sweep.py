"""Housing geometry sweep (``housing_sweep``): first N frequencies against one parameter.

Points run in parallel worker processes (spawned, OPENBLAS_NUM_THREADS=1), each through the
housing cache.  Every finished point is appended to ``housing_sweep_points.jsonl`` at once
(a :class:`~vibrogear.pipeline.resume.PartialStore`), so a killed sweep resumes where it
stopped, and only a run of the same housing, parameter, values, frequency count and version
does (:func:`sweep_signature`); otherwise the file is set aside.  ``housing_sweep.csv`` and
``housing_sweep.png`` are written at the end by :mod:`vibrogear.report.writers.housing`
(only when every point succeeded; the finished points stay in the resume file).

With ``reuse`` (the default) and an all-hex parametric housing, the points are split into
``processes`` runs of neighbouring values, each solved in order by
:func:`vibrogear.models.housing.sweep.sweep_housing_modes` (every point after a run's first from the
previous point's mesh, factor ordering and modes; no housing cache); a run's points are stored
when it ends.
"""
from __future__ import annotations

import concurrent.futures as cf
import multiprocessing as mp
import os
import time
from dataclasses import dataclass

import numpy as np

from ...pipeline.outcome import AnalysisOutcome, NumericalFailure, is_root_process
from ...pipeline.resume import PartialStore
from ...status import Outcome, Status

__all__ = ["run_sweep", "sweep_point", "sweep_signature", "HousingSweepResult"]

POINTS_FILE = "housing_sweep_points.jsonl"


@dataclass(frozen=True, eq=False)
class HousingSweepResult:
    """The swept ``parameter``, one row (dict: value, n_dofs, ...) per point and the first
    frequencies per point (``freqs``: points x n_freqs, NaN where a point has fewer)."""
    parameter: str
    rows: tuple
    freqs: np.ndarray


def sweep_point(housing: dict, n_freqs: int) -> dict:
    """Worker: one sweep point from a plain housing dict (picklable)."""
    from ...config.base import build
    from ...config.model.housing import HousingConfig
    from ...geometry.housing import MeshingError
    from ...models.housing.fe import HousingSolveError
    from ...models.housing.run import HousingNumericalError, housing_modes

    cfg = build(HousingConfig, housing, "housing")
    t0 = time.perf_counter()
    try:
        res = housing_modes(cfg, cache=True)
    except (MeshingError, HousingSolveError, HousingNumericalError) as exc:
        return {"status": "failed", "message": str(exc)}
    return {"status": "ok", "freqs_hz": [float(f) for f in res.freqs_hz[:n_freqs]], "n_dofs": res.n_dofs,
            "cached": res.cached, "seconds": time.perf_counter() - t0,
            "counters": res.outcome.counters}


def sweep_chain(housings: list, n_freqs: int) -> list[dict]:
    """Worker: the points of one run of neighbouring values (plain housing dicts), each from the
    previous one (:func:`vibrogear.models.housing.sweep.sweep_housing_modes`)."""
    from ...config.base import build
    from ...config.model.housing import HousingConfig
    from ...geometry.housing import MeshingError
    from ...models.housing.fe import HousingSolveError
    from ...models.housing.sweep import sweep_housing_modes

    cfgs = [build(HousingConfig, h, "housing") for h in housings]
    try:
        res = sweep_housing_modes(cfgs, count=n_freqs, reuse=True)
    except (MeshingError, HousingSolveError, ArithmeticError) as exc:
        return [{"status": "failed", "message": str(exc)} for _ in housings]
    return [{"status": "ok", "freqs_hz": [float(f) for f in r.freqs_hz], "n_dofs": r.n_dofs, "cached": False,
             "seconds": r.seconds, "start": r.start, "mesh": r.mesh, "criterion": r.bound,
             "counters": {"dofs": r.n_dofs, "modes": int(np.size(r.freqs_hz)),
                          "lanczos_steps": r.steps, "rhs_solves": r.n_rhs}} for r in res]


def _runs(items: list, k: int) -> list[list]:
    """``items`` in at most ``k`` runs of neighbours, as equal as may be."""
    k = max(1, min(k, len(items)))
    edges = np.linspace(0, len(items), k + 1).round().astype(int)
    return [items[a:b] for a, b in zip(edges[:-1], edges[1:]) if b > a]


def point_outcome(row: dict) -> Outcome:
    """A finished point's solve (a row of the points file) as an
    :class:`~vibrogear.status.Outcome`."""
    return Outcome(Status.OK, Status.OK.message, row.get("counters", {}), row["seconds"], {})


def sweep_signature(scene) -> dict:
    """What the points depend on: the base housing (its cache key: config, data files and
    version), the swept parameter and its values, and the number of frequencies."""
    from ...models.housing.run import housing_cache_key

    opts = scene.housing_sweep
    return {"analysis": "housing_sweep", "physics": housing_cache_key(scene.housing, "modes"),
            "grid": [repr(float(v)) for v in opts.points()],
            "settings": {"parameter": opts.parameter, "n_freqs": opts.n_freqs,
                         **({"reuse": True} if _reusing(scene) else {})}}


def _reusing(scene) -> bool:
    """Whether the sweep of ``scene`` solves its points from the previous ones."""
    from ...models.housing.sweep import reusable

    return bool(scene.housing_sweep.reuse) and reusable(scene.housing) is None


def run_sweep(scene, ctx) -> AnalysisOutcome:
    from ...config.base import as_data

    opts = scene.housing_sweep
    cfgs = opts.housing_points(scene.housing, "housing_sweep")
    values = opts.points()
    if not is_root_process():
        raise NumericalFailure("housing_sweep runs its points in worker processes: start it without mpirun")
    store = None                  # a run in memory (no output folder): nothing resumed or kept
    if ctx.out is not None:
        ctx.out.mkdir(parents=True, exist_ok=True)
        store = PartialStore(ctx.out / POINTS_FILE, sweep_signature(scene))
    done = {float(row["value"]): row for row in (store.items if store is not None else ())}
    todo = [(v, c) for v, c in zip(values, cfgs) if float(v) not in done]
    n = opts.n_freqs
    t0 = time.perf_counter()
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    failures, solves = [], []
    with ctx.progress(len(todo), "housing sweep") as bar:
        with cf.ProcessPoolExecutor(max_workers=min(opts.processes, max(len(todo), 1)),
                                    mp_context=mp.get_context("spawn")) as pool:
            futs = {}
            if _reusing(scene):
                for run in _runs(todo, opts.processes):
                    futs[pool.submit(sweep_chain, [as_data(c) for _, c in run], n)] = [v for v, _ in run]
            else:
                for v, c in todo:
                    d = as_data(c)
                    d["modes"] = {**d["modes"], "count": max(n, c.modes.count)}
                    futs[pool.submit(sweep_point, d, n)] = [v]
            for fut in cf.as_completed(futs):
                out = fut.result()
                for v, res in zip(futs[fut], out if isinstance(out, list) else [out]):
                    row = {"value": float(v), **res}
                    if row["status"] != "ok":
                        failures.append(row)
                        continue
                    if store is not None:
                        store.append(row)
                    done[float(v)] = row
                    solves.append(point_outcome(row))
                    bar.update(1, f"{opts.parameter}={v:g}")
    rows = [done[float(v)] for v in values if float(v) in done]
    freqs = np.full((len(rows), n), np.nan)
    for i, r in enumerate(rows):
        freqs[i, :len(r["freqs_hz"])] = r["freqs_hz"][:n]
    if failures:
        raise NumericalFailure(f"housing_sweep: {len(failures)} point(s) failed, first: "
                               f"{opts.parameter}={failures[0]['value']:g}: {failures[0]['message']}")
    summary = {"parameter": opts.parameter, "values": [r["value"] for r in rows],
               "frequencies_hz": freqs.tolist(), "n_dofs": [r["n_dofs"] for r in rows],
               "points_computed": len(todo), "points_resumed": len(values) - len(todo),
               "resume": store.note if store is not None else ""}
    # the points computed in this run (resumed ones were solved before), over the sweep's
    # own clock (they run side by side)
    return AnalysisOutcome(summary=summary, result=HousingSweepResult(
        parameter=opts.parameter, rows=tuple(rows), freqs=freqs),
        solver=Outcome.combine(solves, wall_s=time.perf_counter() - t0))
