"""Calling an analysis: the one convention the runner and the optimiser's evaluations share.
An analysis is ``module:function`` in :mod:`vibrogear.analyses` (``Verb.runs``); it takes
(study, scene, ctx) or (scene, ctx), and ``previous`` (the earlier outcomes, read-only) where
its signature names it; it returns an :class:`AnalysisOutcome` or a plain summary dict."""
from __future__ import annotations

import importlib
import inspect
from types import MappingProxyType
from typing import Callable

from ..pipeline.outcome import AnalysisOutcome

__all__ = ["load", "as_outcome", "invoke"]


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
