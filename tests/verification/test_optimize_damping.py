"""configs/optimize_impact_damping.toml (`make optimize-damping`): the least damping whose
period-1 branch has no fold over Omega in [0.6, 1.2] is the cusp where the primary
resonance's folds meet.  Reference, independent of the optimiser: the bisection of
continuations of `make critical-zeta` (analyses/critical_damping.py, tol 1e-5) brackets it
in [0.033748, 0.033756]; the optimiser must find it within 1e-3 (the issue's requirement)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from vibrogear import cli

ROOT = Path(__file__).resolve().parents[2]
BRACKET = (0.033748, 0.033756)


@pytest.mark.slow
def test_optimizer_finds_the_cusp_damping(tmp_path):
    out = tmp_path / "out"
    assert cli.main(["optimize", str(ROOT / "configs" / "optimize_impact_damping.toml"),
                     "--out", str(out), "--quiet"]) == 0
    doc = json.loads((out / "optimize.json").read_text())
    zeta = doc["best"]["values"]["impact_pair.zeta"]
    assert doc["best"]["feasible"] and doc["best"]["constraints"][0] == 0
    assert abs(zeta - sum(BRACKET) / 2) <= 1e-3
    # the search closed in on the boundary from both sides: an evaluation with folds just below
    below = [h["values"]["impact_pair.zeta"] for h in doc["history"]
             if h["status"] == "ok" and not h["feasible"]]
    assert below and max(below) < zeta and zeta - max(below) <= 1e-3
    assert doc["evaluations"] <= 40


def test_the_cusp_reference_bracket_is_a_fold_change(tmp_path):
    """The reference itself, at the example's continuation settings: folds just below the
    bracket, none just above (two continuations)."""
    from vibrogear.config import load_scene
    from vibrogear.analyses.optimize.evaluate import Evaluation, evaluate
    from vibrogear.config.sections.optimize import evaluation_data

    scene = load_scene(ROOT / "configs" / "optimize_impact_damping.toml")
    task = Evaluation(base=evaluation_data(scene), config=scene.optimize, scratch=str(tmp_path))
    lo = evaluate(task, 1, {"impact_pair.zeta": BRACKET[0] - 2e-4})
    hi = evaluate(task, 2, {"impact_pair.zeta": BRACKET[1] + 2e-4})
    assert lo["status"] == hi["status"] == "ok"
    assert lo["constraints"][0] == 2 and hi["constraints"][0] == 0
