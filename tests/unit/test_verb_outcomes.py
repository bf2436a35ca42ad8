"""The verbs that run several solves hand the runner one combined solver outcome
(:meth:`vibrogear.status.Outcome.combine`): their ``summary.json`` entry's ``counters`` are
the sum of the counters of every solve they ran, and a failed solve shows as ``partial``.

Each test wraps the solver functions the verb calls in a spy that keeps every result's
outcome (the solves the verb actually ran, seen from outside its own bookkeeping), runs the
verb on a tiny scene, and compares the entry with the spies' sum.  Where a spy makes one
solve fail (a copy of its result with a failure status), the entry must say ``partial``
with that solve's message."""
from __future__ import annotations

import dataclasses
import json
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from cli_cases import cli_args
from vibrogear.cli import main
from vibrogear.status import Status

from test_extreme_optimize import SCENE as OPTIMIZE_SCENE

ROOT = Path(__file__).resolve().parents[2]
IMPACT = str(ROOT / "configs" / "impact_pair.toml")
GEAR_PAIR = str(ROOT / "configs" / "gear_pair.toml")
HOUSING = str(ROOT / "configs" / "housing_small.toml")


class Spy:
    """Wraps a solver function: keeps every result's outcome; ``fail``: a set of call
    numbers (1-based) whose result is returned as a copy with ``status`` and ``message``
    (``alter(result, status, message)`` makes the copy where the status lives deeper)."""

    def __init__(self, fn, *, fail=(), status=Status.MAX_STEPS, message="injected failure",
                 alter=None):
        self.fn, self.fail, self.status, self.message = fn, set(fail), status, message
        self.alter = alter or (lambda r, st, msg: dataclasses.replace(r, status=st, message=msg))
        self.outcomes = []

    def __call__(self, *args, **kw):
        res = self.fn(*args, **kw)
        if len(self.outcomes) + 1 in self.fail:
            res = self.alter(res, self.status, self.message)
        self.outcomes.append(res.outcome)
        return res


def _sum(*spies) -> dict:
    total = Counter()
    for s in spies:
        for o in s.outcomes:
            total.update(o.counters)
    return dict(total)


def _entry(out: Path, name: str) -> dict:
    return json.loads((out / "summary.json").read_text())["results"][name]


def _run(name, scene, out, overrides) -> dict:
    """``vibrogear run`` of the scene with only analysis ``name``; its summary entry."""
    assert main(cli_args("run", scene, out, [f'scene.analyses=["{name}"]', *overrides])) == 0
    return _entry(out, name)


# ------------------------------------------------------------------ report (precision)

REPORT = ["report.rtols=[1e-4,1e-6]", "report.periods=2", "report.repeats=2",
          "report.shooting_tols=[1e-6,1e-8]"]


def _spy_precision(monkeypatch, **shoot_kw):
    import vibrogear.analyses.precision as mod

    spies = {name: Spy(getattr(mod, name), **(shoot_kw if name == "shoot" else {}))
             for name in ("integrate", "shoot", "static_equilibrium")}
    for name, spy in spies.items():
        monkeypatch.setattr(mod, name, spy)
    return spies


def test_report_counts_every_integration_and_shooting(monkeypatch, tmp_path):
    spies = _spy_precision(monkeypatch)
    e = _run("report", IMPACT, tmp_path / "out", REPORT)
    # 2 JIT warm-ups + 2 rtols x 2 repeats + the transient; 2 tols x 2 repeats of shooting
    assert len(spies["integrate"].outcomes) == 7 and len(spies["shoot"].outcomes) == 4
    assert e["counters"] == _sum(*spies.values())
    assert e["status"] == "ok"
    assert e["solver_wall_s"] == pytest.approx(
        sum(o.wall_s for s in spies.values() for o in s.outcomes))
    # the analysis's own error estimates join the solvers'
    assert "integrator_error_at_min_rtol" in e["error_estimate"]
    assert "accumulated_local_error" in e["error_estimate"]


def test_report_with_a_failed_shooting_is_partial(monkeypatch, tmp_path):
    spies = _spy_precision(monkeypatch, fail={3}, status=Status.NOT_CONVERGED,
                           message="maximum Newton iterations reached (injected)")
    e = _run("report", IMPACT, tmp_path / "out", REPORT)
    assert e["status"] == "partial"
    assert e["message"] == ("1 of 12 solves failed; the first: maximum Newton iterations "
                            "reached (injected)")
    assert e["counters"] == _sum(*spies.values())


