"""``vibrogear states`` (issue 33): the Wilson interval, the starts, the grouping of settled
motions into attractors, and bad input (exit 2 naming the field, nothing written)."""
from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

from vibrogear import runner
from vibrogear.analyses.states.cluster import cluster_point, wilson
from vibrogear.analyses.states.starts import draw_start, start_scales
from vibrogear.cli import main
from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.integrator.contact_eval import contact_kinematics
from vibrogear.solvers.sequential.sweep_point import PointRecord

ROOT = Path(__file__).resolve().parents[2]
IMPACT = str(ROOT / "configs" / "impact_pair.toml")
GEAR_PAIR = str(ROOT / "configs" / "gear_pair.toml")
Z = 1.959963984540054          # the 97.5 % point of the normal distribution


def _wilson_closed_form(k, n):
    p = k / n
    c = (p + Z * Z / (2 * n)) / (1 + Z * Z / n)
    h = Z / (1 + Z * Z / n) * math.sqrt(p * (1 - p) / n + Z * Z / (4 * n * n))
    return c - h, c + h


@pytest.mark.parametrize("k, n", [(0, 10), (3, 10), (16, 32), (32, 32), (1, 400)])
def test_wilson_interval_is_the_closed_form_score_interval(k, n):
    lo, hi = wilson(k, n)
    elo, ehi = _wilson_closed_form(k, n)
    assert abs(lo - max(elo, 0.0)) < 1e-12 and abs(hi - min(ehi, 1.0)) < 1e-12


def test_wilson_of_a_sure_outcome_is_n_over_n_plus_z2():
    # all N starts on one attractor: the interval is [N / (N + z^2), 1]
    for n in (8, 32, 128):
        lo, hi = wilson(n, n)
        assert hi == pytest.approx(1.0) and lo == pytest.approx(n / (n + Z * Z), rel=1e-12)


def _model():
    return impact_pair_model(0.015, 0.5, 0.55, 0.12, 1.0)


def test_box_starts_are_reproducible_uniform_and_independent_of_order():
    m = _model()
    sc = start_scales(m, 0.9, np.zeros(2), deformation_scale=2.0, velocity_scale=1.0,
                      box=((-4.0, 5.0), (-1.0, 3.0)))
    a = np.array([draw_start(sc, m, 7, 3, k) for k in range(400)])
    b = np.array([draw_start(sc, m, 7, 3, k) for k in reversed(range(400))])[::-1]
    assert np.array_equal(a, b)                       # start k is start k, in any order
    assert not np.array_equal(a, [draw_start(sc, m, 8, 3, k) for k in range(400)])
    assert a[:, 0].min() >= -4.0 and a[:, 0].max() <= 5.0
    assert a[:, 1].min() >= -1.0 and a[:, 1].max() <= 3.0
    # uniform: the mean within 4 standard errors of the box's middle (9 / sqrt(12 * 400))
    assert abs(a[:, 0].mean() - 0.5) < 4 * 9 / math.sqrt(12 * 400)


def test_scaled_starts_put_the_mesh_in_its_documented_interval():
    """No box: the contact deformation at t = 0 is uniform over [g_lo - a P, g_hi + a P]
    (P: static penetration), the velocity within b times the forced response's amplitude."""
    from vibrogear.solvers.static import static_equilibrium

    m = _model()
    u_s = static_equilibrium(m, 0.9).u0
    sc = start_scales(m, 0.9, u_s, deformation_scale=2.0, velocity_scale=1.0)
    pen = u_s[0] - 1.0                      # q_s - b_r: the static state is in contact
    assert pen > 0
    d = np.array([contact_kinematics(m, 0.9, [0.0], draw_start(sc, m, 0, 0, k)[None, :])[0][0, 0]
                  for k in range(300)])
    assert d.min() >= -1.0 - 2 * pen - 1e-12 and d.max() <= 1.0 + 2 * pen + 1e-12
    lo, hi = -1.0 - 2 * pen, 1.0 + 2 * pen
    assert d.min() < lo + 0.05 * (hi - lo) and d.max() > hi - 0.05 * (hi - lo)   # all of it
    # the forced response of the linearised pair: contact stiffness 1 at the static state,
    # the velocity c Re(V e^(i phi)), |c| <= 1, |V| = Omega f_p / |1 - Omega^2 + 2 i zeta Omega| (one harmonic, one mode)
    amp = 0.9 * 0.12 / abs(1 - 0.81 + 2j * 0.015 * 0.9)
    v = np.array([draw_start(sc, m, 0, 0, k)[1] for k in range(300)])
    assert np.max(np.abs(v)) <= amp + 1e-12 and np.max(np.abs(v)) > 0.7 * amp


def _rec(k, n, cycle, cls=1, qmin=0.0, qmax=1.0, metrics=None):
    cyc = None if cycle is None else np.asarray(cycle, float)
    return PointRecord("start", k, 1.0, qmin, qmax, np.zeros(4), n, 0.0, 0.0, n, 0, "ok",
                       np.zeros(2) if cyc is None else cyc[-1], states=cyc, motion_class=cls,
                       metrics=metrics or {})


