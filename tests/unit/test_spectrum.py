"""One-sided amplitude spectra over whole periods (solvers/sequential/spectrum.py) against closed forms,
and the ``nvh`` verb on the gear pair: frequency axis from the tooth count, Parseval, the
same spectra whether the steady points come from a sweep or from the [nvh] grid, and bad
[nvh] input."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.config import load_scene
from vibrogear.config.base import ConfigError
from vibrogear.solvers.sequential.spectrum import amplitude_spectrum, power_from_amplitudes

ROOT = Path(__file__).resolve().parents[2]
GEAR_PAIR = ROOT / "configs" / "gear_pair.toml"


@pytest.mark.parametrize("R,S", [(8, 64), (5, 32), (1, 16)])
def test_pure_harmonics_exact_to_the_bin(R, S):
    T = 2.7e-4                                   # an excitation period [s]
    n = R * S
    t = np.arange(n) * (T / S)
    # mean 0.3, harmonic 1: 2.0 at phase 0.4, harmonic 3: 0.5 (sin), harmonic 5: 0.125
    x = (0.3 + 2.0 * np.cos(2 * np.pi * t / T + 0.4) + 0.5 * np.sin(2 * np.pi * 3 * t / T)
         + 0.125 * np.cos(2 * np.pi * 5 * t / T - 1.0))
    sp = amplitude_spectrum(x, R * T)
    assert sp.freq.size == n // 2 + 1
    expect = np.zeros(n // 2 + 1)
    expect[0] = 0.3
    for h, a in ((1, 2.0), (3, 0.5), (5, 0.125)):
        k = h * R
        assert sp.freq[k] == pytest.approx(h / T, rel=1e-14)      # exactly on bin h R
        expect[k] = a
    assert np.max(np.abs(sp.amplitude - expect)) < 1e-12
    # Parseval: mean(x^2) of the closed form = 0.3^2 + (2^2 + 0.5^2 + 0.125^2) / 2
    closed = 0.3 ** 2 + (2.0 ** 2 + 0.5 ** 2 + 0.125 ** 2) / 2
    assert np.mean(x ** 2) == pytest.approx(closed, rel=1e-12)
    assert power_from_amplitudes(sp.amplitude, n) == pytest.approx(closed, rel=1e-12)
    assert sp.parseval_error < 1e-12


def test_nyquist_bin_and_odd_lengths():
    n = 16
    x = np.cos(np.pi * np.arange(n))             # the Nyquist bin: +1, -1, ...
    sp = amplitude_spectrum(x, 1.0)
    assert sp.amplitude[-1] == pytest.approx(1.0) and np.allclose(sp.amplitude[:-1], 0.0)
    assert sp.parseval_error < 1e-14
    assert power_from_amplitudes(sp.amplitude, n) == pytest.approx(1.0)
    rng = np.random.default_rng(1)
    for m in (15, 17, 64):
        y = rng.standard_normal((3, m))
        assert amplitude_spectrum(y, 2.0).parseval_error < 1e-12


def _spectra(out: Path) -> dict:
    with np.load(out / "spectra.npz") as z:
        return {k: z[k] for k in z.files}


def test_nvh_gear_pair_sweep_and_own_grid_agree(tmp_path):
    """Three speeds of the gear pair: settled by a [sweep] run before nvh, or by nvh's own
    grid; both give the same steady spectra (the points are period-1).  The frequency axis
    is the tooth-pass frequency z n / 60 of the scene's pinion (read from the TOML)."""
    common = ["--quiet", "--set", "nvh.rpm_min=4600", "--set", "nvh.rpm_max=4700",
              "--set", "nvh.n_speeds=3", "--set", "nvh.record_periods=4"]
    own, swept = tmp_path / "own", tmp_path / "swept"
    assert main(["nvh", str(GEAR_PAIR), "--out", str(own), *common]) == 0
    assert main(["run", str(GEAR_PAIR), "--out", str(swept), *common,
                 "--set", 'scene.analyses=["sweep", "nvh"]', "--set", "sweep.rpm_min=4600",
                 "--set", "sweep.rpm_max=4700", "--set", "sweep.n_points=3",
                 "--set", 'sweep.directions=["up"]', "--set", "sweep.lyapunov=false"]) == 0
    a, b = _spectra(own), _spectra(swept)
    assert np.allclose(a["rpm"], [4600, 4650, 4700]) and np.allclose(b["rpm"], a["rpm"])
    scene = load_scene(GEAR_PAIR)
    g = scene.gearbox
    teeth = g.gears[g.gear_index(g.meshes[0].gear_a, "")].teeth
    R = 4
    assert np.allclose(a["freq_hz"][:, R], teeth * a["rpm"] / 60.0, rtol=1e-12)
    assert np.allclose(a["mesh_hz"][:, 0], teeth * a["rpm"] / 60.0, rtol=1e-12)
    for q in ("dte", "mesh_force"):
        assert float(a[f"parseval_{q}"]) < 1e-10
        amp_a, amp_b = a[f"amp_{q}"][:, 0], b[f"amp_{q}"][:, 0]
        big = amp_a[:, R] + amp_a[:, 2 * R]
        assert np.all(big > 0)
        # mesh orders 1 and 2 of two settled orbits: equal to the settling tolerance
        for k in (0, R, 2 * R):
            assert np.allclose(amp_a[:, k], amp_b[:, k], rtol=1e-3, atol=1e-4 * big.max())
    summary = json.loads((swept / "summary.json").read_text())["results"]["nvh"]
    assert summary["source"] == "sweep:up"
    assert "no housing" in summary["erp"] and not (own / "erp.csv").exists()
    assert (own / "nvh_waterfall_dte.png").stat().st_size > 0


@pytest.mark.parametrize("override,field", [
    ("nvh.samples_per_period=48", "nvh.samples_per_period"),
    ("nvh.max_order=32", "nvh.samples_per_period"),
    ("nvh.rho_air=-1.0", "nvh.rho_air"),
    ("nvh.record_periods=0", "nvh.record_periods"),
    ('nvh.sweep_direction="sideways"', "nvh.sweep_direction"),
    ("nvh.velocity_rpms=[-5.0]", "nvh.velocity_rpms"),
])
def test_bad_nvh_input_names_the_field(override, field):
    with pytest.raises(ConfigError) as err:
        load_scene(GEAR_PAIR, (override,))
    assert err.value.path.startswith(field), str(err.value)


def test_grid_needs_both_ends(tmp_path):
    text = GEAR_PAIR.read_text().replace("[nvh]\nrpm_min = 4500.0\n", "[nvh]\n")
    p = tmp_path / "gp.toml"
    p.write_text(text)
    with pytest.raises(ConfigError) as err:
        load_scene(p)
    assert err.value.path == "nvh.rpm_min"
    # no grid and no sweep before: exit 2, nothing written
    text = text.replace("rpm_max = 7000.0\nn_speeds = 26", "n_speeds = 26")
    p.write_text(text)
    out = tmp_path / "out"
    assert main(["nvh", str(p), "--out", str(out), "--quiet"]) == 2
    assert not out.exists()
