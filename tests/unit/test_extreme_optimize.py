"""Extreme and degenerate ``vibrogear optimize`` input (issue 24, item 6): each case gives
exit 2 naming the field before anything is written, or runs to an explicit outcome: every
evaluation ``ok`` with finite numbers or ``failed`` with its reason, the summary's status
("ok", "no feasible evaluation") or exit 1 when every evaluation failed; never NaN or inf
beside an ``ok``.

The scene is a linear oscillator (the impact pair inside its clearance) whose objective is
the amplitude of a 10-period time response: one evaluation takes milliseconds."""
from __future__ import annotations

import csv
import json
import math
import re
from pathlib import Path

import pytest

from cli_cases import cases, cli_args

from vibrogear.analyses.optimize.optimize import F_CAP, penalised
from vibrogear.cli import main
from vibrogear.config import load_scene

SCENE = """
[scene]
name = "linear"
analyses = ["optimize"]

[impact_pair]
zeta = 0.1
kappa = 0.5
f_m = 0.0
f_p = 0.05
b_r = 1.0

[integration]
rtol = 1e-6
atol = 1e-8

[time_response]
omega = 0.8
periods = 10
samples_per_period = 16

[optimize]
variables = [{ key = "impact_pair.kappa", min = 0.3, max = 1.0 }]
objective = { analysis = "time_response", metric = "deformation_second_half.clearance", reduce = "max", sense = "max" }
budget = 6
xtol = 1e-2
"""

AMP = "deformation_second_half.clearance"
TR = f'analysis="time_response",metric="{AMP}"'


def _var(**kw) -> str:
    body = ",".join(f"{k}={json.dumps(v) if isinstance(v, str) else _num(v)}"
                    for k, v in kw.items())
    return "{" + body + "}"


def _num(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v)


def _vars(*items) -> str:
    return "optimize.variables=[" + ",".join(items) + "]"


KAPPA = _var(key="impact_pair.kappa", min=0.3, max=1.0)


@pytest.fixture
def scene(tmp_path) -> str:
    p = tmp_path / "linear.toml"
    p.write_text(SCENE)
    return str(p)


_args = cli_args


# ------------------------------------------------------------------ rejected input (exit 2)

BAD = [
    ("budget-0", ["optimize.budget=0"], "optimize.budget"),
    ("budget-negative", ["optimize.budget=-1"], "optimize.budget"),
    ("no-variables", ["optimize.variables=[]"], "optimize.variables"),
    ("range-of-zero-width", [_vars(_var(key="impact_pair.kappa", min=0.5, max=0.5))],
     "optimize.variables[0].max"),
    ("min-above-max", [_vars(_var(key="impact_pair.kappa", min=1.0, max=0.3))],
     "optimize.variables[0].max"),
    ("log-from-zero", [_vars(_var(key="impact_pair.b_r", min=0.0, max=1.0, log=True))],
     "optimize.variables[0].min"),
    ("start-outside", [_vars(_var(key="impact_pair.kappa", min=0.3, max=1.0, start=2.0))],
     "optimize.variables[0].start"),
    ("key-twice", [_vars(KAPPA, KAPPA)], "optimize.variables[1].key"),
    ("unknown-key", [_vars(_var(key="impact_pair.kapa", min=0.3, max=1.0))],
     "optimize.variables[0].key"),
    ("bound-outside-field", [_vars(_var(key="impact_pair.zeta", min=0.1, max=1.5))],
     "optimize.variables[0].max"),
    ("nan-bound", ["optimize.variables=[{key=\"impact_pair.kappa\",min=nan,max=1.0}]"],
     "optimize.variables[0].min"),
    # regression: no integer in [1.2, 1.4]; every evaluation ran at 1, outside the bounds
    ("integer-without-integer", [_vars(_var(key="time_response.periods", min=1.2, max=1.4,
                                            integer=True))], "optimize.variables[0].max"),
    ("bounded-two-variables", ['optimize.method="bounded"',
                               _vars(KAPPA, _var(key="impact_pair.zeta", min=0.01, max=0.5))],
     "optimize.method"),
    ("unknown-method", ['optimize.method="simplex"'], "optimize.method"),
    ("constraint-without-bounds", [f"optimize.constraints=[{{{TR}}}]"],
     "optimize.constraints[0].max"),
    ("constraint-min-above-max", [f"optimize.constraints=[{{{TR},min=1,max=0}}]"],
     "optimize.constraints[0].max"),
    ("constraint-scale-0", [f"optimize.constraints=[{{{TR},max=1,scale=0}}]"],
     "optimize.constraints[0].scale"),
    ("xtol-0", ["optimize.xtol=0"], "optimize.xtol"),
    ("xtol-half", ["optimize.xtol=0.5"], "optimize.xtol"),
    ("penalty-0", ["optimize.penalty=0"], "optimize.penalty"),
    ("workers-0", ["optimize.workers=0"], "optimize.workers"),
    ("no-analyses", ["optimize.analyses=[]"], "optimize.analyses"),
    # the objective is a variable and nothing else is read: no analysis to run (the message
    # named the evaluated scene's empty scene.analyses)
    ("nothing-to-evaluate", ['optimize.objective={metric="impact_pair.kappa",sense="min"}'],
     "optimize.objective.analysis"),
    ("unknown-analysis", [f'optimize.objective={{analysis="swep",metric="{AMP}"}}'],
     "optimize.objective.analysis"),
]


