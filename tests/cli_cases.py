"""Helpers of the CLI case tables (tests/unit/test_extreme_*.py): the argument list of one
run and the pytest.param entries of a case table."""
from __future__ import annotations

import pytest


def cli_args(verb: str, scene: str, out, overrides) -> list:
    """``verb scene --quiet --out out --set o ...``."""
    args = [verb, scene, "--quiet", "--out", str(out)]
    for o in overrides:
        args += ["--set", o]
    return args


def cases(table) -> list:
    """pytest.param entries, the id being each case's first value (entries that are already
    pytest.param, e.g. the slow ones, keep their marks)."""
    out = []
    for c in table:
        if hasattr(c, "values"):
            out.append(pytest.param(*c.values[1:], marks=c.marks, id=c.values[0]))
        else:
            out.append(pytest.param(*c[1:], id=c[0]))
    return out
