"""Mesh stiffness in the terms people have it (config/model/gearbox_meshes.py,
models/gearbox/mesh_law.py).

Independent references:
* a Fourier series' actual minimum over a mesh period, by brute force on a fine grid, and
  the closed form 1 - sqrt(a^2 + b^2) of a single harmonic;
* the square wave of two levels: its mean k_single + s (k_double - k_single) and its
  Fourier coefficients by quadrature of the two-level function itself (not the closed
  form the code uses), times the Fejer weights 1 - h / (N + 1);
* the default double-contact share eps_alpha - 1 from the involute geometry of the spur
  pair (tip and base radii, centre distance, base pitch);
* a stiff-driven pair (a mesh spring k(t) in series with a driver 1000 x stiffer, the
  driver's displacement imposed, slow): its force is k(t) K u / (K + k(t)), so its peak
  approaches the two-level value k_double K u / (K + k_double) as the terms grow.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.config import ConfigError, load_scene
from vibrogear.config.model.gearbox_meshes import stiffness_wave_minimum
from vibrogear.models.gearbox.mesh_law import level_harmonics, mesh_law
from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate

ROOT = Path(__file__).resolve().parents[2]
GEAR_PAIR = ROOT / "configs" / "gear_pair.toml"
K_SINGLE, K_DOUBLE, SHARE = 3.0e8, 5.25e8, 0.557


def _square_wave(terms: int, share: float = SHARE):
    """The plain Fourier series (relative to the mean) of the two-level wave, by quadrature
    of the wave: double contact over [0, share) of the period."""
    n = 200_000
    theta = (np.arange(n) + 0.5) * 2 * np.pi / n
    k = np.where(theta < 2 * np.pi * share, K_DOUBLE, K_SINGLE)
    mean = k.mean()
    h = np.arange(1, terms + 1)
    a = 2 * (np.cos(np.outer(h, theta)) @ k) / n / mean
    b = 2 * (np.sin(np.outer(h, theta)) @ k) / n / mean
    return mean, a, b


def _levels_file(tmp_path, extra: str = "") -> Path:
    text = GEAR_PAIR.read_text()
    text = text.replace("stiffness = 3.5e8          # ~14 N/(mm um) x 25 mm face width",
                        f"stiffness_levels = [{K_SINGLE!r}, {K_DOUBLE!r}]\n{extra}")
    text = text.replace("stiffness_cos = [0.2]      # single/double tooth contact alternation, "
                        "first harmonic", "")
    p = tmp_path / "levels.toml"
    p.write_text(text)
    return p


def test_a_fifty_term_square_wave_passes_check_and_runs(tmp_path, capsys):
    _, a, b = _square_wave(50)
    assert np.abs(a).sum() + np.abs(b).sum() > 1.0          # the old sufficient bound refused it
    th = np.linspace(0.0, 2 * np.pi, 400_000, endpoint=False)
    h = np.arange(1, 51)
    brute = float((1.0 + np.cos(np.outer(th, h)) @ a + np.sin(np.outer(th, h)) @ b).min())
    low, _ = stiffness_wave_minimum(a, b)
    assert low == pytest.approx(brute, abs=1e-6) and low > 0.6
    sets = ["--set", f"gearbox.meshes[0].stiffness_cos={[float(v) for v in a]}",
            "--set", f"gearbox.meshes[0].stiffness_sin={[float(v) for v in b]}"]
    assert main(["check", str(GEAR_PAIR), *sets]) == 0
    out = tmp_path / "run"
    assert main(["time", str(GEAR_PAIR), *sets, "--set", "time_response.periods=8",
                 "--quiet", "--out", str(out)]) == 0
    assert (out / "time_response.npz").exists()


def test_the_actual_minimum_decides():
    """1 + 0.7 cos + 0.7 sin: sum of |harmonics| 1.4, minimum 1 - 0.99 > 0: accepted;
    0.8 / 0.7: minimum 1 - 1.063 < 0: refused with it, naming the field."""
    assert stiffness_wave_minimum([0.7], [0.7])[0] == pytest.approx(1 - math.hypot(0.7, 0.7),
                                                                    abs=1e-12)
    load_scene(GEAR_PAIR, ("gearbox.meshes[0].stiffness_cos=[0.7]",
                           "gearbox.meshes[0].stiffness_sin=[0.7]"))
    with pytest.raises(ConfigError) as exc:
        load_scene(GEAR_PAIR, ("gearbox.meshes[0].stiffness_cos=[0.8]",
                               "gearbox.meshes[0].stiffness_sin=[0.7]"))
    assert exc.value.path == "gearbox.meshes[0].stiffness_cos"
    assert f"{1 - math.hypot(0.8, 0.7):.3g}" in str(exc.value)


def test_levels_are_the_square_waves_fejer_series(tmp_path):
    sc = load_scene(_levels_file(tmp_path, f"double_contact_share = {SHARE}\nlevel_terms = 30"))
    k, hc, hs, rec = mesh_law(sc.gearbox, 0)
    mean, a, b = _square_wave(30)
    assert k == pytest.approx(K_SINGLE + SHARE * (K_DOUBLE - K_SINGLE), rel=1e-12)
    assert k == pytest.approx(mean, rel=1e-5)
    w = 1.0 - np.arange(1, 31) / 31.0
    assert np.max(np.abs(np.array(hc) - w * a)) < 1e-4
    assert np.max(np.abs(np.array(hs) - w * b)) < 1e-4
    assert rec["levels"]["terms"] == 30 and rec["source"] == "levels"


def test_the_default_share_is_the_contact_ratio_less_one(tmp_path):
    sc = load_scene(_levels_file(tmp_path))
    m, alpha = 0.002, math.radians(20.0)
    r1, r2 = 40 * m / 2, 80 * m / 2
    eps = (math.sqrt((r1 + m) ** 2 - (r1 * math.cos(alpha)) ** 2)
           + math.sqrt((r2 + m) ** 2 - (r2 * math.cos(alpha)) ** 2)
           - (r1 + r2) * math.sin(alpha)) / (math.pi * m * math.cos(alpha))
    rec = mesh_law(sc.gearbox, 0)[3]
    assert rec["levels"]["double_contact_share"] == pytest.approx(eps - 1.0, rel=1e-9)
    assert rec["levels"]["share_source"].startswith("eps_alpha")


def _stiff_driven_peak(hc, hs, k_mean) -> float:
    """Peak mesh force [in units of k_mean u] of the stiff-driven pair (module docstring):
    x'' + c x' + K x + k(t) x = K u, K = 1000 k_mean, u = 1, slow mesh frequency."""
    H = len(hc)
    K = 1000.0
    model = ReducedModel(omega2=np.array([K]), damping=np.array([2 * 0.7 * math.sqrt(K)]),
                         coupling=LinearCoupling.none(1),
                         forcing=Forcing(np.array([K]), np.zeros((H, 1)), np.zeros((H, 1))),
                         contacts=ContactSet(np.ones((1, 1)), np.array([1.0]), np.array([0.0]),
                                             np.array([0.0]), np.array([-np.inf]),
                                             np.array([1.0]), np.array([0.0]),
                                             np.array([hc]), np.array([hs]),
                                             np.zeros((1, H)), np.zeros((1, H))),
                         omega_per_param=1.0)
    W = 0.01
    T = 2 * math.pi / W
    t = np.linspace(T, 2 * T, 128 * H + 1)
    tr = integrate(model, W, np.array([K / (K + 1.0), 0.0]), 0.0, 2 * T, t_eval=t,
                   options=IntegrationOptions(rtol=1e-10, atol=1e-13))
    h = np.arange(1, H + 1)
    mu = 1.0 + np.cos(np.outer(W * t, h)) @ np.asarray(hc) + np.sin(np.outer(W * t, h)) @ \
        np.asarray(hs)
    return float(np.max(mu * tr.u[:, 0]))


