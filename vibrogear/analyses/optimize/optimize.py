"""``vibrogear optimize SCENE``: design optimisation over the scene's ``--set`` keys ([optimize],
:mod:`vibrogear.config.sections.optimize`).

Each evaluation builds the scene with the variables set and runs its analyses
(:mod:`.evaluate`); the search method (:mod:`.methods`) minimises the
penalised value

    f = s * objective + penalty * violation        (s = +1 for sense "min", -1 for "max")

where ``violation`` sums each constraint's excess over its bounds (in units of its
``scale``).  A failed evaluation is recorded with its reason and gets ``f`` = the worst
``f`` of the evaluations before it + ``penalty``; it never stops the run.  The best
evaluation is the feasible one with the least ``s * objective`` (without a feasible one, the
least ``f``, flagged infeasible).

Every finished evaluation is appended at once to ``optimize.partial.jsonl``
(:class:`~vibrogear.pipeline.resume.PartialStore`, the sweeps' one resume rule: reused only
for the same evaluated scene, variables, objective, constraints, method, seed, tolerances
and version; the budget and the workers may change).  On resume the method runs again from
the start; a point it asks for that is in the file is read back, not run again (the methods
are deterministic), so no evaluation is lost or repeated.  Batches of evaluations run on
processes or MPI ranks through :func:`~vibrogear.pipeline.executors.run_units`.
"""
from __future__ import annotations

import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...config.base import as_data
from ...config.sections.optimize import evaluation_data
from ...pipeline.executors import broadcast, run_units
from ...pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ...pipeline.resume import PartialStore, fingerprint
from ...status import Outcome, Status
from .evaluate import Evaluation, evaluate, solver_outcome
from .methods import BudgetSpent, Space, choose_method, search

__all__ = ["OptimizeResult", "run", "PARTIAL_NAME", "penalised", "violation"]

PARTIAL_NAME = "optimize.partial.jsonl"


@dataclass(frozen=True, eq=False)
class OptimizeResult:
    """What :mod:`vibrogear.report.writers.optimize` writes: every evaluation (``history``,
    records in the order the method asked for them, each with ``f``, ``feasible``,
    ``evaluation``), the best one, and the evaluated scene as data (``base``)."""
    history: tuple
    best: dict | None
    variables: tuple              # OptimizeVariable
    objective: object             # OptimizeObjective
    constraints: tuple            # OptimizeConstraint
    method: str
    base: dict
    title: str
    stop: str = ""
    notes: tuple = field(default=())


def violation(cfg, constraint_values) -> float:
    """Sum over the constraints of the excess over their bounds, in units of each scale."""
    total = 0.0
    for c, x in zip(cfg.constraints, constraint_values):
        if c.max is not None and x > c.max:
            total += (x - c.max) / c.scale
        if c.min is not None and x < c.min:
            total += (c.min - x) / c.scale
    return float(total)


#: |f| is capped here: a huge penalty times a huge violation (or the worst f plus the
#: penalty) would overflow to inf, which the methods and the files do not take
F_CAP = 1e300


def penalised(cfg, record: dict, worst: float) -> float:
    """The value the method minimises (module docstring), capped to [-F_CAP, F_CAP];
    ``worst``: the largest finite f of the evaluations before this one (0 if none)."""
    if record["status"] != "ok":
        f = float(worst) + cfg.penalty
    else:
        s = 1.0 if cfg.objective.sense == "min" else -1.0
        f = s * record["objective"] + cfg.penalty * violation(cfg, record["constraints"])
    return float(min(max(f, -F_CAP), F_CAP))      # NaN cannot occur: penalty > 0, finite metrics


def _key(values: dict) -> tuple:
    return tuple((k, repr(v)) for k, v in values.items())


class _Evaluator:
    """``fbatch`` of the methods: the cache of evaluations (resumed ones included), the
    budget, the partial file and the parallel batches."""

    def __init__(self, cfg, space: Space, task: Evaluation, store, resumed: list, bar):
        self.cfg, self.space, self.task, self.store, self.bar = cfg, space, task, store, bar
        self.cache = {_key(r["values"]): r for r in resumed}
        self.history: list[dict] = []
        self.f_of: dict = {}            # key of each point evaluated -> its penalised value
        self.next_index = 1 + max((int(r["index"]) for r in resumed), default=0)
        self.worst = 0.0

    def _record(self, r: dict) -> float:
        if _key(r["values"]) not in self.f_of:
            r = dict(r, f=penalised(self.cfg, r, self.worst),
                     feasible=r["status"] == "ok" and violation(self.cfg, r["constraints"]) == 0,
                     evaluation=len(self.history) + 1)
            if np.isfinite(r["f"]):
                self.worst = max(self.worst, r["f"]) if self.history else r["f"]
            self.history.append(r)
            self.f_of[_key(r["values"])] = r["f"]
            return r["f"]
        return self.f_of[_key(r["values"])]

    def __call__(self, us: list) -> list[float]:
        values = [self.space.values(u) for u in us]
        keys = [_key(v) for v in values]
        # distinct points new to this run, in order; evaluations read back from the partial
        # file count against the budget as they are asked for again
        new = list(dict.fromkeys(k for k in keys if k not in self.f_of))
        room = self.cfg.budget - len(self.history)
        allowed = set(new[:max(room, 0)]) | self.f_of.keys()
        fresh: dict = {}
        for k, v in zip(keys, values):
            if k in allowed and k not in self.cache and k not in fresh:
                fresh[k] = (self.next_index, v)
                self.next_index += 1
        if fresh:
            for r in self._run(list(fresh.values())):
                self.cache[_key(r["values"])] = r
        out = [self._record(self.cache[k]) for k in keys if k in allowed]
        if len(new) > room:
            raise BudgetSpent
        return out

    def _run(self, units: list) -> list[dict]:
        task, store, bar = self.task, self.store, self.bar

        def fn(unit, emit):
            r = evaluate(task, *unit)
            emit(r)
            return r

        def on_result(_, r):
            if store is not None:
                store.append(r)
            bar.update(1, f"#{r['index']} {r['status']}")

        return run_units(fn, units, workers=self.cfg.workers, on_result=on_result)