# ------------------------------------------------------------------ critical_damping

CRITICAL = ["critical_damping.tol=0.02", "critical_damping.curve_points=1",
            "critical_damping.transient_periods=50", "critical_damping.ds_max=0.1",
            "critical_damping.ds=0.05", "shooting.tol=1e-6", "integration.rtol=1e-6",
            "integration.atol=1e-8"]


def _spy_critical(monkeypatch, **cont_kw):
    import vibrogear.analyses.critical_damping as mod

    spies = {name: Spy(getattr(mod, name), **(cont_kw if name == "continuation" else {}))
             for name in ("integrate", "continuation", "static_equilibrium")}
    for name, spy in spies.items():
        monkeypatch.setattr(mod, name, spy)
    return spies


def test_critical_damping_counts_every_scan(monkeypatch, tmp_path):
    spies = _spy_critical(monkeypatch)
    e = _run("critical_damping", IMPACT, tmp_path / "out", CRITICAL)
    n = len(e["scans"]) + len(e["curve_scans"])
    assert n == len(spies["continuation"].outcomes) == e["continuations"] + 1
    assert e["counters"] == _sum(*spies.values())
    # the continuations' points: those of the scans' period-1 branches
    assert e["counters"]["points"] == sum(s["points"] for s in e["scans"] + e["curve_scans"])
    assert e["status"] == "ok"
    # one wall time, the spine's (the scans' own clocks summed), not a second by hand
    assert e["solver_wall_s"] == pytest.approx(
        sum(s["wall_time"] for s in e["scans"] + e["curve_scans"]))
    doc = json.loads((tmp_path / "out" / "critical_damping.json").read_text())
    assert doc["counters"] == e["counters"] and doc["solver_wall_s"] == e["solver_wall_s"]


def _stopped(res, status, message):
    """A continuation whose period-1 branch stopped (the scan reads the branch's status)."""
    b0 = dataclasses.replace(res.branches[0], status=status, message=message)
    return dataclasses.replace(res, branches=(b0, *res.branches[1:]), status=status,
                               message=message)


def test_critical_damping_with_a_failed_curve_scan_is_partial(monkeypatch, tmp_path):
    """The bracket 0.035 wide halves once to below tol = 0.02: three bisection scans, then
    the one curve scan, the fourth continuation; it stops early (injected), is left out of
    the figure and counted as a failed solve."""
    spies = _spy_critical(monkeypatch, fail={4}, status=Status.NO_START,
                          message="no starting orbit (injected)", alter=_stopped)
    e = _run("critical_damping", IMPACT, tmp_path / "out", CRITICAL)
    assert len(e["scans"]) == 3 and len(spies["continuation"].outcomes) == 4
    assert e["status"] == "partial" and e["curve_scans"] == []
    assert e["message"] == "1 of 4 solves failed; the first: no starting orbit (injected)"
    assert e["counters"] == _sum(*spies.values())


# ------------------------------------------------------------------ reduction_accuracy

REDUCTION = ["reduction_accuracy.rpm=5800",
             "reduction_accuracy.shaft_counts=[10,16]", "reduction_accuracy.housing_counts=[1,1]",
             "reduction_accuracy.transient_periods=5", "reduction_accuracy.record_periods=5",
             "reduction_accuracy.full_model=false", "reduction_accuracy.frequency_level=false"]


def _spy_integrate(monkeypatch, **kw) -> Spy:
    import importlib

    mod = importlib.import_module("vibrogear.solvers.integrator.integrate")  # imported where called
    spy = Spy(mod.integrate, **kw)
    monkeypatch.setattr(mod, "integrate", spy)
    return spy


def test_reduction_accuracy_counts_every_integration(monkeypatch, tmp_path):
    spy = _spy_integrate(monkeypatch)
    e = _run("reduction_accuracy", GEAR_PAIR, tmp_path / "out", REDUCTION)
    assert len(spy.outcomes) == 5              # the warm-up, transient + record per level
    assert e["counters"] == _sum(spy) and e["status"] == "ok"
    # each level's steps: its transient's and its record's
    steps = [o.counters["steps"] for o in spy.outcomes]
    assert [r["steps"] for r in e["levels"]] == [steps[1] + steps[2], steps[3] + steps[4]]


