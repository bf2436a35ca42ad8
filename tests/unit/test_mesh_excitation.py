"""Every mesh excites at its own mesh frequency (config/model/gearbox.py, models/gearbox/model.py).

The scene: configs/gear_pair.toml (input z1 = 40 -> intermediate z2 = 80) with a second
stage on a third shaft, z3 on the intermediate shaft -> z4 on the output shaft, no housing.
Independent references:
* kinematics: the second stage's mesh frequency over the first's is z3 p_2 / z1 = z3 (40 /
  80) / 40 = z3 / 80, an exact fraction of the tooth counts; its excitation repeats with
  the first stage's after the denominator's count of mesh periods (z3 = 15: 3/16, 16 mesh
  periods; z3 = 23: 23/80, 80);
* the spectrum of a linear time-periodic system whose only parametric and kinematic
  source is stage 2 (G1 excite = false) holds lines only at multiples of stage 2's mesh
  frequency: the periodic orbit over the common period has no line at G1's mesh frequency
  (1 is no multiple of 3/16), and does once G1 excites.
"""
from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.config import ConfigError, load_scene
from vibrogear.models.gearbox.model import build_gearbox
from vibrogear.models.validate import validate_scene
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.periodic.shooting import ShootingOptions, shoot
from vibrogear.solvers.static import static_equilibrium

ROOT = Path(__file__).resolve().parents[2]
GEAR_PAIR = ROOT / "configs" / "gear_pair.toml"


def _second_stage(z3: int, module: float) -> str:
    """A third shaft with stage 2 (z3 -> 2 z3) at housing y = 0.14, its bearings and a load."""
    z4 = 2 * z3
    x = 0.24 + module * (z3 + z4) / 2
    return f"""
[[gearbox.shafts]]
name = "output"
x = {x!r}
z = 0.18
y0 = -0.04
master_count = 16
modal_damping = 0.01
[gearbox.shafts.material]
E = 2.1e11
nu = 0.3
rho = 7850.0
[[gearbox.shafts.sections]]
length = 0.04
outer_diameter = 0.040
elements = 2
[[gearbox.shafts.sections]]
length = 0.20
outer_diameter = 0.050
elements = 10
[[gearbox.shafts.sections]]
length = 0.04
outer_diameter = 0.040
elements = 2

[[gearbox.gears]]
name = "z3"
shaft = "driven"
position = 0.18
teeth = {z3}
module = {module!r}
width = 0.02
inner_diameter = 0.05

[[gearbox.gears]]
name = "z4"
shaft = "output"
position = 0.18
teeth = {z4}
module = {module!r}
width = 0.02
inner_diameter = 0.05

[[gearbox.meshes]]
name = "G2"
gear_a = "z3"
gear_b = "z4"
stiffness = 3.0e8
damping = 500.0
backlash = 1.0e-4
stiffness_cos = [0.15]
te_cos = [4.0e-6, 1.0e-6]

[[gearbox.bearings]]
name = "C front"
shaft = "output"
position = 0.04
type = "spring"
stiffness = 2.5e8
axial_stiffness = 5.0e7
damping = 300.0

[[gearbox.bearings]]
name = "C back"
shaft = "output"
position = 0.24
type = "spring"
stiffness = 2.5e8
damping = 300.0

[[gearbox.couplings]]
name = "output load"
shaft = "output"
position = 0.28
role = "load"
stiffness = 1.0e4
twist = 0.01
damping = 2.0
"""


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    """(within the period limit: z3 = 15, module 4 mm; beyond: z3 = 23, module 3 mm)."""
    d = tmp_path_factory.mktemp("two_stage")
    out = []
    for name, z3, module in (("within", 15, 0.004), ("beyond", 23, 0.003)):
        p = d / f"{name}.toml"
        p.write_text(GEAR_PAIR.read_text() + _second_stage(z3, module))
        out.append(p)
    return out


