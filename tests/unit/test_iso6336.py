"""ISO 6336-1 mesh stiffness: the factors' formulas, the SI units, the scene keys
(``stiffness = "iso6336"``, errors naming the field), the model's use of k_normal and the
contact harmonics, and ``vibrogear modes`` reporting the ISO value."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.config import ConfigError
from vibrogear.config.scene import read_toml, scene_from_dict
from vibrogear.models.validate import validate_scene
from vibrogear.models.gearbox.model import build_gearbox
from vibrogear.models.gearbox.iso6336 import (basic_rack_factor, blank_factor, contact_harmonics,
                                      inverse_involute, involute, mesh_stiffness,
                                      virtual_teeth)

ROOT = Path(__file__).resolve().parents[2]
GEAR_PAIR = ROOT / "configs" / "gear_pair.toml"
DEG = math.pi / 180.0


def _scene(**mesh):
    data = read_toml(GEAR_PAIR)
    data["scene"]["analyses"] = ["modes"]
    data["gearbox"]["meshes"][0].update(mesh)
    return scene_from_dict(data)


def test_factors_follow_their_formulas():
    assert basic_rack_factor(1.2, 20 * DEG) == pytest.approx(1.0, rel=1e-15)
    assert basic_rack_factor(1.25, 20 * DEG) == pytest.approx(0.975, rel=1e-15)
    assert basic_rack_factor(1.2, 25 * DEG) == pytest.approx(1.1, rel=1e-14)
    assert blank_factor() == 1.0                      # b_s / b = 1: solid
    assert blank_factor(0.5, 2.0) == pytest.approx(1 + math.log(0.5) / (5 * math.exp(0.4)))
    assert blank_factor(0.05, 0.1) == blank_factor(0.2, 1.0)      # clamped to the range
    assert virtual_teeth(30, 0.0, 20 * DEG) == 30.0
    for a in (0.05, 0.35, 0.9, 1.3):
        assert inverse_involute(float(involute(a))) == pytest.approx(a, rel=1e-13)


def test_units_and_low_line_load():
    """c' in N/m^2 (1 N/(mm um) = 1e9 N/m^2), k_mean = c_gamma_alpha b in N/m; a line load
    of 50 N/mm (5e4 N/m) halves c' (ISO: factor (K_A F_t / b) / 100 N/mm)."""
    r = mesh_stiffness(40, 80, 0.002, 0.025)
    assert 1.0e10 < r.c_prime < 2.0e10
    assert r.k_mean == pytest.approx(r.c_gamma_alpha * 0.025, rel=1e-15)
    assert r.k_normal == r.k_mean                      # spur
    half = mesh_stiffness(40, 80, 0.002, 0.025, line_load=5e4)
    assert half.c_prime == pytest.approx(0.5 * r.c_prime, rel=1e-14)
    assert mesh_stiffness(40, 80, 0.002, 0.025, line_load=3e5).c_prime == r.c_prime


def test_helical_normal_stiffness_gives_isos_torsional_stiffness():
    """ISO's stiffness acts along the transverse line of action (torsional mesh stiffness
    c_gamma_alpha b r_b^2); the model's contact along the 3-D normal with k_normal must give
    the same torsional stiffness: k_normal (c . e_psi_a)^2 = c_gamma_alpha b r_b1^2."""
    data = read_toml(GEAR_PAIR)
    data["scene"]["analyses"] = ["modes"]
    for g in data["gearbox"]["gears"]:
        g["helix_angle"] = 15.0
    data["gearbox"]["shafts"][1]["x"] = 0.12 + _centre_distance(data)
    data["gearbox"]["meshes"][0]["stiffness"] = "iso6336"
    sc = scene_from_dict(data)
    gm = build_gearbox(sc)
    mesh = gm.contacts[0]
    ga = sc.gearbox.gears[0]
    beta, alpha_n = math.radians(ga.helix_angle), math.radians(sc.gearbox.meshes[0].pressure_angle)
    assert beta > 0.2
    r = mesh_stiffness(ga.teeth, sc.gearbox.gears[1].teeth, ga.module,
                       min(ga.width, sc.gearbox.gears[1].width), alpha_n=alpha_n, beta=beta)
    alpha_t = math.atan(math.tan(alpha_n) / math.cos(beta))
    rb1 = 0.5 * ga.pitch_diameter * math.cos(alpha_t)
    s, idx, val = mesh.vector.parts[0]
    c_psi = val[5]                                         # psi of gear a
    assert mesh.k_hi == pytest.approx(r.k_normal, rel=1e-14)
    assert mesh.k_hi * c_psi**2 == pytest.approx(r.c_gamma_alpha * r.face_width * rb1**2,
                                                 rel=1e-12)