def test_reduction_accuracy_with_a_failed_level_is_partial(monkeypatch, tmp_path):
    spy = _spy_integrate(monkeypatch, fail={3}, message="maximum number of steps reached "
                                                        "(injected)")
    e = _run("reduction_accuracy", GEAR_PAIR, tmp_path / "out", REDUCTION)
    assert e["status"] == "partial"
    assert e["message"] == ("1 of 5 solves failed; the first: maximum number of steps "
                            "reached (injected)")
    assert e["levels"][0]["status"] != "ok" and e["levels"][1]["status"] == "ok"
    assert e["counters"] == _sum(spy)


# ------------------------------------------------------------------ optimize

# the linear impact pair of the optimiser's extreme-input tests, with 4 evaluations on one worker
LINEAR = OPTIMIZE_SCENE.replace("budget = 6\n", "budget = 4\nworkers = 1\n")
assert "workers = 1" in LINEAR


def _spy_analyses(monkeypatch, fail=()):
    """Keeps the solver outcome of every analysis an evaluation runs; the evaluations
    numbered in ``fail`` raise a numerical failure instead."""
    import vibrogear.analyses.optimize.evaluate as mod
    from vibrogear.pipeline.outcome import NumericalFailure

    real, seen = mod.invoke, []

    def invoke(*args, **kw):
        if len(seen) + 1 in fail:
            seen.append(None)
            raise NumericalFailure("time_response: injected failure")
        outcome = real(*args, **kw)
        seen.append(outcome.solver)
        return outcome

    monkeypatch.setattr(mod, "invoke", invoke)
    return seen


def _counts(outcomes) -> dict:
    total = Counter()
    for o in outcomes:
        if o is not None:
            total.update(o.counters)
    return dict(total)


def test_optimize_counts_every_evaluation(monkeypatch, tmp_path):
    scene = tmp_path / "linear.toml"
    scene.write_text(LINEAR)
    seen = _spy_analyses(monkeypatch)
    e = _run("optimize", str(scene), tmp_path / "out", [])
    assert len(seen) == e["evaluations"] == 4 and e["failed_evaluations"] == 0
    assert e["counters"] == _counts(seen) and e["counters"]["steps"] > 0
    assert e["status"] == "ok"
    doc = json.loads((tmp_path / "out" / "optimize.json").read_text())
    assert doc["status"] == "ok" and doc["counters"] == e["counters"]


def test_optimize_with_a_failed_evaluation_is_partial(monkeypatch, tmp_path):
    scene = tmp_path / "linear.toml"
    scene.write_text(LINEAR)
    seen = _spy_analyses(monkeypatch, fail={2})
    e = _run("optimize", str(scene), tmp_path / "out", [])
    assert e["failed_evaluations"] == 1 and e["best"]["feasible"]
    assert e["status"] == "partial"
    assert e["message"] == ("1 of 4 evaluations failed; the first: NumericalFailure: "
                            "time_response: injected failure")
    assert e["counters"] == _counts(seen)


def test_optimize_without_a_feasible_evaluation_says_so(monkeypatch, tmp_path):
    """The domain status (no evaluation met the constraints) stays above the solvers' ok,
    and the failed evaluation is named in its message."""
    scene = tmp_path / "linear.toml"
    scene.write_text(LINEAR)
    seen = _spy_analyses(monkeypatch, fail={1})
    e = _run("optimize", str(scene), tmp_path / "out", [
        'optimize.constraints=[{analysis="time_response",metric="deformation_second_half.'
        'clearance",max=-1}]'])
    assert e["status"] == "no feasible evaluation" and e["feasible_evaluations"] == 0
    assert e["message"].startswith("no evaluation met every constraint; 1 of 4 evaluations "
                                   "failed")
    assert e["counters"] == _counts(seen)


# ------------------------------------------------------------------ housing verbs

HOUSING_SMALL = ["housing.mesh.degree=1", "housing.modes.count=4", "housing.modes.shapes=0"]


@pytest.fixture(scope="module")
def housing_modes_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("housing") / "out"
    assert main(cli_args("run", HOUSING, out, HOUSING_SMALL)) == 0
    return _entry(out, "modes")