def test_mesh_frequencies_are_the_tooth_count_fractions(scenes):
    within = load_scene(scenes[0])
    beyond = load_scene(scenes[1], ("scene.analyses=['time_response']",))
    assert within.gearbox.mesh_frequency_ratios() == (Fraction(1), Fraction(15, 80))
    assert within.gearbox.common_period() == 16 and not within.gearbox.multi_frequency
    assert beyond.gearbox.mesh_frequency_ratios() == (Fraction(1), Fraction(23, 80))
    assert beyond.gearbox.common_period() == 80 and beyond.gearbox.multi_frequency
    r = build_gearbox(within).reduced
    assert r.period_multiple == 16 and r.forcing_period_multiple == 16
    assert r.excitation_period(3000.0) == pytest.approx(16 * r.base_period(3000.0), rel=1e-15)
    # G2's harmonics sit in the slots of orders 3/16 and 6/16, G1's in 1 and 2
    orders = list(r.harmonic_orders)
    g2 = list(r.contacts.names).index("G2")
    k1, k2 = orders.index(3 / 16), orders.index(6 / 16)
    assert r.contacts.stiffness_cos[g2, k1] == 0.15
    assert r.contacts.error_cos[g2, [k1, k2]].tolist() == [4.0e-6, 1.0e-6]
    assert not np.any(r.contacts.stiffness_cos[g2, [orders.index(1.0), orders.index(2.0)]])
    assert r.contacts.error_cos[0, orders.index(1.0)] == 5.0e-6
    # beyond the limit the solvers sample per mesh period of G1: multi-frequency forced
    rb = build_gearbox(beyond).reduced
    assert rb.multi_frequency and rb.period_multiple == 1 and rb.forcing_period_multiple == 80
    assert rb.excitation_period(3000.0) == rb.base_period(3000.0)


def test_excite_false_keeps_the_mean_spring_only(scenes):
    sc = load_scene(scenes[0], ("gearbox.meshes[1].excite=false",))
    assert sc.gearbox.common_period() == 1
    r = build_gearbox(sc).reduced
    g2 = list(r.contacts.names).index("G2")
    for a in (r.contacts.stiffness_cos, r.contacts.stiffness_sin, r.contacts.error_cos,
              r.contacts.error_sin):
        assert not np.any(a[g2])
    assert build_gearbox(sc).contacts[g2].k_hi == 3.0e8       # the mean spring stays


def _orbit_lines(sc, rpm):
    """The periodic orbit over the common period (shooting) and the amplitude spectrum of
    each mesh's deformation over it, by order of G1's mesh frequency: {order: |line|} per mesh."""
    r = build_gearbox(sc).reduced
    st = static_equilibrium(r, rpm)
    u0 = np.concatenate([st.x, np.zeros(r.n_modes)])
    opts = IntegrationOptions(rtol=1e-9, atol=1e-14)
    tol = sc.shooting.tol
    sh = shoot(r, rpm, u0, options=opts, shooting=ShootingOptions(tol=tol, max_iter=25))
    P, n = r.period_multiple, 32
    t = np.arange(1, P * n + 1) * r.base_period(rpm) / n
    tr = integrate(r, rpm, sh.u0, 0.0, t[-1], t_eval=t, options=opts)
    x = np.vstack([sh.u0[None, :r.n_modes], tr.u[:-1, :r.n_modes]])    # u(T) = u(0)
    delta = x @ r.contacts.directions[:2].T                         # (samples, 2 meshes)
    amp = np.abs(np.fft.rfft(delta, axis=0)) / (P * n) * 2
    return sh, r, {k / P: amp[k] for k in range(amp.shape[0])}


def test_each_stage_excites_at_its_own_mesh_frequency_and_shooting_closes(scenes):
    rpm = 3000.0
    sc = load_scene(scenes[0])
    sh, r, lines = _orbit_lines(sc, rpm)
    assert sh.converged and sh.residual < sc.shooting.tol
    size = max(v.max() for v in lines.values())
    # both stages' lines: G1 at 1 and 2, G2 at 3/16 and 6/16
    for order in (1.0, 2.0, 3 / 16, 6 / 16):
        assert lines[order].max() > 1e-3 * size, order
    # G1 switched off: G2's lines stay, none at G1's mesh frequency and its harmonic
    off = load_scene(scenes[0], ("gearbox.meshes[0].excite=false",))
    sh2, _, lines2 = _orbit_lines(off, rpm)
    assert sh2.converged and sh2.residual < off.shooting.tol
    size2 = max(v.max() for k, v in lines2.items() if k > 0)
    assert lines2[3 / 16].max() > 1e-2 * size2
    for order in (1.0, 2.0):
        assert lines2[order].max() < 1e-6 * size2, (order, lines2[order], size2)
    # every line of the G1-off orbit is at a multiple of 3/16
    for order, v in lines2.items():
        if order > 0 and Fraction(order).limit_denominator(16) % Fraction(3, 16):
            assert v.max() < 1e-6 * size2, order