def _centre_distance(data):
    g = data["gearbox"]["gears"]
    beta = math.radians(g[0].get("helix_angle", 0.0))
    return 0.5 * g[0]["module"] * (g[0]["teeth"] + g[1]["teeth"]) / math.cos(beta)


def test_iso_stiffness_and_harmonics_enter_the_model():
    sc = _scene(stiffness="iso6336", stiffness_cos=[], te_cos=[5e-6], iso_harmonics=4)
    gm = build_gearbox(sc)
    m, g = sc.gearbox.meshes[0], sc.gearbox.gears
    ref = mesh_stiffness(g[0].teeth, g[1].teeth, g[0].module, min(g[0].width, g[1].width),
                         dedendum=m.dedendum, harmonics=4)
    c = gm.contacts[0]
    assert c.k_hi == c.k_lo == pytest.approx(ref.k_normal, rel=1e-15)
    assert c.stiffness_cos == ref.harmonics_cos and c.stiffness_sin == ref.harmonics_sin
    assert len(c.stiffness_cos) == 4
    rec = gm.mesh_stiffness_summary()[0]
    assert rec["source"] == "iso6336" and rec["user_N_per_m"] is None
    assert rec["iso6336_N_per_m"] == rec["used_N_per_m"] == c.k_hi
    # the user's harmonics win over ISO's
    gm2 = build_gearbox(_scene(stiffness="iso6336", stiffness_cos=[0.1]))
    assert gm2.contacts[0].stiffness_cos == (0.1,) and gm2.contacts[0].stiffness_sin == ()


def test_user_value_is_reported_next_to_iso():
    gm = build_gearbox(_scene())
    rec = gm.mesh_stiffness_summary()[0]
    assert rec["source"] == "user" and rec["used_N_per_m"] == rec["user_N_per_m"] == 3.5e8
    assert 2e8 < rec["iso6336_N_per_m"] < 8e8
    assert gm.contacts[0].stiffness_cos == (0.2,)


@pytest.mark.parametrize("mesh, field, words", [
    ({"stiffness": "iso"}, "gearbox.meshes[0].stiffness", "iso6336"),
    ({"stiffness": -1.0}, "gearbox.meshes[0].stiffness", "> 0"),
    ({"profile_shift_a": 3.0}, "gearbox.meshes[0].profile_shift_a", "<= 2"),
    ({"face_width": 0.0}, "gearbox.meshes[0].face_width", "> 0"),
    ({"iso_harmonics": -1}, "gearbox.meshes[0].iso_harmonics", ">= 0"),
])
def test_bad_iso_keys_name_the_field(mesh, field, words):
    with pytest.raises(ConfigError) as exc:
        _scene(**mesh)
    assert exc.value.path == field and words in str(exc.value)


def test_out_of_range_gear_data_fail_at_check_time():
    """addendum 0.2 m_n: eps_alpha < 1, ISO's method does not apply; the scene check (no
    model built) reports the mesh's stiffness field."""
    with pytest.raises(ConfigError) as exc:
        validate_scene(_scene(stiffness="iso6336", addendum=0.2))
    assert exc.value.path == "gearbox.meshes[0].stiffness" and "eps_alpha" in str(exc.value)
    build_gearbox(_scene(addendum=0.2))           # a user value still builds (no ISO record)


def test_contact_wave_mean_and_levels():
    """Mean of the wave over one period is 1 (k_mean), its two levels are c'/k_mean and
    1.75 c'/k_mean (sampled from the full series' partial sums away from the jumps)."""
    eps = 1.6
    a, b = contact_harmonics(eps, 0.0, 400)
    h = np.arange(1, 401)
    t = np.array([0.3, 0.8])                          # double contact, single contact
    val = 1.0 + np.cos(2 * np.pi * np.outer(t, h)) @ a + np.sin(2 * np.pi * np.outer(t, h)) @ b
    mean_level = 0.75 * eps + 0.25
    np.testing.assert_allclose(val, [1.75 / mean_level, 1.0 / mean_level], atol=3e-3)


