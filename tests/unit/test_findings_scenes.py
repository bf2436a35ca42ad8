"""Every band of the shipped gearbox scenes' findings recomputes from its rule alone (issue
40): a short sweep of each scene (4 speeds up and down), then each band's test
``metric op threshold`` on the named array of sweep.npz (test_findings.recompute_band,
written from docs/findings.md), the ISO band from its n_E1, and the judgement arrays
from their definitions: kv = largest mesh force / static mesh force, rattle power =
impact energy per mesh period x mesh frequency, the static mesh force x the pinion's base
radius = the motor coupling's static torque (torque balance of the pinion shaft)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.config import load_scene

from test_findings import check_bands_recompute

SHORT = ("sweep.n_points=4", "sweep.transient_periods=60", "sweep.extra_transient_periods=40",
         "sweep.record_periods=16")


def _sweep(scene: str, out) -> tuple[dict, dict]:
    args = ["sweep", f"configs/{scene}.toml", "--out", str(out), "--quiet"]
    for s in SHORT:
        args += ["--set", s]
    assert main(args) == 0
    summary = json.loads((out / "summary.json").read_text())
    with np.load(out / "sweep.npz") as z:
        arrays = {k: z[k] for k in z.files}
    return summary, arrays


def _check(scene: str, tmp_path):
    summary, arrays = _sweep(scene, tmp_path)
    f = summary["findings"]
    sweep_bands = [b for b in f["bands"] if b["source"] == "sweep.npz"]
    assert check_bands_recompute(arrays, f) == len(sweep_bands)
    lo, hi = f["range"]
    iso = {m["name"]: m["iso6336"] for m in f["meshes"] if "iso6336" in m}
    for b in f["bands"]:
        assert b["source"] in ("sweep.npz", "iso6336"), b
        if b["source"] == "iso6336":            # 0.85 < rpm / n_E1 <= 1.15 in the range
            n = iso[b["where"]]["n_E1_rpm"]
            assert (b["from"], b["to"]) == pytest.approx((max(lo, 0.85 * n), min(hi, 1.15 * n)))
    ok = arrays["ok"]
    cfg = load_scene(f"configs/{scene}.toml").gearbox
    z1 = cfg.gears[cfg.gear_index(cfg.meshes[0].gear_a, "")].teeth
    for m in f["meshes"]:
        k = m["name"]
        peak, f0 = arrays[f"max_force_{k}"], arrays[f"static_force_{k}"]
        if m["role"] == "loaded":
            assert np.allclose(arrays[f"kv_{k}"][ok], peak[ok] / f0[ok], rtol=1e-12)
            assert f0[0] == pytest.approx(m["static_force_N"] or f0[0], rel=1e-6)
        # the first mesh's period: 60 / (rpm z1) s (the base excitation period)
        mesh_hz = arrays["param"] * z1 / 60.0
        assert np.allclose(arrays[f"rattle_power_{k}"][ok],
                           arrays[f"rattle_{k}"][ok] * mesh_hz[ok], rtol=1e-9, atol=1e-12)
        db = 10 * np.log10(np.maximum(arrays[f"rattle_power_{k}"], 1e-12) / 1e-12)
        assert np.allclose(arrays[f"rattle_db_{k}"][ok], db[ok])
    assert f["verdict"] and f["windows"] is not None
    return summary, arrays, f


def test_gear_pair_bands_recompute_and_torque_balance(tmp_path):
    summary, arrays, f = _check("gear_pair", tmp_path)
    assert [(m["name"], m["role"]) for m in f["meshes"]] == [("G1", "loaded")]
    # torque balance of the pinion shaft: F_static r_b1 = motor coupling torque, from the
    # coupling's own twist (stiffness 2.5e3 N m/rad x (disc angle - shaft angle))
    from vibrogear.analyses.study import build_study
    from vibrogear.models.gearbox.load_path import coupling_torques
    scene = load_scene("configs/gear_pair.toml")
    study = build_study(scene)
    x = study.start(float(arrays["param"][0]))[: study.model.n_modes]
    T = coupling_torques(study.gearbox, scene.gearbox, x)
    rb1 = 0.002 * 40 / 2 * math.cos(math.radians(20.0))
    assert arrays["static_force_G1"][0] * rb1 == pytest.approx(abs(T[0]), rel=1e-4)
    # kv >= 1 where the mesh stays in contact (the largest force is at least the mean)
    full = arrays["ok"] & (arrays["contact_fraction_G1"] == 1.0)
    assert np.all(arrays["kv_G1"][full] > 1.0)


@pytest.mark.slow
@pytest.mark.parametrize("scene", ["two_stage", "single_stage", "two_stage_helical",
                                   "two_stage_iso6336", "two_stage_seed", "fva_two_stage",
                                   "three_stage"])
def test_shipped_gearbox_scene_bands_recompute(scene, tmp_path):
    _summary, _arrays, f = _check(scene, tmp_path)
    roles = {m["name"]: m["role"] for m in f["meshes"]}
    # an idle gear's rattle is never "avoid" without a rattle_limit_db
    assert not any(b["severity"] == "avoid" and roles.get(b["where"]) == "idle"
                   for b in f["bands"])