def test_continuation_beyond_the_period_limit_is_refused_by_name(scenes, capsys, tmp_path):
    with pytest.raises(ConfigError) as exc:           # gear_pair.toml lists continuation
        validate_scene(load_scene(scenes[1]))
    msg = str(exc.value)
    assert exc.value.path == "gearbox.meshes"
    assert "'G2' (23/46 teeth) at 23/80" in msg and "80 mesh periods" in msg
    assert main(["check", str(scenes[1])]) == 2
    assert "continuation: shooting needs a common excitation period" in capsys.readouterr().err
    out = tmp_path / "o"
    assert main(["continue", str(scenes[1]), "--quiet", "--out", str(out)]) == 2
    assert not out.exists()
    capsys.readouterr()
    # a map with LP/PD curves shoots too (gear_pair.toml: [map] curves = true); without them
    # it samples
    assert main(["map", str(scenes[1]), "--quiet", "--out", str(out)]) == 2
    assert "map (its LP/PD curves): shooting needs" in capsys.readouterr().err
    assert main(["check", str(scenes[1]), "--set", "scene.analyses=['map']",
                 "--set", "map.curves=false"]) == 0
    capsys.readouterr()
    # the verbs that sample run on the same file (the CLI checks the verb alone)
    assert main(["time", str(scenes[1]), "--set", "time_response.periods=4", "--quiet",
                 "--out", str(tmp_path / "t")]) == 0
    # the analyses that sample run: check passes and states the period
    ok = ["--set", "scene.analyses=['time_response', 'sweep', 'nvh']"]
    assert main(["check", str(scenes[1]), *ok]) == 0
    text = capsys.readouterr().out
    assert "repeat together only every 80 mesh periods" in text
    assert "multi-frequency forced" in text


def test_time_response_beyond_the_limit_has_each_stages_lines(scenes):
    """z3 = 23 (G2 at 23/80, no common period within the limit): a time response from the
    static equilibrium, 160 mesh periods settled, 320 recorded (bins of 1/320 of G1's mesh
    frequency: G2's 23/80 is bin 92), Hann window: G2's lines at 23/80 and 46/80 stand out,
    and with G1 excite = false nothing is left at G1's 1 and 2 (bins 320, 640)."""
    rpm, settle, rec, n = 3000.0, 160, 320, 32

    def spectrum(overrides):
        sc = load_scene(scenes[1], ("scene.analyses=['time_response']",) + overrides)
        r = build_gearbox(sc).reduced
        assert r.multi_frequency
        T = r.base_period(rpm)
        u0 = np.concatenate([static_equilibrium(r, rpm).x, np.zeros(r.n_modes)])
        opts = IntegrationOptions(rtol=1e-9, atol=1e-14)
        t = settle * T + np.arange(rec * n) * T / n
        tr = integrate(r, rpm, u0, 0.0, t[-1], t_eval=t, options=opts)
        assert tr.ok
        delta = tr.u[:, :r.n_modes] @ r.contacts.directions[:2].T
        delta = delta - delta.mean(axis=0)
        return np.abs(np.fft.rfft(delta * np.hanning(t.size)[:, None], axis=0))

    both = spectrum(())
    g2 = list(range(88, 97))                    # around bin 92 (Hann: the line spans 3 bins)
    assert both[92, 1] > 100 * np.median(both[40:80, 1])       # G2's own line on G2
    assert both[320, 0] > 100 * np.median(both[40:80, 0])      # G1's own line on G1
    off = spectrum(("gearbox.meshes[0].excite=false",))
    assert off[92].max() > 1e6 * max(off[319:322].max(), off[639:642].max()), \
        (off[g2].max(axis=0), off[319:322], off[639:642])
    assert off[184].max() > 1e6 * off[639:642].max()          # G2's 2nd harmonic, not G1's
