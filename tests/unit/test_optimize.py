"""``vibrogear optimize`` ([optimize]): a 1-D problem with a closed-form optimum, a failing
evaluation recorded and penalised, bad input refused with the field named (exit 2, nothing
written), the best scene runs, and the metric reductions."""
from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from vibrogear import cli
from vibrogear.analyses.optimize.evaluate import reduce_values

ROOT = Path(__file__).resolve().parents[2]

#: q'' + 2 zeta q' + kappa q = f_p cos(Omega t) inside the clearance (|q| < b_r = 1: no
#: contact, f_m = 0): steady amplitude f_p / sqrt((kappa - Omega^2)^2 + (2 zeta Omega)^2),
#: largest at kappa = Omega^2 (closed form), where it is f_p / (2 zeta Omega)
ZETA, F_P, OMEGA = 0.1, 0.05, 0.8
LINEAR = f"""
[scene]
name = "linear"
analyses = ["optimize"]

[impact_pair]
zeta = {ZETA}
kappa = 0.5
f_m = 0.0
f_p = {F_P}
b_r = 1.0

[integration]
rtol = 1e-9
atol = 1e-11

[time_response]
omega = {OMEGA}
periods = 60            # the transient decays like exp(-zeta t): 1e-10 by the second half
samples_per_period = 400

[optimize]
variables = [{{ key = "impact_pair.kappa", min = 0.3, max = 1.0 }}]
objective = {{ analysis = "time_response", metric = "deformation_second_half.clearance", reduce = "max", sense = "max" }}
budget = 30
xtol = 1e-4
"""


