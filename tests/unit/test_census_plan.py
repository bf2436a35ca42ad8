"""The census as one stream of units (analyses/states/plan.py) and the replay of a run's units
on W workers (pipeline/wall_split.simulate).

* ``simulate`` against makespans worked out by hand: list scheduling of equal units, the
  longest first, and a unit that adds two more when it is done.
* The plan's promise: the branches kept, their notes and their order are those of one
  candidate after the other, whatever the number of workers and the order in which units
  come back.  The impact pair around its folds (zeta = 0.015, folds at Omega = 0.872 and
  0.926: two stable orbits coexist between them) gives eight periodic attractors, and the
  branches of the first ones pass through the others.  Its units are recorded once on one
  worker, then replayed on 1, 2, 3 and 8 workers with unit walls drawn at random (20
  draws): each replay must keep the same branches with the same notes, whatever the
  candidates it took early and dropped.
"""
from __future__ import annotations

import numpy as np
import pytest

from vibrogear.pipeline.wall_split import simulate


def _run_as_wall(unit):
    return [], unit, unit


def test_simulate_hands_out_the_longest_first_to_the_first_free_worker():
    assert simulate([(1.0, 1)] * 4, _run_as_wall, 2)["wall_s"] == 2.0
    # longest first: 3 on one worker, 1 + 1 + 1 on the other
    assert simulate([(1.0, 1), (3.0, 3), (1.0, 1), (1.0, 1)], _run_as_wall, 2)["wall_s"] == 3.0
    # in index order (equal costs) the 3 would start last: 1 + 3 on one worker
    assert simulate([(1.0, 0), (1.0, 0), (1.0, 0), (3.0, 0)], _run_as_wall, 2)["wall_s"] == 4.0
    one = simulate([(1.0, 1), (3.0, 3)], _run_as_wall, 1)
    assert one["wall_s"] == 4.0 and one["unit_work_s"] == 4.0 and one["idle_s"] == 0.0
    with pytest.raises(ValueError, match="workers"):
        simulate([(1.0, 1)], _run_as_wall, 0)


def test_simulate_starts_added_units_when_their_parent_is_done():
    """A 2 s unit adds two 1 s units when done; two 0.5 s units run beside it: one worker
    runs 2 then 1, the other 0.5 + 0.5, waits for the 2 s unit, then 1: wall 3 s."""
    def on_done(_i, value):
        return [(1.0, 5), (1.0, 5)] if value == 2.0 else []

    got = simulate([(2.0, 1), (0.5, 0), (0.5, 0)], _run_as_wall, 2, on_done=on_done)
    assert got["wall_s"] == pytest.approx(3.0, abs=1e-3)
    assert got["units"] == 5 and got["unit_work_s"] == 5.0
    assert got["idle_s"] == pytest.approx(1.0, abs=2e-3)


PAIR = {"zeta": 0.015, "kappa": 0.5, "f_m": 0.55, "f_p": 0.12, "b_r": 1.0}


def _scene(workers):
    from vibrogear.config import scene_from_dict
    return scene_from_dict({
        "scene": {"name": "ip", "analyses": ["states"]}, "impact_pair": dict(PAIR),
        "integration": {"rtol": 1e-8, "atol": 1e-10}, "shooting": {"tol": 1e-10},
        "states": {"omega_min": 0.86, "omega_max": 0.94, "n_points": 5, "starts": 6,
                   "batch": 3, "q_range": [-4.0, 5.0], "v_range": [-4.0, 4.0],
                   "transient_periods": 150, "record_periods": 16, "branches": True,
                   "workers": workers}})


@pytest.fixture(scope="module")
def recorded():
    """Every unit of a one-worker census: {key: (items, value)}; and its notes."""
    from vibrogear.analyses.states import plan as plan_mod
    from vibrogear.analyses.states.states import census_plan
    from vibrogear.analyses.study import build_study
    from vibrogear.pipeline.executors import run_units

    scene = _scene(1)
    plan, ctx = census_plan(build_study(scene), scene)
    first = plan.start()
    units, keep = {}, {}

    def fn(unit, emit):
        items = []
        value = plan_mod.work_unit(ctx, unit, lambda it: (items.append(it), emit(it)))
        if unit[0] == "start":                # each start on its own: units differ with W
            keep.update({("start", i, int(rec.index)): (i, rec) for i, rec in items})
        else:
            keep[_key(unit)] = (items, value)
        return value

    run_units(fn, [u for u, _c in first], workers=1, on_result=plan.on_result,
              on_done=plan.on_done)
    assert plan.finished()
    units.update(keep)
    return units, plan.notes, [b.array("qmax").sum() for b in plan.found], ctx


def _key(unit):
    if unit[0] == "orbit":
        return unit[:3]
    return ("half", unit[3], unit[4], unit[5], np.asarray(unit[2]).tobytes())


def test_the_branches_kept_do_not_depend_on_workers_or_timing(recorded):
    from vibrogear.analyses.states import plan as plan_mod
    from vibrogear.analyses.states.states import census_plan
    from vibrogear.analyses.study import build_study

    units, notes, qmax, ctx = recorded
    periodic = sum(1 for k in units if k[0] == "orbit")
    assert periodic == 8                      # 1 + 2 + 2 + 2 + 1 period-1 attractors
    # branches pass through several attractors: fewer kept than candidates (the rule at work)
    assert 1 <= len(notes) < periodic
    rng = np.random.default_rng(7)
    taken_early = 0
    for draw in range(20):
        w = (1, 2, 3, 8)[draw % 4]
        scene = _scene(w)
        plan, _ = census_plan(build_study(scene), scene)
        halves = []

        def run(unit):
            if unit[0] == "start":
                items = [units[("start", unit[1], int(k))] for k in unit[3]]
                return items, len(items), float(rng.uniform(0.1, 1.0, len(items)).sum())
            key = _key(unit)
            if key not in units:              # a half-branch never taken on one worker
                units[key] = ([], plan_mod.work_unit(ctx, unit, lambda _it: None))
            halves.append(key)
            items, value = units[key]
            return items, value, float(rng.uniform(0.01, 3.0))

        simulate(plan.start(), run, w, on_result=plan.on_result, on_done=plan.on_done)
        assert plan.finished()
        assert plan.notes == notes, (w, draw)
        assert [b.array("qmax").sum() for b in plan.found] == qmax
        halves = [k for k in halves if k[0] == "half"]
        assert len(halves) % 2 == 0 and len(halves) >= 2 * len(notes)
        if w == 1:                            # one worker takes one candidate at a time
            assert len(halves) == 2 * len(notes)
        taken_early += len(halves) - 2 * len(notes)
    assert taken_early > 0                     # some replays took a candidate and dropped it


def test_a_unit_of_unknown_kind_is_refused():
    from vibrogear.analyses.states.plan import work_unit
    with pytest.raises(ValueError, match="unknown work unit"):
        work_unit(None, ("nothing",), lambda _x: None)
