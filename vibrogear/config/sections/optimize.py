"""[optimize]: design optimisation over any ``--set`` key (``vibrogear optimize SCENE``).

``variables``: the design variables, each a key that ``--set`` accepts (list indices
included: ``gearbox.meshes[1].backlash``) with its bounds ``min`` < ``max`` (``log``: searched
on a log scale; ``integer``: rounded).  ``objective``: a metric of one analysis of the
evaluated scene (``analysis``, a verb of the registry) reduced over the analysis's operating
range (``reduce``), minimised or maximised (``sense``); ``metric`` may also name one of the
variables (the design's own cost, e.g. the least damping).  ``constraints``: metrics with a
lower and/or upper bound (e.g. the count of folds <= 0).  Each evaluation builds the scene
with the variables set and runs ``analyses`` (default: the analyses the objective and the
constraints name).  The checks here need no solve; :meth:`OptimizeConfig.check_scene` builds
the evaluated scene at each variable's bounds, so a key that does not exist, or bounds that
its field does not allow, are found by ``vibrogear check`` (exit 2).
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass

from ..base import ConfigError, as_data, spec
from ..overrides import parse_override, set_path

__all__ = ["OptimizeConfig", "OptimizeVariable", "OptimizeObjective", "OptimizeConstraint",
           "METHODS", "REDUCTIONS", "evaluation_data", "data_with"]


def data_with(base: dict, values: dict) -> dict:
    """A deep copy of the scene data ``base`` with each dotted key of ``values`` (a variable's
    ``key``, e.g. ``gearbox.meshes[1].backlash``) set to its value."""
    data = copy.deepcopy(base)
    for key, value in values.items():
        keys, _ = parse_override(f"{key}=0")
        set_path(data, keys, value)
    return data


#: optimisation methods ("auto": "bounded" for one variable, else the measured choice)
METHODS = ("auto", "bounded", "nelder-mead", "differential-evolution", "tpe")
#: how a metric's values over the operating range become one number
REDUCTIONS = ("max", "min", "mean", "sum", "count", "range")


@dataclass(frozen=True)
class OptimizeVariable:
    key: str = spec(doc="a key that --set accepts, e.g. housing.wall_thickness or "
                    "gearbox.meshes[1].backlash")
    min: float = spec(doc="lower bound")
    max: float = spec(doc="upper bound (> min)")
    log: bool = spec(False, doc="search on a log scale (min > 0)")
    integer: bool = spec(False, doc="round to an integer (e.g. a tooth count)")
    start: float | None = spec(None, doc="start of nelder-mead (default: the middle)")

    def validate(self, path: str) -> None:
        try:
            parse_override(f"{self.key}=0")
        except ConfigError as exc:
            raise ConfigError(f"{path}.key", str(exc).split(": ", 1)[-1]) from None
        if not self.max > self.min:
            raise ConfigError(f"{path}.max", f"must be greater than min = {self.min:g}, got "
                              f"{self.max:g}")
        if self.log and not self.min > 0:
            raise ConfigError(f"{path}.min", f"log = true needs min > 0, got {self.min:g}")
        if self.integer and not math.ceil(self.min) <= math.floor(self.max):
            raise ConfigError(f"{path}.max", f"integer = true needs an integer in [min, max] = "
                              f"[{self.min:g}, {self.max:g}]")
        if self.start is not None and not self.min <= self.start <= self.max:
            raise ConfigError(f"{path}.start", f"must lie in [min, max] = [{self.min:g}, "
                              f"{self.max:g}], got {self.start:g}")

    def value(self, x: float):
        """The value set in the scene: ``x`` clipped to the bounds (rounded if integer)."""
        x = min(max(float(x), self.min), self.max)
        if self.integer:         # the nearest integer inside the bounds
            return min(max(int(round(x)), math.ceil(self.min)), math.floor(self.max))
        return x


@dataclass(frozen=True)
class OptimizeObjective:
    metric: str = spec(doc="a metric of the analysis (rattle_G2, erp_w, max_force_G1, qmax, "
                       "folds, ...) or one of the variables' keys")
    analysis: str | None = spec(None, doc="the verb whose outcome holds the metric (sweep, map, "
                                "nvh, continuation, modes, ...); not needed for a variable")
    reduce: str = spec("max", choices=REDUCTIONS, doc="over the operating range")
    sense: str = spec("min", choices=("min", "max"))


@dataclass(frozen=True)
class OptimizeConstraint:
    metric: str = spec(doc="a metric of the analysis, as for the objective")
    analysis: str | None = spec(None, doc="default: the objective's analysis")
    reduce: str = spec("max", choices=REDUCTIONS)
    min: float | None = spec(None, doc="lower bound of the reduced metric")
    max: float | None = spec(None, doc="upper bound of the reduced metric")
    scale: float = spec(1.0, gt=0.0, doc="the violation is counted in units of scale")

    def validate(self, path: str) -> None:
        if self.min is None and self.max is None:
            raise ConfigError(f"{path}.max", "missing: a constraint needs min and/or max")
        if self.min is not None and self.max is not None and not self.min <= self.max:
            raise ConfigError(f"{path}.max", f"must be >= min = {self.min:g}, got {self.max:g}")


@dataclass(frozen=True)
class OptimizeConfig:
    variables: tuple[OptimizeVariable, ...] = spec(min_len=1, max_len=20)
    objective: OptimizeObjective = spec()
    constraints: tuple[OptimizeConstraint, ...] = spec(())
    analyses: tuple[str, ...] | None = spec(None, min_len=1, doc="the analyses each evaluation "
                                            "runs, in order (default: those the objective and "
                                            "the constraints name)")
    method: str = spec("auto", choices=METHODS)
    budget: int = spec(60, ge=1, le=100_000, doc="evaluations at most")
    workers: int = spec(1, ge=1, le=4096, doc="evaluations at a time (processes or MPI "
                        "ranks) where the method proposes several")
    seed: int = spec(0, ge=0, le=2**32 - 1)
    xtol: float = spec(1e-3, gt=0.0, lt=0.5, doc="stop tolerance as a fraction of each "
                       "variable's range (of its log range)")
    penalty: float = spec(1e3, gt=0.0, doc="added to the objective per unit of constraint "
                          "violation")

    def validate(self, path: str) -> None:
        keys = [v.key for v in self.variables]
        for i, k in enumerate(keys):
            if k in keys[:i]:
                raise ConfigError(f"{path}.variables[{i}].key", f"{k!r} is given twice")
        if self.method == "bounded" and len(keys) != 1:
            raise ConfigError(f"{path}.method", f"'bounded' searches one variable, got "
                              f"{len(keys)}; use 'nelder-mead', 'differential-evolution' or "
                              "'tpe'")
        for name, item in [("objective", self.objective),
                           *((f"constraints[{i}]", c) for i, c in enumerate(self.constraints))]:
            if self.analysis_of(item) is None and item.metric not in keys:
                raise ConfigError(f"{path}.{name}.analysis", "missing: the analysis whose "
                                  f"metric {item.metric!r} is read (or name a variable's key)")
        if not self.evaluated_analyses():
            raise ConfigError(f"{path}.objective.analysis", "missing: nothing to evaluate, "
                              "the objective and every constraint read variables; name the "
                              "analysis of a metric (objective.analysis, a constraint's "
                              "analysis) or give analyses")
        from ..verbs import VERBS
        for i, a in enumerate(self.evaluated_analyses()):
            if a not in VERBS or a == "optimize":
                where = f"analyses[{i}]" if self.analyses else "objective.analysis"
                raise ConfigError(f"{path}.{where}", f"{a!r} is not one of "
                                  f"{', '.join(repr(v) for v in VERBS if v != 'optimize')}")
        if self.analyses:
            for name, item in [("objective", self.objective),
                               *((f"constraints[{i}]", c) for i, c in enumerate(self.constraints))]:
                a = self.analysis_of(item)
                if a is not None and a not in self.analyses:
                    raise ConfigError(f"{path}.{name}.analysis", f"{a!r} is not in "
                                      f"{path}.analyses = {list(self.analyses)}")

    def analysis_of(self, item) -> str | None:
        """The analysis a metric is read from (a constraint defaults to the objective's)."""
        if item.analysis is not None:
            return item.analysis
        if item is not self.objective and item.metric not in {v.key for v in self.variables}:
            return self.objective.analysis
        return None

    def evaluated_analyses(self) -> tuple[str, ...]:
        if self.analyses:
            return tuple(self.analyses)
        names = [self.analysis_of(i) for i in (self.objective, *self.constraints)]
        return tuple(dict.fromkeys(n for n in names if n is not None))

    def check_scene(self, scene, scene_from_dict, path: str = "optimize") -> None:
        """Build the evaluated scene with every variable at its bounds (``scene_from_dict``:
        :func:`vibrogear.config.scene.scene_from_dict`, handed in by ``Scene.validate``):
        names the variable's key (no such key, or its field takes no number) or bound
        (outside the field's range), and the analyses (a verb the model does not have, a
        missing option section)."""
        base = evaluation_data(scene)
        try:
            scene_from_dict(base)
        except ConfigError as exc:
            raise ConfigError(f"{path}.analyses" if self.analyses else f"{path}.objective.analysis",
                              f"the evaluated scene (analyses {list(self.evaluated_analyses())})"
                              f" is invalid: {exc}") from None
        for i, v in enumerate(self.variables):
            errors = {}
            for end in ("min", "max"):
                try:
                    scene_from_dict(data_with(base, {v.key: v.value(getattr(v, end))}))
                except ConfigError as exc:
                    errors[end] = exc
            if len(errors) == 2:
                raise ConfigError(f"{path}.variables[{i}].key", f"{v.key!r} cannot be set to a "
                                  f"number: {errors['min']}") from None
            for end, exc in errors.items():
                raise ConfigError(f"{path}.variables[{i}].{end}", f"{v.key} = "
                                  f"{getattr(v, end):g} is not allowed: {exc}") from None


def evaluation_data(scene) -> dict:
    """The scene as data without [optimize], running the analyses each evaluation runs."""
    data = as_data(scene)
    data.pop("optimize", None)
    data["scene"]["analyses"] = list(scene.optimize.evaluated_analyses())
    return data
