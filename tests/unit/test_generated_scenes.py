"""Generated scenes (hypothesis, property-based) over the whole schema: every shipped scene,
mutated at any section, key or list entry (other types, extremes, NaN/inf, empty and huge
values, unknown keys, removed keys), is either accepted or refused with a ConfigError that
names a field: ``vibrogear check`` then exits 0 or 2, never with a traceback (issue 24).

200 examples per CI run; ``make test-slow`` runs 2,000 more (another draw).  Examples that once failed are kept below as ``@example`` regression cases.
"""
from __future__ import annotations

import copy
import math
from pathlib import Path

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, example, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from vibrogear.config.base import ConfigError  # noqa: E402
from vibrogear.config.scene import read_toml, scene_from_dict  # noqa: E402
from vibrogear.models.validate import validate_scene  # noqa: E402
from vibrogear.runner import resolve  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENES = {p.name: read_toml(p) for p in sorted((ROOT / "configs").glob("*.toml"))}


def _paths(node, prefix=()):
    """Every (path) to a value in the scene's nested dicts and lists."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield prefix + (k,)
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield prefix + (i,)
            yield from _paths(v, prefix + (i,))


scalars = st.one_of(
    st.none(), st.booleans(),
    st.integers(min_value=-2**70, max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, -1, 1, 0.0, -0.0, 1e-300, 1e308, -1e308, 2**31, 2**63]),
    st.text(max_size=12), st.sampled_from(["", "up", "down", "max", "fixed", "../x", "a" * 300]))
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=3)),
    max_leaves=6)


@st.composite
def mutated_scenes(draw):
    name = draw(st.sampled_from(sorted(SCENES)))
    data = copy.deepcopy(SCENES[name])
    paths = list(_paths(data))
    for _ in range(draw(st.integers(min_value=1, max_value=3))):
        path = draw(st.sampled_from(paths))
        parent = data
        try:
            for k in path[:-1]:
                parent = parent[k]
            action = draw(st.sampled_from(["replace", "replace", "delete", "unknown"]))
            if action == "replace":
                parent[path[-1]] = draw(values)
            elif action == "delete":
                del parent[path[-1]]
            elif isinstance(parent, dict):
                parent[draw(st.text(min_size=1, max_size=10))] = draw(values)
        except (KeyError, IndexError, TypeError):
            pass                                 # an earlier mutation removed the path
    return name, data


def _check(data) -> None:
    """What ``vibrogear check`` does with a scene's data (before any output folder)."""
    scene = scene_from_dict(data, base_dir=ROOT / "configs")
    validate_scene(scene)
    resolve(scene)


@settings(max_examples=200, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(mutated_scenes())
@example(("impact_pair.toml", {"scene": {"name": "x", "analyses": ["sweep"]},
                               "impact_pair": {"zeta": math.nan, "kappa": 0.5, "f_m": 0.55,
                                               "f_p": 0.12, "b_r": 1.0}}))
def test_mutated_scene_is_accepted_or_refused_naming_a_field(case):
    _, data = case
    try:
        _check(data)
    except ConfigError as exc:
        assert str(exc).strip(), "a refusal must say why"


@pytest.mark.slow
@settings(max_examples=2000, deadline=None, derandomize=False,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(mutated_scenes())
def test_2000_mutated_scenes(case):
    test_mutated_scene_is_accepted_or_refused_naming_a_field.hypothesis.inner_test(case)
