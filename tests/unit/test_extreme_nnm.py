"""Extreme and degenerate ``vibrogear nnm`` input (issue 24, item 6): each case gives exit 2
naming the field with nothing written, or runs to an explicit outcome: a backbone whose
every point is finite with the branch's status, or exit 1 with the reason (no elastic mode,
no starting orbit); never NaN, inf or round-off beside an ``ok``.

The impact pair (configs/impact_pair_nnm.toml, ~0.3 s a backbone) carries most cases; the
gear pair (configs/gear_pair_nnm.toml) the gearbox-only ones (mesh names, an unloaded mesh,
absolute energies in J) with short branches."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from cli_cases import cases, cli_args, read_outputs

from vibrogear.cli import main

ROOT = Path(__file__).resolve().parents[2]
IMPACT = str(ROOT / "configs" / "impact_pair_nnm.toml")
GEAR = str(ROOT / "configs" / "gear_pair_nnm.toml")

#: the impact pair's backbone to 10 x its contact-switch energy (51 points)
IP = ["nnm.energy_max=10"]
#: the gear pair's first 10 points
GP = ["nnm.energy_max=3", "nnm.max_points=10"]
UNLOADED = ["gearbox.couplings[0].twist=0", "gearbox.couplings[1].twist=0"]
BRANCH_STATUS = ("left_range", "max_points", "ds_too_small")


_args = cli_args


# ------------------------------------------------------------------ rejected input (exit 2)

#: (id, scene, overrides, field, found by `vibrogear check` (else only once the model is
#: built, still before anything is written)); mesh names, the impact pair's one mode and the
#: unloaded gearbox's onset unit are decided from the config (NnmConfig.check_model)
BAD = [
    ("energy-min-above-max", IMPACT, ["nnm.energy_min=10", "nnm.energy_max=1"],
     "nnm.energy_max", True),
    ("energy-range-of-one-point", IMPACT, ["nnm.energy_min=1", "nnm.energy_max=1"],
     "nnm.energy_max", True),
    ("energy-min-0", IMPACT, ["nnm.energy_min=0"], "nnm.energy_min", True),
    ("energy-min-nan", IMPACT, ["nnm.energy_min=nan"], "nnm.energy_min", True),
    ("ds-above-ds-max", IMPACT, ["nnm.ds=0.5"], "nnm.ds", True),
    ("ds-min-above-ds", IMPACT, ["nnm.ds_min=0.1"], "nnm.ds", True),
    ("max-points-1", IMPACT, ["nnm.max_points=1"], "nnm.max_points", True),
    ("rtol-0", IMPACT, ["nnm.rtol=0"], "nnm.rtol", True),
    ("rtol-1e-3", IMPACT, ["nnm.rtol=1e-3"], "nnm.rtol", True),
    ("tol-0", IMPACT, ["nnm.tol=0"], "nnm.tol", True),
    ("mode-negative", IMPACT, ["nnm.mode=-1"], "nnm.mode", True),
    ("frequency-0", IMPACT, ["nnm.frequency=0"], "nnm.frequency", True),
    ("shape-samples-2", IMPACT, ["nnm.shape_samples=2"], "nnm.shape_samples", True),
    ("rational-max-0", IMPACT, ["nnm.rational_max=0"], "nnm.rational_max", True),
    ("energy-and-amplitude", IMPACT, ["nnm.amplitude_min=1", "nnm.amplitude_max=2"],
     "nnm.amplitude_min", True),
    ("mode-and-mesh", GEAR, ['nnm.mode=1'], "nnm.mesh", True),
    ("mode-beyond-the-model", IMPACT, IP + ["nnm.mode=5"], "nnm.mode", True),
    ("second-mode-beyond-the-model", IMPACT, IP + ["nnm.second_mode=3"], "nnm.second_mode",
     True),
    ("unknown-mesh", GEAR, GP + ['nnm.mesh="G9"'], "nnm.mesh", True),
    # regression: ignored (the impact pair's one mode was taken)
    ("mesh-of-the-impact-pair", IMPACT, IP + ['nnm.mesh="clearance"'], "nnm.mesh", True),
    # a gearbox's elastic-mode count is known only after the reduction
    ("second-mode-beyond-the-gearbox", GEAR, GP + ["nnm.second_mode=100000"],
     "nnm.second_mode", False),
    # regression: an unloaded mesh sits on its contact switch, the onset energy is 0 and
    # the energy range [0, 0] was a ValueError traceback (NnmMethod)
    ("onset-energy-of-an-unloaded-mesh", GEAR, GP + UNLOADED, "nnm.energy_unit", True),
    # regression: energies below the round-off of the energy about the static state gave
    # backbones of noise (1e-16 for 1e-30 asked) reported as ok, and negative energies
    ("energy-below-round-off", IMPACT, ['nnm.energy_unit="absolute"', "nnm.energy_min=1e-30",
                                        "nnm.energy_max=1e-29"], "nnm.energy_min", False),
    ("energy-below-round-off-gearbox", GEAR, GP + ['nnm.energy_unit="absolute"',
                                                   "nnm.energy_min=1e-20",
                                                   "nnm.energy_max=1e-19"],
     "nnm.energy_min", False),
]


@pytest.mark.parametrize("scene, overrides, field, by_check", [c[1:] for c in BAD],
                         ids=[c[0] for c in BAD])
def test_degenerate_input_exits_2_naming_the_field(tmp_path, capsys, scene, overrides, field,
                                                   by_check):
    out = tmp_path / "out"
    assert main(_args("check", scene, out, overrides)) == (2 if by_check else 0)
    if by_check:
        assert f"invalid input: {field}" in capsys.readouterr().err
    assert main(_args("nnm", scene, out, overrides)) == 2
    err = capsys.readouterr().err
    assert f"invalid input: {field}" in err, err
    assert not out.exists()


def test_check_refuses_the_onset_unit_of_an_unloaded_gearbox(tmp_path, capsys, monkeypatch):
    """No static load and no contact off its switch at x = 0: the onset energy is 0, decided
    from the config (no model built) by `vibrogear check` and the `nnm` verb; absolute
    energies, or a bearing with a clearance (the analysis decides), pass the check."""
    import vibrogear.analyses.study as study

    def no_build(*_a, **_k):
        raise AssertionError("the model was built")
    monkeypatch.setattr(study, "build_study", no_build)
    out = tmp_path / "out"
    for verb in ("check", "nnm"):
        assert main(_args(verb, GEAR, out, GP + UNLOADED)) == 2
        err = capsys.readouterr().err
        assert "invalid input: nnm.energy_unit: 'onset': the gearbox has no static load" in err
    assert not out.exists()
    assert main(_args("check", GEAR, out, GP + UNLOADED + ['nnm.energy_unit="absolute"'])) == 0
    assert main(_args("check", GEAR, out, GP + UNLOADED + ['gearbox.bearings[0].type="linear"',
                                                           "gearbox.bearings[0].clearance=1e-5",
                                                           "gearbox.bearings[0].elements=8"])
                ) == 0
    # nnm not among the analyses: check leaves [nnm] alone
    assert main(_args("check", GEAR, out, GP + UNLOADED + ['scene.analyses=["continuation"]'])
                ) == 0


# ------------------------------------------------------------------ extreme but valid input

def _check_backbone(s, z, rows):
    """Every point: omega > 0, energy > 0 above the static state, the branch's status one of
    the statuses and its message given."""
    assert s["status"] == "ok"
    f = z["omega"] if "omega" in z else 2 * np.pi * z["frequency_hz"]
    assert len(rows) == f.size == sum(b["points"] for b in s["branches"])
    assert np.all(f > 0) and np.all(z["energy"] > 0)
    for b in s["branches"]:
        assert b["status"] in BRANCH_STATUS and b["message"], b
        assert b["points"] >= 2
        lo, hi = b["energy_range_model_units" if "energy_range_model_units" in b
                  else "energy_range_J"]
        assert 0 < lo < hi


def _linear_frequency(expected):
    def check(s, z, rows):
        assert s["branches"][0]["linear_omega"] == pytest.approx(expected, rel=1e-12)
        assert z["omega"][0] == pytest.approx(expected, rel=1e-6)
    return check


def _constant_frequency(expected):
    """A linear pair (no stiffness change at the clearance, or a clearance never reached):
    the backbone is flat, omega = its linear frequency at every energy."""
    def check(s, z, rows):
        assert np.allclose(z["omega"], expected, rtol=1e-8)
    return check


def _hardening(s, z, rows):
    """A clearance of 1e6 around the static state q_s = 1.1: the linear pair (omega =
    sqrt(kappa)) up to the onset energy, hardening once the outer spring is reached."""
    e_on = s["branches"][0]["onset_energy_model_units"]
    assert e_on == pytest.approx(0.5 * 0.5 * (1e6 - 1.1) ** 2, rel=1e-9)
    below = z["energy"] < 0.99 * e_on
    assert below.sum() >= 2 and np.allclose(z["omega"][below], math.sqrt(0.5), rtol=1e-8)
    assert z["omega"][-1] > 1.1 * math.sqrt(0.5)


def _points(n, status):
    def check(s, z, rows):
        assert [b["points"] for b in s["branches"]] == [n]
        assert s["branches"][0]["status"] == status
    return check


def _shapes(s, z, rows):
    """Shapes at 1e30 and 1e-30 x the onset energy: the nearest orbits, the branch's ends."""
    assert z["shape_x"].shape[0] == 2 and z["shape_x"].shape[1] == 5
    e = np.sort(z["energy"])
    assert z["shape_energy"][0] == e[-1] and z["shape_energy"][1] == e[0]