def test_housing_modes_hand_their_one_eigen_solve(housing_modes_run):
    """One eigen-solve: its own outcome; counters the solved problem's size (the summary's
    own entries), the wall time the FE stages' (meshing to post-processing, its parts not
    counted twice)."""
    e = housing_modes_run
    assert e["n_modes"] == 4
    assert e["counters"] == {"dofs": e["n_dofs"], "modes": 4,
                             "converged": e["error_estimates"]["n_converged"]}
    t = e["timings_s"]
    stages = ("meshing", "mesh_read", "form_compilation", "assembly", "eigensolve",
              "postprocess")
    if "cache_load" not in t:
        assert e["solver_wall_s"] == pytest.approx(sum(t.get(k, 0.0) for k in stages))
    assert e["error_estimate"]["max_eigen_residual"] == \
        e["error_estimates"]["max_eigen_residual"]
    assert e["status"] == "ok"


def test_housing_convergence_sums_its_meshes(monkeypatch, tmp_path):
    """Each mesh's modes (a stand-in with known sizes: the real small housing's result with
    another DOF count) are counted once; a truncated one makes the study partial."""
    import vibrogear.analyses.housing.convergence as mod
    from vibrogear.models.housing.run import housing_modes
    from vibrogear.config import load_scene

    real = housing_modes(load_scene(HOUSING, tuple(HOUSING_SMALL)).housing, cache=True)
    sizes = []

    def fake(cfg, cache=True):
        k = len(sizes) + 1
        sizes.append(1000 * k)
        f = real.freqs_hz[:cfg.modes.count] * (1 + 0.01 / k)
        return dataclasses.replace(real, n_dofs=1000 * k, freqs_hz=f, n_converged=f.size,
                                   residuals=real.residuals[:f.size],
                                   status="truncated" if k == 2 else "ok",
                                   message="max_count reached (injected)" if k == 2 else "")

    monkeypatch.setattr(mod, "compute_modes", fake)
    out = tmp_path / "out"
    e = _run("housing_convergence", str(ROOT / "configs" / "housing_convergence.toml"), out,
             ["housing_convergence.size_factors=[1.5,1.2,1.0]",
              "housing_convergence.p1_size_factors=[1.0]", "housing_convergence.n_freqs=3"])
    assert e["counters"] == {"dofs": sum(sizes), "modes": 3 * len(sizes),
                             "converged": 3 * len(sizes)}
    assert len(sizes) == 4 and e["status"] == "partial"
    assert e["message"] == "1 of 4 solves failed; the first: max_count reached (injected)"


def test_housing_sweep_counts_the_points_it_computed(monkeypatch, tmp_path):
    """The points run in this process (a stand-in for the worker pool); the resumed point
    was solved by an earlier run and is not counted."""
    import concurrent.futures as cf

    import vibrogear.analyses.housing.sweep as mod
    import vibrogear.models.housing.run as run_mod
    from vibrogear.config import load_scene
    from vibrogear.pipeline.resume import PartialStore

    class Inline:
        def __init__(self, **kw):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def submit(self, fn, *args):
            f = cf.Future()
            f.set_result(fn(*args))
            return f

    monkeypatch.setattr(mod.cf, "ProcessPoolExecutor", Inline)
    spy = Spy(run_mod.housing_modes)
    monkeypatch.setattr(run_mod, "housing_modes", spy)
    sets = [*HOUSING_SMALL, 'scene.analyses=["housing_sweep"]',
            'housing_sweep.parameter="housing.wall_thickness"',
            "housing_sweep.values=[0.015, 0.018, 0.021]", "housing_sweep.n_freqs=3",
            "housing_sweep.reuse=false"]
    out = tmp_path / "out"
    out.mkdir()
    store = PartialStore(out / mod.POINTS_FILE, mod.sweep_signature(load_scene(HOUSING, tuple(sets))))
    store.append({"value": 0.018, "status": "ok", "freqs_hz": [1.0, 2.0, 3.0], "n_dofs": 7,
                  "seconds": 99.0, "counters": {"dofs": 7, "modes": 3, "converged": 3}})
    assert main(cli_args("run", HOUSING, out, sets)) == 0
    e = _entry(out, "housing_sweep")
    assert e["points_resumed"] == 1 and e["points_computed"] == 2 == len(spy.outcomes)
    assert e["counters"] == _sum(spy) and e["status"] == "ok"
    assert e["counters"]["modes"] == 2 * 4 and e["solver_wall_s"] < 99.0
    assert "seconds" not in e