def test_the_peak_tooth_force_converges_to_the_two_level_value():
    K = 1000.0
    errors = []
    for terms in (5, 10, 20, 50):
        k_mean, hc, hs, reported = level_harmonics(K_SINGLE, K_DOUBLE, SHARE, terms)
        kd = K_DOUBLE / k_mean                            # k_double in units of k_mean
        two_level = kd * K / (K + kd)
        peak = _stiff_driven_peak(hc, hs, k_mean)
        assert peak <= two_level * (1 + 1e-6)            # Fejer: no overshoot
        errors.append((two_level - peak) / two_level)
        assert errors[-1] == pytest.approx(reported, abs=2e-3)
    assert all(e2 < e1 for e1, e2 in zip(errors, errors[1:]))
    assert errors[-1] < 0.005 and errors[0] > 0.01
    # a plain truncation overshoots by ~9 % of the step (Gibbs) at any number of terms
    mean, a, b = _square_wave(50)
    th = np.linspace(0.0, 2 * np.pi, 100_000, endpoint=False)
    h = np.arange(1, 51)
    plain = mean * (1 + np.cos(np.outer(th, h)) @ a + np.sin(np.outer(th, h)) @ b).max()
    assert plain > K_DOUBLE + 0.07 * (K_DOUBLE - K_SINGLE)


@pytest.mark.parametrize("extra, field, words", [
    ("stiffness = 4e8", "stiffness_levels", "not both"),
    ("stiffness_cos = [0.1]", "stiffness_levels", "not both"),
    ("double_contact_share = 1.2", "double_contact_share", "< 1"),
])
def test_bad_levels_name_the_field(tmp_path, capsys, extra, field, words):
    p = _levels_file(tmp_path, extra)
    assert main(["check", str(p)]) == 2
    err = capsys.readouterr().err
    assert f"gearbox.meshes[0].{field}" in err and words in err


def test_levels_shape_and_order_are_checked(tmp_path):
    p = _levels_file(tmp_path)
    for value, words in (("[3e8]", "2 numbers"), ("[5e8, 3e8]", "k_double")):
        with pytest.raises(ConfigError) as exc:
            load_scene(p, (f"gearbox.meshes[0].stiffness_levels={value}",))
        assert exc.value.path == "gearbox.meshes[0].stiffness_levels"
        assert words in str(exc.value)
    with pytest.raises(ConfigError) as exc:
        load_scene(GEAR_PAIR, ("gearbox.meshes[0].double_contact_share=0.5",))
    assert exc.value.path == "gearbox.meshes[0].double_contact_share"


def test_a_helical_pair_needs_the_share_given(tmp_path):
    p = _levels_file(tmp_path)
    x = 0.12 + 0.002 * 120 / (2 * math.cos(math.radians(15.0)))    # the centre distance
    sc = load_scene(p, ("gearbox.gears[0].helix_angle=15.0", "gearbox.gears[1].helix_angle=15.0",
                        f"gearbox.shafts[1].x={x!r}"))
    with pytest.raises(ConfigError) as exc:
        mesh_law(sc.gearbox, 0)
    assert exc.value.path == "gearbox.meshes[0].double_contact_share"
    assert "helical" in str(exc.value)
