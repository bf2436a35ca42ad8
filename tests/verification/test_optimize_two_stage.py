"""configs/optimize_two_stage.toml (`make optimize-two-stage`), a short run with tpe: evaluations
in two worker processes, the housing rebuilt for each wall thickness, and the best scene reproduces
the recorded objective when the CLI runs it on its own (the runner and the nvh report writer's
erp.csv, not the optimiser's in-process evaluation)."""
from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from vibrogear import cli

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_two_stage_short_run_and_best_scene_reproduces_its_erp(tmp_path):
    out = tmp_path / "out"
    assert cli.main(["optimize", str(ROOT / "configs" / "optimize_two_stage.toml"), "--set",
                     "optimize.budget=4", "--set", "optimize.method=tpe", "--out", str(out),
                     "--quiet"]) == 0
    doc = json.loads((out / "optimize.json").read_text())
    assert doc["evaluations"] == 4 and doc["failed_evaluations"] == 0
    ok = [h["objective"] for h in doc["history"]]
    assert doc["best"]["objective"] == min(ok)
    walls = {h["values"]["housing.wall_thickness"] for h in doc["history"]}
    assert len(walls) == 4                          # four housings built
    best = out / "best_scene.toml"
    assert cli.main(["check", str(best)]) == 0
    assert cli.main(["run", str(best), "--out", str(tmp_path / "best"), "--quiet"]) == 0
    with open(tmp_path / "best" / "erp.csv", newline="") as fh:
        erp = [float(r["erp_w"]) for r in csv.DictReader(fh)]
    assert max(erp) == pytest.approx(doc["best"]["objective"], rel=1e-9)