def _scene(tmp_path, text=LINEAR, name="s.toml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def _rows(out: Path) -> list[dict]:
    with open(out / "optimize.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def test_one_variable_finds_the_closed_form_resonance(tmp_path):
    out = tmp_path / "out"
    assert cli.main(["optimize", str(_scene(tmp_path)), "--out", str(out), "--quiet"]) == 0
    doc = json.loads((out / "optimize.json").read_text())
    assert doc["method"] == "bounded"
    best = doc["best"]
    # the closed form: kappa* = Omega^2, amplitude f_p / (2 zeta Omega)
    assert best["values"]["impact_pair.kappa"] == pytest.approx(OMEGA ** 2, abs=2e-3)
    assert best["objective"] == pytest.approx(F_P / (2 * ZETA * OMEGA), rel=1e-4)
    # and every evaluation lies on the closed-form curve (the metric is the amplitude)
    for row in _rows(out):
        k = float(row["impact_pair.kappa"])
        amp = F_P / math.hypot(k - OMEGA ** 2, 2 * ZETA * OMEGA)
        assert float(row["objective_max_deformation_second_half.clearance"]) == \
            pytest.approx(amp, rel=1e-4)
    assert "converged" in doc["stop"]
    for name in ("optimize.csv", "best_scene.toml", "optimize_convergence.png",
                 "optimize_landscape.png", "summary.json"):
        assert (out / name).is_file(), name
    assert not (out / "optimize.partial.jsonl").exists()
    assert not (out / "optimize_evals").exists()
    # best_scene.toml: the scene with the best kappa, accepted by check and run as is
    best_scene = out / "best_scene.toml"
    assert cli.main(["check", str(best_scene)]) == 0
    from vibrogear.config import load_scene
    sc = load_scene(best_scene)
    assert sc.impact_pair.kappa == best["values"]["impact_pair.kappa"]
    assert sc.scene.analyses == ("time_response",) and sc.optimize is None
    assert cli.main(["run", str(best_scene), "--out", str(tmp_path / "best"), "--quiet"]) == 0
    # run by the CLI on its own, the best scene gives the recorded objective
    summary = json.loads((tmp_path / "best" / "summary.json").read_text())
    lo, hi = summary["results"]["time_response"]["deformation_second_half"]["clearance"]
    assert hi == pytest.approx(best["objective"], rel=1e-12)


def test_a_failing_evaluation_is_recorded_and_penalised(tmp_path):
    # max_steps below the steps 60 periods need: the time response fails there
    text = LINEAR.replace('variables = [{ key = "impact_pair.kappa", min = 0.3, max = 1.0 }]',
                          'variables = [{ key = "integration.max_steps", min = 20, max = 200000, '
                          'log = true, integer = true }]')
    text = text.replace('budget = 30', 'budget = 8\nmethod = "differential-evolution"\nseed = 1')
    out = tmp_path / "out"
    assert cli.main(["optimize", str(_scene(tmp_path, text)), "--out", str(out), "--quiet"]) == 0
    rows = _rows(out)
    failed = [r for r in rows if r["status"] == "failed"]
    ok = [r for r in rows if r["status"] == "ok"]
    assert failed and ok and len(rows) == 8
    for r in failed:
        assert r["reason"] and int(r["integration.max_steps"]) < 10000
        # penalised: worse than every successful evaluation (the method minimises)
        assert float(r["penalised"]) > max(float(o["penalised"]) for o in ok)
    doc = json.loads((out / "optimize.json").read_text())
    assert doc["failed_evaluations"] == len(failed) and doc["best"]["feasible"]
    assert doc["best"]["values"]["integration.max_steps"] in [int(r["integration.max_steps"])
                                                              for r in ok]


@pytest.mark.parametrize("edit, field", [
    (('key = "impact_pair.kappa"', 'key = "impact_pair.kapa"'), "optimize.variables[0].key"),
    (('key = "impact_pair.kappa"', 'key = "impact_pair.kappa[0]"'), "optimize.variables[0].key"),
    (("min = 0.3, max = 1.0", "min = 1.0, max = 0.3"), "optimize.variables[0].max"),
    (("min = 0.3, max = 1.0", "min = 0.3, max = 1.5"), "optimize.variables[0].max"),
    (('analysis = "time_response"', 'analysis = "map"'), "optimize.objective.analysis"),
    (('analysis = "time_response"', 'analysis = "swep"'), "optimize.objective.analysis"),
    (('analysis = "time_response", ', ''), "optimize.objective.analysis"),
    (('reduce = "max"', 'reduce = "median"'), "optimize.objective.reduce"),
    (("budget = 30", "budget = 0"), "optimize.budget"),
    (("budget = 30", 'budget = 30\nmethod = "simplex"'), "optimize.method"),
])
def test_bad_optimize_input_exits_2_naming_the_field(tmp_path, capsys, edit, field):
    text = LINEAR.replace(*edit)
    assert text != LINEAR
    out = tmp_path / "out"
    assert cli.main(["check", str(_scene(tmp_path, text))]) == 2
    assert field in capsys.readouterr().err
    assert cli.main(["optimize", str(_scene(tmp_path, text)), "--out", str(out)]) == 2
    assert field in capsys.readouterr().err
    assert not out.exists()


def test_shipped_optimize_scenes_pass_check(capsys):
    for name in ("optimize_impact_damping.toml", "optimize_two_stage.toml"):
        assert cli.main(["check", str(ROOT / "configs" / name)]) == 0, capsys.readouterr().err


def test_reductions():
    v = np.array([3.0, np.nan, 1.0, 2.0])
    assert [reduce_values(v, r) for r in ("max", "min", "mean", "sum", "count", "range")] == \
        [3.0, 1.0, 2.0, 6.0, 3.0, 2.0]
    assert reduce_values([], "count") == 0.0 and reduce_values([0.9], "range") == 0.0
    assert math.isnan(reduce_values([], "max"))


def test_a_metric_the_analysis_lacks_fails_every_evaluation_exit_1(tmp_path, capsys):
    text = LINEAR.replace('metric = "deformation_second_half.clearance"',
                          'metric = "deformation_second_half.G1"').replace("budget = 30",
                                                                          "budget = 2")
    out = tmp_path / "out"
    assert cli.main(["optimize", str(_scene(tmp_path, text)), "--out", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "no metric 'deformation_second_half.G1'" in err
    assert "deformation_second_half.clearance" in err          # what it has instead
    assert (out / "optimize.partial.jsonl").is_file()            # kept


def test_optimize_prints_its_best_point(tmp_path, capsys):
    """The console ends with the best point (the value in optimize.json, 6 digits)."""
    out = tmp_path / "out"
    text = LINEAR.replace("budget = 30", "budget = 4")
    assert cli.main(["optimize", str(_scene(tmp_path, text)), "--out", str(out)]) == 0
    doc = json.loads((out / "optimize.json").read_text())
    best = doc["best"]
    last = [line for line in capsys.readouterr().out.strip().splitlines()
            if line.startswith(("best:", "no feasible"))][-1]
    assert last.startswith(f"best: impact_pair.kappa = {best['values']['impact_pair.kappa']:.6g} "
                           f"(max max deformation_second_half.clearance = "
                           f"{best['objective']:.6g}; evaluation {best['evaluation']} of 4;")