@pytest.mark.parametrize("overrides, field", [c[1:] for c in BAD], ids=[c[0] for c in BAD])
def test_degenerate_input_exits_2_naming_the_field(scene, tmp_path, capsys, overrides, field):
    out = tmp_path / "out"
    assert main(_args("check", scene, out, overrides)) == 2
    err = capsys.readouterr().err
    assert f"invalid input: {field}" in err, err
    assert main(_args("optimize", scene, out, overrides)) == 2
    assert f"invalid input: {field}" in capsys.readouterr().err
    assert not out.exists()


# ------------------------------------------------------------------ extreme but valid input

def _rows(out: Path) -> list[dict]:
    with open(out / "optimize.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def _check_history(out: Path, doc: dict, bounds: dict, budget: int) -> list[dict]:
    """Every evaluation: ok with finite numbers, or failed with a reason; the values inside
    the bounds; no more evaluations than the budget; no NaN/inf in the files."""
    rows = _rows(out)
    assert 1 <= len(rows) == doc["evaluations"] <= budget
    for text in ((out / "optimize.json").read_text(), (out / "summary.json").read_text()):
        assert "NaN" not in text and "Infinity" not in text
    for r in rows:
        assert r["status"] in ("ok", "failed"), r
        assert math.isfinite(float(r["penalised"])), r
        for key, (lo, hi) in bounds.items():
            assert lo <= float(r[key]) <= hi, (key, r)
        numbers = [v for k, v in r.items() if k.startswith(("objective_", "constraint_"))]
        if r["status"] == "ok":
            assert all(math.isfinite(float(v)) for v in numbers), r
            assert r["reason"] == ""
        else:
            assert r["reason"] and all(v == "" for v in numbers), r
    assert doc["failed_evaluations"] == sum(r["status"] == "failed" for r in rows)
    return rows


def _best_in_history(doc, rows):
    best = doc["best"]
    row = rows[best["evaluation"] - 1]
    assert row["status"] == "ok"
    assert float(row[next(k for k in row if k.startswith("objective_"))]) == best["objective"]
    return best


def _budget_one(doc, rows, out):
    assert doc["evaluations"] == 1 and doc["status"] == "ok"
    assert rows[0]["status"] == "ok" and doc["best"]["evaluation"] == 1


def _tiny_range(doc, rows, out):
    """A range of 1e-10: every evaluation gives the same amplitude to 1e-9."""
    objs = [float(r[f"objective_max_{AMP}"]) for r in rows]
    assert max(objs) - min(objs) < 1e-9 * max(objs) and doc["status"] == "ok"


def _log_range(doc, rows, out):
    """b_r from 1e-300 to 1e300: a clearance of any size; the response stays finite and
    below the linear oscillator's (kappa + (1 - kappa) = 1 in contact, kappa alone free)."""
    assert doc["status"] == "ok" and all(r["status"] == "ok" for r in rows)
    assert all(0 < float(r[f"objective_max_{AMP}"]) < 1.0 for r in rows)


def _huge_penalty(doc, rows, out):
    """penalty 1e300 x a violation of 1e10: capped at F_CAP, not inf (regression)."""
    assert doc["status"] == "no feasible evaluation" and not doc["best"]["feasible"]
    assert all(float(r["penalised"]) == F_CAP for r in rows)


def _infeasible(doc, rows, out):
    assert doc["status"] == "no feasible evaluation" and doc["feasible_evaluations"] == 0
    assert not doc["best"]["feasible"]
    assert all(r["feasible"] == "false" and float(r["penalised"]) > 0 for r in rows)


def _count(doc, rows, out):
    assert all(float(r[f"objective_count_{AMP}"]) == 2.0 for r in rows)


def _coarse_xtol(doc, rows, out):
    """A tolerance of half the range: the bounded search stops on it after its first
    golden-section points (measured: 3), far inside the budget of 100."""
    assert "converged" in doc["stop"] and doc["evaluations"] < 10


def _fine_xtol(doc, rows, out):
    """A tolerance below what the objective resolves: the search ends by one of its two
    stops, with its reason (the budget bounds the count by itself)."""
    assert ("converged" in doc["stop"] or "budget" in doc["stop"]) and doc["evaluations"] >= 3


def _one_integer(doc, rows, out):
    """integer in [2.5, 3.4]: 3 is the only value; every method call reads it back."""
    assert doc["evaluations"] == 1 and int(rows[0]["time_response.periods"]) == 3


def _variable_objective(doc, rows, out):
    """The objective is a variable (a constraint every zeta meets): the least zeta is its
    lower bound."""
    assert doc["status"] == "ok"
    assert doc["best"]["values"]["impact_pair.zeta"] == pytest.approx(0.01, abs=0.02)  # xtol


def _zero_load(doc, rows, out):
    """No forcing at all (f_m = f_p = 0): the response is exactly zero, a finite objective."""
    assert all(float(r[f"objective_max_{AMP}"]) == 0.0 for r in rows)


VALID = [
    ("budget-1-bounded", ["optimize.budget=1"], {"impact_pair.kappa": (0.3, 1.0)}, 1,
     _budget_one),
    ("budget-1-nelder-mead", ["optimize.budget=1", 'optimize.method="nelder-mead"'],
     {"impact_pair.kappa": (0.3, 1.0)}, 1, _budget_one),
    ("budget-1-differential-evolution", ["optimize.budget=1",
                                         'optimize.method="differential-evolution"'],
     {"impact_pair.kappa": (0.3, 1.0)}, 1, _budget_one),
    ("budget-1-tpe", ["optimize.budget=1", 'optimize.method="tpe"'],
     {"impact_pair.kappa": (0.3, 1.0)}, 1, _budget_one),
    ("range-1e-10", [_vars(_var(key="impact_pair.kappa", min=0.5, max=0.5000000001))],
     {"impact_pair.kappa": (0.5, 0.5000000001)}, 6, _tiny_range),
    ("log-range-600-decades", [_vars(_var(key="impact_pair.b_r", min=1e-300, max=1e300,
                                          log=True))],
     {"impact_pair.b_r": (1e-300, 1e300)}, 6, _log_range),
    ("huge-penalty", ["optimize.penalty=1e300", f"optimize.constraints=[{{{TR},max=-1e10}}]"],
     {"impact_pair.kappa": (0.3, 1.0)}, 6, _huge_penalty),
    ("never-feasible", [f"optimize.constraints=[{{{TR},max=-1}}]"],
     {"impact_pair.kappa": (0.3, 1.0)}, 6, _infeasible),
    ("reduce-count", [f'optimize.objective={{{TR},reduce="count",sense="min"}}'],
     {"impact_pair.kappa": (0.3, 1.0)}, 6, _count),
    ("xtol-0.49", ["optimize.xtol=0.49", "optimize.budget=100"],
     {"impact_pair.kappa": (0.3, 1.0)}, 100, _coarse_xtol),
    ("xtol-1e-12", ["optimize.xtol=1e-12", "optimize.budget=12"],
     {"impact_pair.kappa": (0.3, 1.0)}, 12, _fine_xtol),
    ("largest-seed-tpe", ["optimize.seed=4294967295", 'optimize.method="tpe"'],
     {"impact_pair.kappa": (0.3, 1.0)}, 6, None),
    ("one-integer", [_vars(_var(key="time_response.periods", min=2.5, max=3.4,
                                integer=True))], {"time_response.periods": (3, 3)}, 6,
     _one_integer),
    ("objective-is-a-variable", [_vars(_var(key="impact_pair.zeta", min=0.01, max=0.99)),
                                 'optimize.objective={metric="impact_pair.zeta",sense="min"}',
                                 f"optimize.constraints=[{{{TR},max=10}}]",
                                 "optimize.budget=30"],
     {"impact_pair.zeta": (0.01, 0.99)}, 30, _variable_objective),
    ("zero-load", ["impact_pair.f_p=0.0"], {"impact_pair.kappa": (0.3, 1.0)}, 6, _zero_load),
    ("near-critical-damping", ["impact_pair.zeta=0.999"],
     {"impact_pair.kappa": (0.3, 1.0)}, 6, None),
]


@pytest.mark.parametrize("overrides, bounds, budget, check", cases(VALID, ci=(
    "log-range-600-decades", "never-feasible", "zero-load")))      # the rest: make test-system
def test_extreme_input_runs_to_an_explicit_outcome(scene, tmp_path, overrides, bounds, budget,
                                                   check):
    out = tmp_path / "out"
    assert main(_args("optimize", scene, out, overrides)) == 0
    doc = json.loads((out / "optimize.json").read_text())
    summary = json.loads((out / "summary.json").read_text())
    assert summary["results"]["optimize"]["status"] == doc["status"]
    assert doc["status"] in ("ok", "no feasible evaluation")
    rows = _check_history(out, doc, bounds, budget)
    _best_in_history(doc, rows)
    assert not (out / "optimize.partial.jsonl").exists()
    if check is not None:
        check(doc, rows, out)


def test_every_evaluation_failing_exits_1_and_keeps_them(scene, tmp_path, capsys):
    """max_steps 1 .. 3: every time response fails; exit 1 naming the first reason, the
    evaluations kept in the partial file (each with its reason), no result files."""
    out = tmp_path / "out"
    code = main(_args("optimize", scene, out, [_vars(_var(
        key="integration.max_steps", min=1, max=3, integer=True))]))
    assert code == 1
    err = capsys.readouterr().err
    m = re.search(r"optimize: all (\d+) evaluations failed", err)
    assert m and "maximum number of steps" in err, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed"
    lines = (out / "optimize.partial.jsonl").read_text().splitlines()[1:]
    records = [json.loads(x) for x in lines]
    assert len(records) == int(m.group(1)) >= 2
    assert all(r["status"] == "failed" and r["reason"] for r in records)
    assert not (out / "optimize.csv").exists()


def test_penalised_value_is_finite_and_capped(scene):
    """The penalised value of an ok evaluation and of a failed one stays finite however
    large the penalty and the violation (the methods and the CSV take no inf)."""
    cfg = load_scene(scene, ("optimize.penalty=1e300",
                             f"optimize.constraints=[{{{TR},max=0}}]")).optimize
    ok = {"status": "ok", "objective": 1.0, "constraints": [1e300]}
    assert penalised(cfg, ok, 0.0) == F_CAP
    assert penalised(cfg, {"status": "failed"}, F_CAP) == F_CAP
    cfg = load_scene(scene, ('optimize.objective={metric="impact_pair.kappa",sense="max"}',
                             f"optimize.constraints=[{{{TR},max=10}}]")).optimize
    assert penalised(cfg, {"status": "ok", "objective": 1e308, "constraints": [0.0]},
                     0.0) == -F_CAP
