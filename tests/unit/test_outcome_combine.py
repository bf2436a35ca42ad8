"""``Outcome.combine``: one outcome of several solves, counted in one place."""
from __future__ import annotations

import ast
from pathlib import Path

from vibrogear.status import MESSAGES, Outcome, Status

ROOT = Path(__file__).resolve().parents[2]

def test_counters_are_summed_and_error_estimates_are_the_largest():
    a = Outcome(Status.OK, "ok", {"steps": 10, "rhs_calls": 70}, 1.5, {"defect": 1e-6, "x": None})
    b = Outcome(Status.OK, "ok", {"steps": 5, "events": 2}, 0.25, {"defect": 3e-6, "x": None})
    c = Outcome(Status.LEFT_RANGE, "done", {"steps": 1}, 0.25, {"defect": None, "y": 2.0})
    got = Outcome.combine([a, b, c])
    assert got.counters == {"steps": 16, "rhs_calls": 70, "events": 2}
    assert got.error_estimate == {"defect": 3e-6, "x": None, "y": 2.0}
    assert got.wall_s == 2.0 and got.status == Status.OK and got.message == MESSAGES[Status.OK]
    assert Outcome.combine([a, b], wall_s=0.5).wall_s == 0.5    # solves run side by side

def test_status_ok_partial_or_the_one_shared_failure():
    ok = Outcome(Status.OK, "ok", {}, 0.0, {})
    bad = Outcome(Status.MAX_STEPS, "maximum number of steps reached at 3.1", {}, 0.0, {})
    worse = Outcome(Status.NONFINITE, "blew up", {}, 0.0, {})
    assert Outcome.combine([]).status == Status.OK and Outcome.combine([]).counters == {}
    mixed = Outcome.combine([ok, bad, ok, worse])
    assert mixed.status == Status.PARTIAL and not mixed.ok
    assert mixed.message == ("2 of 4 solves failed; the first: maximum number of steps "
                             "reached at 3.1")
    same = Outcome.combine([bad, bad])
    assert (same.status, same.message) == (Status.MAX_STEPS, bad.message)
    assert Outcome.combine([bad, worse]).status == Status.PARTIAL
    given = Outcome.combine([ok, bad], status=Status.OK, message="the map's own")
    assert (given.status, given.message) == (Status.OK, "the map's own")

def test_analyses_that_run_several_solves_hand_one_outcome_to_the_runner():
    """runup (its runs), states (its starts), nnm (its backbones), nvh (its steady points'
    records), critical_damping (its scans), report (its integrations and shootings),
    reduction_accuracy (its levels' integrations), optimize (its evaluations) and the housing
    convergence and sweep (their meshes, points) combine their solves' outcomes and pass them
    as ``solver=``; the map's result combines its rows' sweeps."""
    for rel in ("analyses/runup/runup.py", "analyses/states/states.py", "analyses/nnm.py",
                "analyses/nvh/nvh.py", "analyses/map/map.py", "analyses/critical_damping.py",
                "analyses/precision.py", "analyses/reduction_accuracy.py",
                "analyses/optimize/optimize.py", "analyses/housing/convergence.py",
                "analyses/housing/sweep.py"):
        src = (ROOT / "vibrogear" / rel).read_text()
        calls = [n for n in ast.walk(ast.parse(src)) if isinstance(n, ast.Call)
                 and isinstance(n.func, ast.Attribute) and n.func.attr == "combine"
                 and getattr(n.func.value, "id", "") == "Outcome"]
        assert calls, rel
        assert "solver=" in src, rel
