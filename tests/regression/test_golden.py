"""Regression tier: fresh runs against the golden numbers of reviewed runs
(tests/regression/golden/*.json, regenerated only by ``make golden`` and reviewed as a diff).
A failure means behaviour moved: if the move is intended, regenerate and review the diff."""
from __future__ import annotations

import json

import pytest

from regression.cases import CASES, GOLDEN, compare, run_case

pytestmark = pytest.mark.regression


@pytest.mark.parametrize("name", sorted(CASES))
def test_run_matches_golden(name, tmp_path):
    path = GOLDEN / f"{name}.json"
    assert path.exists(), f"no golden file {path}: run `make golden` and review it"
    golden = json.loads(path.read_text())["values"]
    problems = compare(name, run_case(name, tmp_path / name), golden)
    assert not problems, "\n".join(problems)


def test_compare_flags_a_moved_value_and_a_changed_count():
    """The comparison itself: within tolerance passes, a moved fold and a changed point count
    fail, a missing key fails."""
    ref = {"LP_rpm": [5127.65, 5236.54], "points_per_branch": [63, 12]}
    assert compare("x", {"LP_rpm": [5127.65 * (1 + 5e-6), 5236.54], "points_per_branch": [63, 12]},
                   ref) == []
    assert len(compare("x", {"LP_rpm": [5128.0, 5236.54], "points_per_branch": [63, 12]}, ref)) == 1
    assert len(compare("x", {"LP_rpm": [5127.65, 5236.54], "points_per_branch": [64, 12]}, ref)) == 1
    assert len(compare("x", {"LP_rpm": [5127.65]}, ref)) == 2