def test_cluster_joins_a_period_2_cycle_reached_at_either_phase_and_counts_basins():
    a = [[1.0, 0.5], [2.0, -0.5]]
    b = [[2.0, -0.5], [1.0 + 1e-6, 0.5]]          # the same cycle, other phase
    c = [[3.0, 0.1], [0.5, -0.1]]                 # another period-2 cycle
    recs = [_rec(0, 2, a), _rec(1, 2, b), _rec(2, 2, c), _rec(3, 1, [[1.0, 0.5]]),
            _rec(4, 2, b)]
    atts, n_ok, n_failed = cluster_point(recs, 0, 1.0, n_modes=1, cluster_tol=1e-3,
                                         stat_tol=0.05)
    assert (n_ok, n_failed) == (5, 0)
    assert sorted(len(x.members) for x in atts) == [1, 1, 3]
    big = atts[0]
    assert big.members == [0, 1, 4] and big.fraction == pytest.approx(0.6)
    assert big.ci == pytest.approx(_wilson_closed_form(3, 5))


def test_cluster_tells_chaotic_motions_apart_by_their_statistics():
    def chaotic(k, imp, err, q1):
        return _rec(k, 0, None, cls=3, qmin=-1.0, qmax=q1, metrics={
            "impacts_drive_G1": imp, "impacts_drive_G1_err": err, "impacts_back_G1": 0.0,
            "impacts_back_G1_err": 0.0, "rattle_G1": 1.0, "rattle_G1_err": 0.01})
    recs = [chaotic(0, 0.40, 0.02, 2.0), chaotic(1, 0.43, 0.02, 2.01),   # within 3 errors
            chaotic(2, 0.90, 0.02, 2.0),                                  # rattles more
            _rec(3, 1, [[0.0, 0.0]])]                                     # a quiet orbit
    atts, _, _ = cluster_point(recs, 0, 1.0, n_modes=1, cluster_tol=1e-3, stat_tol=0.05)
    assert sorted(x.members for x in atts) == [[0, 1], [2], [3]]
    rattle = next(x for x in atts if x.members == [0, 1])
    assert rattle.metrics["G1"]["impacts"] == pytest.approx(0.415)
    assert rattle.summary()["class"] == "chaotic"


def test_failed_starts_are_counted_apart():
    bad = PointRecord("start", 1, 1.0, math.nan, math.nan, np.zeros(4), 0, math.nan, math.nan,
                      0, -3, "diverged", np.zeros(2))
    atts, n_ok, n_failed = cluster_point([_rec(0, 1, [[1.0, 0.0]]), bad], 0, 1.0, n_modes=1,
                                         cluster_tol=1e-3, stat_tol=0.05)
    assert (n_ok, n_failed, len(atts)) == (1, 1, 1) and atts[0].fraction == 1.0


# ------------------------------------------------------------------ bad input

BAD = [
    ("starts-zero", [IMPACT, "--set", "states.starts=0"], ["states.starts", ">= 1"]),
    ("empty-range", [IMPACT, "--set", "states.omega_max=0.5"],
     ["states.omega_max", "greater than omega_min"]),
    ("empty-range-rpm", [GEAR_PAIR, "--set", "states.rpm_max=4000"],
     ["states.rpm_max", "greater than rpm_min"]),
    ("nan-scale", [GEAR_PAIR, "--set", "states.deformation_scale=nan"],
     ["states.deformation_scale", "finite"]),
    ("nan-velocity-scale", [GEAR_PAIR, "--set", "states.velocity_scale=nan"],
     ["states.velocity_scale", "finite"]),
    ("box-on-gearbox", [GEAR_PAIR, "--set", "states.q_range=[0.0, 1e-5]", "--set",
                        "states.v_range=[0.0, 1.0]"], ["states.q_range", "impact pair only"]),
    ("half-a-box", [IMPACT, "--set", "states.v_range=[1.0, 2.0]", "--set",
                    "states.q_range=[3.0, 2.0]"], ["states.q_range", "lo < hi"]),
    ("negative-tol", [IMPACT, "--set", "states.basin_tol=-0.1"], ["states.basin_tol", "> 0"]),
]


