"""The search methods of ``vibrogear optimize``, all on the unit cube u in [0, 1]^n (each
variable's range, or log range, mapped to [0, 1]; :class:`Space`).

Each method minimises a penalised value ``f(u)`` that it gets through ``fbatch(list of u) ->
list of f``: one point at a time (``bounded``, ``nelder-mead``) or a batch that runs on
processes or MPI ranks (``differential-evolution``: one generation; ``tpe``: ``workers``
trials asked at once).  ``fbatch`` raises :class:`BudgetSpent` once the budget of
evaluations is spent; a method otherwise stops on its own criterion (``xtol`` of the unit
range).  Every method is deterministic for a given seed and history, which is what resume
relies on (:mod:`.optimize`: a point already evaluated is read back, not run again).

* ``bounded``: :func:`scipy.optimize.minimize_scalar` (Brent's bounded method: golden section
  and parabolic steps), one variable.
* ``nelder-mead``: :func:`scipy.optimize.minimize` with bounds, from ``start`` (default the
  middle), initial simplex steps of a quarter of each range.
* ``differential-evolution``: :func:`scipy.optimize.differential_evolution`, deferred
  updating (a generation is one batch: the same points whatever the number of workers),
  population 5 per variable (at least 8), no polishing.
* ``tpe``: Optuna's TPE sampler (seeded), batches of ``workers`` trials.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Space", "BudgetSpent", "search", "choose_method"]


class BudgetSpent(Exception):
    """The evaluation budget is spent (stops the method)."""


@dataclass(frozen=True)
class Space:
    """The variables' unit cube: ``values(u)`` -> {key: value set in the scene}."""
    variables: tuple

    @property
    def n(self) -> int:
        return len(self.variables)

    def values(self, u) -> dict:
        out = {}
        for v, t in zip(self.variables, np.clip(np.asarray(u, float).ravel(), 0.0, 1.0)):
            if v.log:
                x = math.exp(math.log(v.min) + float(t) * (math.log(v.max) - math.log(v.min)))
            else:
                x = v.min + float(t) * (v.max - v.min)
            out[v.key] = v.value(x)
        return out

    def unit(self, values: dict) -> np.ndarray:
        out = []
        for v in self.variables:
            x = float(values[v.key])
            out.append((math.log(x / v.min) / math.log(v.max / v.min)) if v.log
                       else (x - v.min) / (v.max - v.min))
        return np.clip(np.array(out), 0.0, 1.0)

    def start(self) -> np.ndarray:
        return np.array([0.5 if v.start is None else Space((v,)).unit({v.key: v.start})[0]
                         for v in self.variables])


def choose_method(cfg) -> str:
    """The method "auto" stands for: one variable ``bounded``; several ``nelder-mead``.
    Measured (docs/optimize.md, "Choosing the method"): on the impact pair's cusp damping
    ``bounded`` 16 evaluations to 6e-6 against 18 (nelder-mead), 56-60 (differential
    evolution) and 60 (tpe) to 4e-5 ... 6e-4; on the two-stage peak ERP (noisy) nelder-mead
    26 evaluations against 40 for the population methods, to the same best within the noise."""
    if cfg.method != "auto":
        return cfg.method
    return "bounded" if len(cfg.variables) == 1 else "nelder-mead"


def search(method: str, space: Space, fbatch, cfg) -> str:
    """Run ``method``; returns why it stopped."""
    f1 = lambda u: fbatch([np.asarray(u, float)])[0]     # noqa: E731
    if method == "bounded":
        from scipy.optimize import minimize_scalar
        r = minimize_scalar(lambda t: f1([t]), bounds=(0.0, 1.0), method="bounded",
                            options={"xatol": cfg.xtol, "maxiter": cfg.budget})
        return f"converged (xtol {cfg.xtol:g} of the range)" if r.success else str(r.message)
    if method == "nelder-mead":
        from scipy.optimize import minimize
        x0 = space.start()
        simplex = [x0]
        for i in range(space.n):
            e = x0.copy()
            e[i] = x0[i] + 0.25 if x0[i] + 0.25 <= 1.0 else x0[i] - 0.25
            simplex.append(e)
        r = minimize(f1, x0, method="Nelder-Mead", bounds=[(0.0, 1.0)] * space.n,
                     options={"xatol": cfg.xtol, "fatol": np.inf, "maxfev": cfg.budget,
                              "initial_simplex": np.array(simplex)})
        return f"converged (xtol {cfg.xtol:g} of the range)" if r.success else str(r.message)
    if method == "differential-evolution":
        from scipy.optimize import differential_evolution
        pop = max(8, 5 * space.n)
        r = differential_evolution(
            f1, [(0.0, 1.0)] * space.n, seed=cfg.seed, popsize=max(1, pop // space.n),
            maxiter=max(1, cfg.budget // pop), tol=0.0, atol=0.0, polish=False,
            updating="deferred", init="latinhypercube",
            workers=lambda func, xs: fbatch([np.asarray(x, float) for x in xs]))
        return str(r.message)
    if method == "tpe":
        return _tpe(space, fbatch, cfg)
    raise ValueError(f"unknown method {method!r}")


def _tpe(space: Space, fbatch, cfg) -> str:
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    sampler = optuna.samplers.TPESampler(seed=cfg.seed, n_startup_trials=max(5, 2 * space.n + 1))
    study = optuna.create_study(direction="minimize", sampler=sampler)
    dist = {f"u{i}": optuna.distributions.FloatDistribution(0.0, 1.0) for i in range(space.n)}
    done = 0
    while done < cfg.budget:
        trials = [study.ask(dist) for _ in range(min(cfg.workers, cfg.budget - done))]
        us = [np.array([t.params[f"u{i}"] for i in range(space.n)]) for t in trials]
        try:
            fs = fbatch(us)
        except BudgetSpent:
            return "budget spent"
        for t, f in zip(trials, fs):
            study.tell(t, f)
        done += len(trials)
    return "budget spent"
