"""Geometry sweep through the CLI: table + plot, parallel points, resume after a kill, and
plate-bending physics (a thicker wall raises the first frequency: f ~ t / a^2)."""
from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest


from vibrogear.analyses.housing.sweep import sweep_signature
from vibrogear.config import load_scene
from vibrogear.pipeline.resume import PartialStore

ROOT = Path(__file__).resolve().parents[2]
VG = Path(sys.executable).parent / "vibrogear"
SCENE = str(ROOT / "configs" / "housing_sweep.toml")


@pytest.mark.system
def test_wall_thickness_sweep_resumes(tmp_path):
    out = tmp_path / "sweep"
    out.mkdir()
    sets = ["housing.mesh.size=0.03", "housing_sweep.values=[0.015, 0.018, 0.022]",
            "housing_sweep.n_freqs=3"]
    # a point "finished before the kill" by the same run: kept, not recomputed; plus a torn
    # last line
    points = out / "housing_sweep_points.jsonl"
    store = PartialStore(points, sweep_signature(load_scene(SCENE, tuple(sets))))
    store.append({"value": 0.015, "status": "ok", "freqs_hz": [1.0, 2.0, 3.0], "n_dofs": 7})
    with points.open("a") as fh:
        fh.write('{"val')
    env = {**os.environ, "VIBROGEAR_CACHE_DIR": str(tmp_path / "cache"), "OPENBLAS_NUM_THREADS": "1"}
    args = [str(VG), "run", SCENE, "--out", str(out), "--quiet"]
    for text in sets:
        args += ["--set", text]
    r = subprocess.run(args, env=env, cwd=ROOT, capture_output=True, text=True, timeout=400)
    assert r.returncode == 0, r.stderr[-3000:]
    summ = json.loads((out / "summary.json").read_text())["results"]["housing_sweep"]
    assert summ["points_resumed"] == 1 and summ["points_computed"] == 2
    with (out / "housing_sweep.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert [float(r["housing.wall_thickness"]) for r in rows] == [0.015, 0.018, 0.022]
    assert float(rows[0]["f1_hz"]) == 1.0                       # the resumed row, untouched
    # another housing material: nothing is reused, the old points are set aside
    r = subprocess.run(args + ["--set", "housing.material.rho=7000.0"], env=env, cwd=ROOT,
                       capture_output=True, text=True, timeout=400)
    assert r.returncode == 0, r.stderr[-3000:]
    again = json.loads((out / "summary.json").read_text())["results"]["housing_sweep"]
    assert again["points_resumed"] == 0 and again["points_computed"] == 3
    assert "physics" in again["resume"] and "set aside" in again["resume"]
    assert len(list(out.glob("housing_sweep_points.jsonl.stale-*"))) == 1
    with (out / "housing_sweep.csv").open() as fh:
        f1_light = float(next(csv.DictReader(fh))["f1_hz"])
    assert f1_light > 100.0                                     # computed, not the fake 1.0
    f1 = [float(r["f1_hz"]) for r in rows[1:]]
    assert f1[1] > f1[0] > 100.0
    assert (out / "housing_sweep.png").stat().st_size > 1000