def run(scene, ctx: RunContext) -> AnalysisOutcome:
    cfg = scene.optimize
    method = choose_method(cfg)
    space = Space(tuple(cfg.variables))
    base = evaluation_data(scene)
    settings = as_data(cfg)
    for k in ("budget", "workers"):
        settings.pop(k, None)
    store, resumed, note = None, [], ""
    if ctx.writes:
        store = PartialStore(Path(ctx.out) / PARTIAL_NAME, {
            "analysis": "optimize", "scene": fingerprint(base), "settings": settings,
            "method": method})
        resumed, note = list(store.items), store.note
    resumed = broadcast(resumed)
    for r in resumed:
        r.pop("kind", None)
    task = Evaluation(base=base, config=cfg,
                      scratch=None if ctx.out is None else str(Path(ctx.out) / "optimize_evals"))
    t0 = time.perf_counter()
    with ctx.progress(cfg.budget, f"optimize ({method})") as bar:
        if resumed:
            bar.update(0, f"{len(resumed)} resumed")
        ev = _Evaluator(cfg, space, task, store, resumed, bar)
        try:
            stop = search(method, space, ev, cfg)
        except BudgetSpent:
            stop = f"budget of {cfg.budget} evaluations spent"
        finally:
            if task.scratch is not None:                        # the evaluations' scratch
                shutil.rmtree(task.scratch, ignore_errors=True)
    # evaluations in the file that this run's method did not ask for again: kept
    for r in resumed:
        if _key(r["values"]) not in ev.f_of:
            ev._record(r)
    wall = time.perf_counter() - t0
    history = ev.history
    best = _best(cfg, history)
    failed = [h for h in history if h["status"] != "ok"]
    if best is None:
        raise NumericalFailure(f"optimize: all {len(history)} evaluations failed (kept in "
                               f"{PARTIAL_NAME}); first: {failed[0]['reason'] if failed else stop}")
    solver = _solver(history, wall)
    summary = {
        **({} if best["feasible"] else {
            "status": "no feasible evaluation",
            "message": "no evaluation met every constraint"
                       + ("" if solver.ok else f"; {solver.message}")}),
        "method": method, "stop": stop, "evaluations": len(history),
        "resumed_evaluations": len({_key(r["values"]) for r in resumed}
                                   & {_key(h["values"]) for h in history}),
        "failed_evaluations": len(failed),
        "feasible_evaluations": sum(1 for h in history if h["feasible"]),
        "best": {
            "evaluation": best["evaluation"], "values": best["values"],
            "objective": best["objective"], "constraints": best["constraints"],
            "feasible": best["feasible"]},
        "objective": {"analysis": cfg.objective.analysis, "metric": cfg.objective.metric,
                      "reduce": cfg.objective.reduce, "sense": cfg.objective.sense},
        "evaluation_wall_s": float(sum(h.get("wall_s", 0.0) for h in history)),
        "evaluation_cpu_s": float(sum(h.get("cpu_s", 0.0) for h in history)),
        **({"resume": note} if note else {}),
        **({"first_failure": failed[0]["reason"]} if failed else {}),
    }
    result = OptimizeResult(history=tuple(history), best=best, variables=tuple(cfg.variables),
                            objective=cfg.objective, constraints=tuple(cfg.constraints),
                            method=method, base=base, stop=stop,
                            title=f"{scene.scene.name}: {cfg.objective.sense} "
                                  f"{_objective_text(cfg)}")
    return AnalysisOutcome(summary=summary, result=result,
                           partial_files=() if store is None else (store.path,), solver=solver)


def _solver(history: list, wall: float) -> Outcome:
    """The optimisation's solver outcome: every evaluation's solves combined (counters
    summed; resumed evaluations included, as they are in the history), over the run's own
    clock (evaluations run side by side).  Status: partial where an evaluation failed (its
    reason the message: a failed evaluation is penalised, it does not stop the run), else
    that of the solves (:meth:`~vibrogear.status.Outcome.combine`)."""
    solves = [solver_outcome(h) for h in history]
    failed = [h for h in history if h["status"] != "ok"]
    if failed:
        return Outcome.combine(solves, status=Status.PARTIAL, wall_s=wall, message=(
            f"{len(failed)} of {len(history)} evaluations failed; the first: "
            f"{failed[0]['reason']}"))
    return Outcome.combine(solves, wall_s=wall)


def _objective_text(cfg) -> str:
    o = cfg.objective
    if cfg.analysis_of(o) is None:
        return o.metric
    return f"{o.reduce} {o.metric} ({cfg.analysis_of(o)})"


def _best(cfg, history: list) -> dict | None:
    s = 1.0 if cfg.objective.sense == "min" else -1.0
    feasible = [h for h in history if h["feasible"]]
    if feasible:
        return min(feasible, key=lambda h: (s * h["objective"], h["evaluation"]))
    ok = [h for h in history if h["status"] == "ok"]
    return min(ok, key=lambda h: (h["f"], h["evaluation"])) if ok else None