def test_modes_summary_shows_the_iso_stiffness(tmp_path):
    data = read_toml(GEAR_PAIR).copy()
    scene_file = ROOT / "configs" / "gear_pair_iso.toml"
    out = tmp_path / "out"
    rc = main(["run", str(scene_file), "--quiet", "--out", str(out), "--set",
               'scene.analyses=["modes"]'])
    assert rc == 0
    summary = json.loads((out / "summary.json").read_text())
    rec = summary["results"]["modes"]["mesh_stiffness"][0]
    assert rec["source"] == "iso6336" and rec["used_N_per_m"] == rec["iso6336_N_per_m"]
    sc = scene_from_dict(read_toml(scene_file))
    assert build_gearbox(sc).contacts[0].k_hi == pytest.approx(rec["used_N_per_m"], rel=1e-15)
    assert data["gearbox"]["meshes"][0]["stiffness"] == 3.5e8


def test_profile_shifted_pair_meshes_on_its_working_pitch_circles():
    """x_a + x_b = 0.5: zero-backlash working pressure angle from
    inv(alpha_w) = inv(alpha) + 2 tan(alpha) (x_a + x_b) / (z_a + z_b) (solved here by
    brentq), working centre distance a cos(alpha) / cos(alpha_w).  The reference centre
    distance is refused naming the mesh; at a_w the mesh normal makes alpha_w with the
    tangent and the gear's lever arm is the unchanged base radius."""
    from scipy.optimize import brentq

    alpha = 20 * DEG
    inv = lambda a: math.tan(a) - a                       # noqa: E731
    alpha_w = brentq(lambda a: inv(a) - inv(alpha) - 2 * math.tan(alpha) * 0.5 / 120,
                     0.1, 1.2)
    a_w = 0.12 * math.cos(alpha) / math.cos(alpha_w)
    assert a_w - 0.12 > 9e-4
    data = read_toml(GEAR_PAIR)
    data["scene"]["analyses"] = ["modes"]
    data["gearbox"]["meshes"][0].update(profile_shift_a=0.3, profile_shift_b=0.2)
    with pytest.raises(ConfigError) as exc:
        validate_scene(scene_from_dict(data))
    assert exc.value.path == "gearbox.meshes[0]" and "working pitch" in str(exc.value)
    data["gearbox"]["shafts"][1]["x"] = 0.12 + a_w
    gm = build_gearbox(scene_from_dict(data))
    s, idx, val = gm.contacts[0].vector.parts[0]
    n, c_psi = val[:3], val[5]
    assert abs(n[0]) == pytest.approx(math.sin(alpha_w), rel=1e-12)      # along the centres
    assert abs(c_psi) == pytest.approx(0.04 * math.cos(alpha), rel=1e-12)  # r_b of z1
    rec = gm.mesh_stiffness_summary()[0]
    iso = mesh_stiffness(40, 80, 0.002, 0.025, x1=0.3, x2=0.2)
    assert rec["iso6336_N_per_m"] == pytest.approx(iso.k_normal, rel=1e-15)
    assert iso.working_centre_distance == pytest.approx(a_w, rel=1e-12)


def test_low_contact_ratio_is_flagged():
    """ISO states c_gamma_alpha = c'(0.75 eps_alpha + 0.25) for eps_alpha >= 1.2; below it
    the summary carries a note (h_aP = 0.6 m_n: eps_alpha = 1.10 for 40 / 80 teeth)."""
    rec = build_gearbox(_scene(stiffness="iso6336", addendum=0.6)).mesh_stiffness_summary()[0]
    # the involute closed form, written out: (g_a1 + g_a2 - a sin alpha) / (pi m cos alpha)
    m, alpha, r1, r2 = 0.002, math.radians(20.0), 0.04, 0.08
    g = sum(math.sqrt((r + 0.6 * m) ** 2 - (r * math.cos(alpha)) ** 2) for r in (r1, r2))
    eps = (g - (r1 + r2) * math.sin(alpha)) / (math.pi * m * math.cos(alpha))
    assert eps == pytest.approx(1.1045, abs=1e-4)
    assert rec["eps_alpha"] == pytest.approx(eps, rel=1e-9) and "1.2" in rec["note"]
    assert build_gearbox(_scene()).mesh_stiffness_summary()[0]["note"] == ""


def test_check_exits_2_naming_the_mesh(capsys):
    rc = main(["check", str(ROOT / "configs" / "gear_pair_iso.toml"), "--set",
               "gearbox.meshes[0].addendum=0.2"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "gearbox.meshes[0].stiffness" in err and "eps_alpha" in err