@pytest.mark.parametrize("args, expected", [c[1:] for c in BAD], ids=[c[0] for c in BAD])
def test_states_bad_input_exits_2_naming_the_field(tmp_path, monkeypatch, capsys, args,
                                                   expected):
    monkeypatch.chdir(tmp_path)

    def tripwire(*a, **k):
        raise AssertionError("run_scene reached: the input was not rejected first")
    monkeypatch.setattr(runner, "run_scene", tripwire)
    code = main(["states", *args, "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2, err
    msg = err[len("vibrogear: invalid input: "):]
    assert msg.startswith(expected[0]), msg
    for text in expected[1:]:
        assert text in msg, msg
    assert os.listdir(tmp_path) == []


# ------------------------------------------------------------------ the run

def _ip_scene(**states):
    from vibrogear.config import scene_from_dict
    d = {"scene": {"name": "ip", "analyses": ["states"]},
         "impact_pair": {"zeta": 0.05, "kappa": 0.5, "f_m": 0.55, "f_p": 0.12, "b_r": 1.0},
         "integration": {"rtol": 1e-8, "atol": 1e-10},
         "states": {"omega_min": 0.9, "omega_max": 1.1, "n_points": 2, "starts": 4,
                    "batch": 3, "q_range": [-3.0, 4.0], "v_range": [-3.0, 3.0],
                    "transient_periods": 100, "record_periods": 16, "branches": False,
                    "workers": 1, **states}}
    return scene_from_dict(d)


def test_resume_reuses_settled_starts_and_more_starts_add_to_them(tmp_path):
    from vibrogear.analyses.states import states
    from vibrogear.analyses.study import build_study
    from vibrogear.pipeline.outcome import RunContext

    ctx = RunContext(out=tmp_path, quiet=True)
    first = states.run(build_study(_ip_scene()), _ip_scene(), ctx)
    assert first.summary["counters"]["starts_resumed"] == 0
    again = states.run(build_study(_ip_scene()), _ip_scene(), ctx)
    assert again.summary["counters"]["starts_resumed"] == 8
    assert again.summary["per_speed"] == first.summary["per_speed"]
    more = states.run(build_study(_ip_scene(starts=6)), _ip_scene(starts=6), ctx)
    assert more.summary["counters"]["starts_resumed"] == 8
    assert more.summary["counters"]["starts_settled"] == 12
    # the first four starts are the same starts: their end states are reused exactly
    a, b = first.result.starts, more.result.starts
    assert np.array_equal(a["attractor"] >= 0, (b["attractor"] >= 0)[np.isin(b["index"], range(4))])


def test_the_census_does_not_depend_on_workers_or_batch(tmp_path):
    from vibrogear.analyses.states import states
    from vibrogear.analyses.study import build_study
    from vibrogear.pipeline.outcome import RunContext

    one = states.run(build_study(_ip_scene()), _ip_scene(),
                     RunContext(out=tmp_path / "a", quiet=True))
    two = states.run(build_study(_ip_scene(workers=2, batch=1)), _ip_scene(workers=2, batch=1),
                     RunContext(out=tmp_path / "b", quiet=True))
    assert one.summary["per_speed"] == two.summary["per_speed"]


def test_cli_writes_the_danger_map_and_its_files(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(Path(IMPACT).read_text())
    code = main(["states", str(scene), "--out", str(tmp_path / "o"), "--quiet",
                 "--set", "states.n_points=2", "--set", "states.starts=3",
                 "--set", "states.omega_min=0.95", "--set", "states.branches=false"])
    assert code == 0
    o = tmp_path / "o"
    for name in ("states.npz", "states.csv", "states.png", "summary.json", "report.html"):
        assert (o / name).is_file(), name
    assert not (o / "states.partial.jsonl").exists()
    with np.load(o / "states.npz") as z:
        for key in ("attractor_param", "attractor_class", "attractor_period_n",
                    "attractor_qmin", "attractor_qmax", "basin_fraction", "basin_ci_lo",
                    "basin_ci_hi", "n_starts", "attractor_class_legend"):
            assert key in z.files, key
        assert z["n_starts"].tolist() == [3, 3]
    import json
    rec = json.loads((o / "summary.json").read_text())["results"]["states"]
    assert [s["n_starts"] for s in rec["per_speed"]] == [3, 3]
    assert (o / "states.csv").read_text().splitlines()[0].startswith("Omega,class,period_n")


def test_basin_tol_stops_a_speed_once_every_interval_is_narrow_enough(tmp_path):
    """One sure attractor (a clearance never reached): the Wilson interval after N starts is
    [N / (N + z^2), 1], width z^2 / (N + z^2) = 0.49, 0.32, 0.24 at N = 4, 8, 12: with
    basin_tol = 0.3 and rounds of 4 the census stops at 12 of the 40 starts."""
    from vibrogear.analyses.states import states
    from vibrogear.analyses.study import build_study
    from vibrogear.config import scene_from_dict

    d = {"scene": {"name": "ip", "analyses": ["states"]},
         "impact_pair": {"zeta": 0.1, "kappa": 0.5, "f_m": 0.55, "f_p": 0.12, "b_r": 100.0},
         "states": {"omega_min": 0.9, "omega_max": 1.1, "n_points": 2, "starts": 40,
                    "batch": 4, "basin_tol": 0.3, "q_range": [-3.0, 4.0],
                    "v_range": [-3.0, 3.0], "transient_periods": 100, "record_periods": 16,
                    "branches": False, "workers": 1}}
    scene = scene_from_dict(d)
    from vibrogear.pipeline.outcome import RunContext
    out = states.run(build_study(scene), scene, RunContext(out=tmp_path, quiet=True))
    assert [s["n_starts"] for s in out.summary["per_speed"]] == [12, 12]
    assert out.summary["stopped_early_at"] == [0.9, 1.1]
    assert out.summary["counters"]["rounds"] == 3