def _highest_mode(s, z, rows):
    assert s["branches"][0]["mode"] == 0          # the impact pair has one mode


def _softening(s, z, rows):
    """The loaded pair softens once the clearance opens: the last point below the first."""
    assert z["omega"][-1] < z["omega"][0]


VALID = [
    ("zero-load", IMPACT, IP + ["impact_pair.f_m=0"], _linear_frequency(math.sqrt(0.5))),
    ("zero-backlash", IMPACT, IP + ["impact_pair.b_r=1e-9"], _linear_frequency(1.0)),
    ("stiffness-ratio-1e4", IMPACT, IP + ["impact_pair.kappa=1e-4"], _linear_frequency(1.0)),
    ("no-stiffness-change", IMPACT, IP + ["impact_pair.kappa=1.0"], _constant_frequency(1.0)),
    ("clearance-of-1e6", IMPACT, IP + ["impact_pair.b_r=1e6"], _hardening),
    ("huge-steps", IMPACT, IP + ["nnm.ds_min=10", "nnm.ds=10", "nnm.ds_max=10"], None),
    ("budget-of-2-points", IMPACT, IP + ["nnm.max_points=2"], _points(2, "max_points")),
    ("energy-range-1e-7-wide", IMPACT, ["nnm.energy_min=1e-3", "nnm.energy_max=1.0000001e-3"],
     _points(2, "left_range")),
    ("loosest-rtol", IMPACT, IP + ["nnm.rtol=9e-4"], _softening),
    ("loosest-tol", IMPACT, IP + ["nnm.tol=0.9"], None),
    ("shapes-outside-the-range", IMPACT, IP + ["nnm.shape_energies=[1e30,1e-30]",
                                               "nnm.shape_samples=4"], _shapes),
    ("phase-on-the-mode", IMPACT, IP + ['nnm.phase="mode"'], _softening),
    ("frequency-far-above", IMPACT, IP + ["nnm.frequency=1e9"], _highest_mode),
    ("tightest-stability-and-widest-rational", IMPACT,
     IP + ["nnm.stability_tol=1e-15", "nnm.rational_tol=0.49", "nnm.rational_max=20"], None),
    ("gear-zero-backlash", GEAR, GP + ["gearbox.meshes[0].backlash=0"], None),
    ("gear-stiff-mesh", GEAR, GP + ["gearbox.meshes[0].stiffness=1e12"], None),
    ("gear-soft-mesh", GEAR, GP + ["gearbox.meshes[0].stiffness=1"], None),
]


