"""Calling an analysis: the one convention the runner and the optimiser's evaluations share.
An analysis is ``module:function`` in :mod:`vibrogear.analyses` (``Verb.runs``); it takes
(study, scene, ctx) or (scene, ctx), and ``previous`` (the earlier outcomes, read-only) where
its signature names it; it returns an :class:`AnalysisOutcome` or a plain summary dict.
What a verb needs from another (``Verb.needs``) is run here first (:func:`with_needs`), so
that no analysis imports or calls another verb's analysis."""
from __future__ import annotations

import importlib
import inspect
from types import MappingProxyType
from typing import Callable

from ..config.verbs import VERBS
from ..pipeline.outcome import AnalysisOutcome

__all__ = ["load", "as_outcome", "invoke", "with_needs"]


def load(target: str) -> Callable:
    """The function of ``"package.module:function"``."""
    module, func = target.split(":")
    return getattr(importlib.import_module(module), func)


def as_outcome(value) -> AnalysisOutcome:
    """Analyses return an AnalysisOutcome; a plain dict is a summary without a result."""
    return value if isinstance(value, AnalysisOutcome) else AnalysisOutcome(summary=dict(value))


def invoke(fn: Callable, study, scene, ctx, previous: dict) -> AnalysisOutcome:
    """``fn`` called by the convention above (``study`` None: it takes none)."""
    args = (scene, ctx) if study is None else (study, scene, ctx)
    kw = {"previous": MappingProxyType(dict(previous))} \
        if "previous" in inspect.signature(fn).parameters else {}
    return as_outcome(fn(*args, **kw))


def with_needs(name: str, kind: str, study, scene, ctx, previous) -> dict:
    """``previous`` plus the outcome of each verb that verb ``name`` needs
    (``Verb.needs``) and that is not in it: that verb's analysis for model ``kind``, run
    here with the same study (its files are not written; it gets no summary entry)."""
    seen = dict(previous)
    for dep in VERBS[name].needs:
        if dep not in seen:
            run = VERBS[dep].runs[kind]
            seen[dep] = invoke(load(f"vibrogear.analyses.{run.analysis}"),
                               study if run.study else None, scene, ctx, seen)
    return seen