@pytest.mark.parametrize("scene, overrides, check", cases(VALID, ci=(
    "budget-of-2-points", "loosest-rtol", "gear-stiff-mesh")))     # the rest: make test-system
def test_extreme_input_gives_a_finite_backbone(tmp_path, scene, overrides, check):
    out = tmp_path / "out"
    overrides = ['scene.analyses=["nnm"]', *overrides]
    assert main(_args("nnm", scene, out, overrides)) == 0
    s, z, rows = read_outputs(out, "nnm", text_columns=("label", "stable"))
    _check_backbone(s, z, rows)
    if check is not None:
        check(s, z, rows)


FAILING = [
    # kappa = 0 and no load: the pair floats free inside its clearance, no stiffness at all
    ("no-elastic-mode", IMPACT, IP + ["impact_pair.f_m=0", "impact_pair.kappa=0"],
     "nnm: the model has no elastic mode"),
    ("energy-of-1e20", IMPACT, ['nnm.energy_unit="absolute"', "nnm.energy_min=1e20",
                                "nnm.energy_max=1e30"], "no starting orbit: diverged"),
    ("step-budget-of-10", IMPACT, IP + ["integration.max_steps=10"],
     "no starting orbit: maximum number of steps"),
]


@pytest.mark.parametrize("scene, overrides, reason", [c[1:] for c in FAILING],
                         ids=[c[0] for c in FAILING])
def test_no_backbone_exits_1_with_the_reason(tmp_path, capsys, scene, overrides, reason):
    out = tmp_path / "out"
    assert main(_args("nnm", scene, out, ['scene.analyses=["nnm"]', *overrides])) == 1
    assert reason in capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed"
    assert summary["results"]["nnm"]["status"] == "failed"
    assert reason in summary["results"]["nnm"]["message"]
    assert not (out / "nnm.npz").exists() and not (out / "nnm.csv").exists()


@pytest.mark.slow
def test_unloaded_gear_pair_with_absolute_energies_exits_1(tmp_path, capsys):
    """An unloaded mesh (no torque) in absolute energies: the start orbit starts on the
    contact switch and its corrector gives up: exit 1 with the reason (~7 s)."""
    out = tmp_path / "out"
    code = main(_args("nnm", GEAR, out, ['scene.analyses=["nnm"]', "nnm.max_points=10",
                                         'nnm.energy_unit="absolute"', "nnm.energy_min=1e-6",
                                         "nnm.energy_max=1e-3", *UNLOADED]))
    assert code == 1 and "no starting orbit" in capsys.readouterr().err
