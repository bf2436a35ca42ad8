"""Findings: bands derived from per-point arrays, checked against hand-made arrays whose
bands are known, and recomputable from the file with the band's own metric, op, threshold
(``recompute_band`` below is written from the documented definition, not from the code)."""
from __future__ import annotations

import operator

import numpy as np
import pytest

from vibrogear.analyses.findings.findings import derive_findings
from vibrogear.config import ConfigError
from vibrogear.config.base import build
from vibrogear.config.sections.findings import FindingsConfig
from vibrogear.report.writers.findings import console_lines, plot_band_chart

OPS = {">": operator.gt, ">=": operator.ge, "<": operator.lt, "<=": operator.le,
       "==": operator.eq}


def recompute_band(arrays: dict, band: dict) -> set[float]:
    """The grid speeds at which ``band``'s test holds in its direction(s), from the file:
    'up'/'down': in that direction and not the other; 'both': in both (docs/findings.md)."""
    param = np.asarray(arrays["param"], float)
    direction = np.asarray(arrays["direction"], str)
    ok = np.asarray(arrays["ok"], bool)
    op = OPS[band["op"]]
    compare = band.get("compare", "")
    if compare.startswith("min("):
        a, b = compare[4:-1].split(", ")
        values = np.minimum(arrays[a], arrays[b])
    else:
        values = np.asarray(arrays[band["metric"]], float)
    if compare == "abs(up - down)":
        held = set()
        for p in np.unique(param):
            u = values[(param == p) & (direction == "up") & ok]
            d = values[(param == p) & (direction == "down") & ok]
            if u.size and d.size and op(abs(u[0] - d[0]), band["threshold"]):
                held.add(float(p))
        return held
    holds = {d: {float(p) for p in param[(direction == d) & ok & op(values, band["threshold"])]}
             for d in ("up", "down")}
    if band["direction"] == "both":
        return holds["up"] & holds["down"]
    other = "down" if band["direction"] == "up" else "up"
    return holds[band["direction"]] - holds[other]


def check_bands_recompute(arrays: dict, findings: dict) -> int:
    """Every sweep band's [from, to] is a maximal run of grid points where its test holds."""
    grid = np.unique(np.asarray(arrays["param"], float))
    checked = 0
    for band in findings["bands"]:
        if band["source"] != "sweep.npz":
            continue
        held = recompute_band(arrays, band)
        inside = {float(p) for p in grid if band["from"] <= p <= band["to"]}
        assert inside <= held, (band, sorted(inside - held))
        i0 = int(np.searchsorted(grid, band["from"]))
        i1 = int(np.searchsorted(grid, band["to"]))
        assert i0 == 0 or float(grid[i0 - 1]) not in held, band       # maximal run
        assert i1 == grid.size - 1 or float(grid[i1 + 1]) not in held, band
        assert band["edge_err"] == pytest.approx(float(np.min(np.diff(grid))))
        checked += 1
    return checked


def _sweep(cf_up, cf_down, back_up=None, back_down=None, cls=None) -> dict:
    """A two-direction sweep on the grid 100, 200, ..., 1000 rpm with one mesh 'G1'."""
    grid = np.arange(1, 11) * 100.0
    n = grid.size
    zeros = np.zeros(n)
    back_up = zeros if back_up is None else np.asarray(back_up, float)
    back_down = zeros if back_down is None else np.asarray(back_down, float)
    cls = np.ones(2 * n, int) if cls is None else np.asarray(cls)
    return {
        "param": np.concatenate([grid, grid[::-1]]),
        "direction": np.array(["up"] * n + ["down"] * n),
        "ok": np.ones(2 * n, bool),
        "qmin": np.zeros(2 * n), "qmax": np.ones(2 * n) * 1e-5,
        "period_n": np.where(cls == 1, 1, 0),
        "motion_class": cls, "motion_class_legend": np.array(["failed", "periodic",
                                                             "quasi-periodic", "chaotic",
                                                             "not settled", "aperiodic"]),
        "contact_fraction_G1": np.concatenate([cf_up, np.asarray(cf_down)[::-1]]),
        "impacts_drive_G1": np.concatenate([zeros, zeros]),
        "impacts_back_G1": np.concatenate([back_up, back_down[::-1]]),
    }


def test_contact_loss_bands_per_direction():
    """Contact lost at 300-500 rpm in both directions and at 600-700 rpm going down only:
    one 'both' band 300-500 and one 'down' band 600-700, each avoid."""
    cf = np.ones(10)
    up = cf.copy()
    up[2:5] = 0.9
    down = up.copy()
    down[5:7] = 0.95
    arrays = _sweep(up, down)
    f = derive_findings({"sweep.npz": arrays}, {}, FindingsConfig())
    loss = [b for b in f["bands"] if b["quantity"] == "contact loss"]
    assert [(b["direction"], b["from"], b["to"], b["severity"]) for b in loss] == \
        [("both", 300.0, 500.0, "avoid"), ("down", 600.0, 700.0, "avoid")]
    assert all(b["metric"] == "contact_fraction_G1" and b["op"] == "<"
               and b["threshold"] == pytest.approx(0.99) for b in loss)
    assert check_bands_recompute(arrays, f) >= 2
    # where to run first: the speeds without a band, then what to avoid
    assert f["verdict"].startswith("Run at 100–200, 800–1000 rpm: no band to avoid or watch")
    assert "Avoid 300–700 rpm: G1 loses contact" in f["verdict"]
    assert [(w["from"], w["to"], w["status"]) for w in f["windows"]] == \
        [(100.0, 200.0, "fine"), (800.0, 1000.0, "fine")]


def test_rattle_and_rules_from_the_section():
    """Back-flank impacts of 0.02 and 0.3 per period: with back_impacts_above = 0.05 only
    the 0.3 points rattle; a rule set to 'fine' removes them from the verdict."""
    back = np.zeros(10)
    back[3] = 0.02
    back[6:9] = 0.3
    arrays = _sweep(np.ones(10), np.ones(10), back, back)
    rules = build(FindingsConfig, {"back_impacts_above": 0.05})
    f = derive_findings({"sweep.npz": arrays}, {}, rules)
    rattle = [b for b in f["bands"] if b["quantity"] == "rattle"]
    assert [(b["from"], b["to"], b["direction"]) for b in rattle] == [(700.0, 900.0, "both")]
    assert "0.30 back-flank impacts" in rattle[0]["evidence"]
    assert check_bands_recompute(arrays, f) >= 1
    quiet = derive_findings({"sweep.npz": arrays}, {},
                            build(FindingsConfig, {"back_impacts_above": 0.05,
                                                   "rattle": "fine"}))
    assert quiet["verdict"].startswith("Run at 100–1000 rpm: no band to avoid or watch")


def test_motion_classes_and_failed_points():
    """Chaos at 400-500 rpm up only; a failed point never belongs to a band."""
    cls = np.ones(20, int)
    cls[3:5] = 3                         # up: 400, 500 rpm
    arrays = _sweep(np.ones(10), np.ones(10), cls=cls)
    arrays["ok"][4] = False              # 500 rpm up failed
    arrays["motion_class"][4] = 0
    f = derive_findings({"sweep.npz": arrays}, {}, FindingsConfig())
    chaos = [b for b in f["bands"] if b["quantity"] == "chaotic motion"]
    assert [(b["from"], b["to"], b["direction"], b["severity"]) for b in chaos] == \
        [(400.0, 400.0, "up", "caution")]
    assert check_bands_recompute(arrays, f) >= 1


def test_hysteresis_band_and_jump_events():
    """qmax 10 um going up and 30 um going down at 500-600 rpm: a hysteresis band there
    and a jump event in each direction."""
    arrays = _sweep(np.ones(10), np.ones(10))
    arrays["qmax"] = np.full(20, 10e-6)
    arrays["qmax"][10 + 4:10 + 6] = 30e-6     # down run: 600, 500 rpm
    f = derive_findings({"sweep.npz": arrays}, {"sweep": {"monitored": "G1"}},
                        FindingsConfig())
    hyst = [b for b in f["bands"] if b["quantity"].startswith("hysteresis")]
    assert [(b["from"], b["to"], b["where"]) for b in hyst] == [(500.0, 600.0, "G1")]
    assert check_bands_recompute(arrays, f) >= 1
    jumps = [e for e in f["events"] if e["kind"] == "jump"]
    assert sorted(e["direction"] for e in jumps) == ["down", "down"]    # onto and off the
    assert sorted(e["at"] for e in jumps) == [450.0, 650.0]              # upper state
    # a file with the per-speed array (sweep.npz since hysteresis_<mesh>): the band's rule
    # reads it as written, 20 um up-down difference at 500 and 600 rpm
    arrays["hysteresis_G1"] = np.zeros(20)
    arrays["hysteresis_G1"][[4, 5, 14, 15]] = 20e-6
    f = derive_findings({"sweep.npz": arrays}, {"sweep": {"monitored": "G1"}},
                        FindingsConfig())
    hyst = [b for b in f["bands"] if b["quantity"].startswith("hysteresis")]
    assert [(b["from"], b["to"], b["metric"], b["op"], b["direction"]) for b in hyst] == \
        [(500.0, 600.0, "hysteresis_G1", ">", "both")]
    assert "compare" not in hyst[0]
    assert check_bands_recompute(arrays, f) >= 1


def test_jump_below_resolution_or_batch_error_is_not_reported():
    """The three-stage model's 'qmax changes from 1.49 to 1.49 um': a change of 5 nm over a
    run whose qmax spans 5 nm is 100 % of the range, but it is within the 1 nm / 1e-3
    resolution only where qmax_res says so, and within the batch-means errors where those
    are larger; a change above both is still a jump."""
    q = np.full(20, 1.49e-6)
    q[[5, 14]] = 1.495e-6                         # up and down at 600 rpm: +5 nm
    arrays = _sweep(np.ones(10), np.ones(10))
    arrays["qmax"] = q
    rules = FindingsConfig()

    def jumps(res, err):
        a = {**arrays, "qmax_res": np.full(20, res), "qmax_err": np.full(20, err)}
        f = derive_findings({"sweep.npz": a}, {"sweep": {"monitored": "G1"}}, rules)
        return [e for e in f["events"] if e["kind"] == "jump"]

    # a 0.3 % change of the level is a steep stretch, not a jump (jump_level_rel 5 %)
    assert jumps(0.0, 0.0) == []
    rules = FindingsConfig(jump_level_rel=0.0)       # the level rule off: span, res, err
    assert len(jumps(0.0, 0.0)) == 4                # old files: relative to the span only
    assert jumps(10e-9, 0.0) == []                  # 5 nm below a 10 nm resolution
    assert jumps(1e-9, 3e-9) == []                  # 5 nm below 3 + 3 nm batch-means error
    assert len(jumps(1e-9, 1e-9)) == 4              # 5 nm above both: jumps


def test_a_few_percent_of_the_level_is_no_jump():
    """The FVA model's full sweep: neighbouring points whose qmax goes from 8.17 to 8.32 um
    (1.8 %) over a run spanning 8.1-8.8 um passed the span, resolution and error tests and
    read as 21 "jumps"; under jump_level_rel (5 %) of the level they are none, while a step
    from 8.2 to 9.0 um (9 %) still is."""
    q = np.full(20, 8.2e-6)
    q[[0, 19]] = 8.8e-6                            # the span: 0.6 um
    q[[5, 14]] = 8.35e-6                           # up and down at 600 rpm: +0.15 um (1.8 %)
    arrays = {**_sweep(np.ones(10), np.ones(10)), "qmax": q,
              "qmax_res": np.full(20, 2e-9), "qmax_err": np.full(20, 20e-9)}

    def jumps(a):
        f = derive_findings({"sweep.npz": a}, {"sweep": {"monitored": "G1"}}, FindingsConfig())
        return [e for e in f["events"] if e["kind"] == "jump" and 500 < e["at"] < 700]

    assert jumps(arrays) == []
    arrays["qmax"] = q.copy()
    arrays["qmax"][[5, 14]] = 9.0e-6               # +0.8 um (9 %): a jump onto and off it
    assert len(jumps(arrays)) == 4


def test_no_response_over_speed_gives_no_verdict(tmp_path):
    f = derive_findings({}, {"modes": {"status": "ok"}}, FindingsConfig())
    assert f["verdict"].startswith("No speed verdict") and not f["bands"]
    assert plot_band_chart(f, tmp_path / "f.png") is None
    assert console_lines(f, quiet=True) == [f["verdict"]]


def test_partial_run_says_partial():
    arrays = _sweep(np.ones(10), np.ones(10))
    f = derive_findings({"sweep.npz": arrays}, {"sweep": {"status": "partial",
                                                          "message": "3 points failed"}},
                        FindingsConfig())
    assert "Partial results: sweep: partial (3 points failed)" in f["verdict"]


def test_console_is_short_and_chart_draws(tmp_path):
    cf = np.where(np.arange(10) % 2 == 0, 0.9, 1.0)
    cls = np.tile([1, 2, 3, 4], 5)
    arrays = _sweep(cf, cf, cf < 1, cf < 1, cls=cls)
    f = derive_findings({"sweep.npz": arrays}, {}, FindingsConfig())
    lines = console_lines(f, "out/x/report.html")
    assert len(lines) <= 10 and lines[-1] == "open out/x/report.html"
    assert lines[0].startswith("findings: ") and "Avoid" in lines[0]
    assert plot_band_chart(f, tmp_path / "f.png").stat().st_size > 1000


def test_findings_section_errors_name_the_field():
    with pytest.raises(ConfigError, match="rattle"):
        build(FindingsConfig, {"rattle": "never"})
    with pytest.raises(ConfigError, match="loss_share_avoid"):
        build(FindingsConfig, {"loss_share_avoid": 1.5})
    with pytest.raises(ConfigError, match="kv_caution"):
        build(FindingsConfig, {"kv_caution": 0.9})


def test_map_bands_per_load():
    """A map of 2 loads x 5 speeds, up only: at 10 N m the mesh loses contact at 300-400
    rpm, at 50 N m nowhere; the band names its load and recomputes from map.npz[:, j, :]."""
    rpm = np.array([100.0, 200.0, 300.0, 400.0, 500.0])
    cf = np.ones((1, 2, 5))
    cf[0, 0, 2:4] = 0.8
    arrays = {"rpm": rpm, "torque": np.array([10.0, 50.0]), "direction": np.array(["up"]),
              "ok": np.ones((1, 2, 5), bool), "contact_fraction_G1": cf,
              "impacts_drive_G1": np.zeros((1, 2, 5)), "impacts_back_G1": np.zeros((1, 2, 5))}
    f = derive_findings({"map.npz": arrays}, {}, FindingsConfig())
    loss = [b for b in f["bands"] if b["quantity"] == "contact loss"]
    assert [(b["where"], b["from"], b["to"], b["load_index"]) for b in loss] == \
        [("G1 at 10 N m", 300.0, 400.0, 0)]
    j = loss[0]["load_index"]
    held = rpm[(arrays[loss[0]["metric"]][0, j] < loss[0]["threshold"])]
    assert set(held) == {300.0, 400.0}


def test_runup_bands_merge_close_periods():
    """A run-up over 1000 mesh periods from 100 to 1099 rpm with losses in periods 200-210
    and 230-240 (one band, 20 periods apart) and 700 (another band)."""
    rpm = 100.0 + np.arange(1000)
    losses = np.zeros(1000)
    losses[200:211] = 1
    losses[230:241] = 2
    losses[700] = 1
    arrays = {"runs": np.array(["up"]), "meshes": np.array(["G2"]), "up_rpm": rpm,
              "up_losses_G2": losses}
    f = derive_findings({"runup.npz": arrays}, {}, FindingsConfig())
    got = [(b["where"], b["from"], b["to"], b["points"]) for b in f["bands"]]
    assert got == [("G2", 300.0, 340.0, 22), ("G2", 800.0, 800.0, 1)]
    assert all(b["edge_err"] == 1.0 and b["direction"] == "up" for b in f["bands"])


def test_coexisting_states_band_and_events():
    """A census with one attractor at 100 and 300 rpm and two at 200 rpm (a quiet period-1
    seen by the sweep, a rattling chaotic state off its path): one band at 200 rpm, two
    events there with their basins."""
    arrays = {"attractor_param": np.array([100.0, 200.0, 200.0, 300.0]),
              "attractor_class": np.array([1, 1, 3, 1]),
              "attractor_class_legend": np.array(["failed", "periodic", "quasi-periodic",
                                                  "chaotic", "not settled", "aperiodic"]),
              "attractor_period_n": np.array([1, 1, 0, 1]),
              "basin_fraction": np.array([1.0, 0.75, 0.25, 1.0]),
              "basin_ci_lo": np.array([0.9, 0.5, 0.1, 0.9]),
              "basin_ci_hi": np.array([1.0, 0.9, 0.5, 1.0]),
              "attractor_seen_by_sweep": np.array([1, 1, 0, 1]),
              "attractor_impacts_G1": np.array([0.0, 0.0, 0.4, 0.0])}
    f = derive_findings({"states.npz": arrays}, {}, FindingsConfig())
    band, = [b for b in f["bands"] if b["quantity"] == "coexisting states"]
    assert (band["from"], band["to"], band["severity"]) == (200.0, 200.0, "caution")
    events = [e for e in f["events"] if e["kind"] == "coexisting"]
    assert [e["at"] for e in events] == [200.0, 200.0]
    rattle = [e for e in events if e["where"] == "chaotic"][0]
    assert "G1 0.40 impacts per period" in rattle["evidence"]
    assert "25 % of the disturbances" in rattle["evidence"]
    assert "not on the sweep's path" in rattle["evidence"]


def test_branch_events_state_the_stability_on_each_side():
    """A period-1 branch stable up to a fold at 200 rpm, unstable after it, with a fold at
    300 rpm where it turns stable again, and an NS inside the unstable part."""
    arrays = {"param": np.array([100.0, 150.0, 200.0, 180.0, 250.0, 300.0, 350.0]),
              "stable": np.array([True, True, True, False, False, False, True]),
              "label": np.array(["", "", "LP", "", "NS", "LP", ""]),
              "branch": np.zeros(7, int), "n_periods": np.ones(7, int),
              "qmax": np.full(7, 1e-5)}
    f = derive_findings({"branch.npz": arrays}, {}, FindingsConfig())
    ev = {(e["kind"], e["at"]): e for e in f["events"]}
    assert ev[("LP", 200.0)]["stability"] == "stable → unstable"
    assert "jumps" in ev[("LP", 200.0)]["evidence"]
    assert ev[("NS", 250.0)]["stability"] == "unstable → unstable"
    assert ev[("LP", 300.0)]["stability"] == "unstable → stable"


def test_chaotic_evidence_in_physical_units_and_multi_frequency_band():
    """A chaotic band quotes the exponent's lower bound in 1/s and per excitation period with
    its noise floor (no 'per time unit'); a multi-frequency forced band is 'fine' and
    recomputes from motion_class == 6."""
    cls = np.array([3, 3, 6, 6] + [1] * 6 + [1] * 6 + [6, 6, 3, 3])
    arrays = _sweep(np.ones(10), np.ones(10), cls=cls)
    arrays["lyapunov_ci"] = np.tile([0.05, 0.07], (20, 1))
    arrays["lyapunov_lo_per_s"] = np.full(20, 314.0)
    arrays["lyapunov_lo_per_period"] = np.full(20, 0.8)
    arrays["lyapunov_floor_per_period"] = np.full(20, 0.2)
    f = derive_findings({"sweep.npz": arrays}, {"sweep": {"monitored": "G1"}},
                        FindingsConfig())
    chaos = [b for b in f["bands"] if b["quantity"] == "chaotic motion"]
    assert [(b["from"], b["to"], b["direction"]) for b in chaos] == [(100.0, 200.0, "both")]
    text = chaos[0]["evidence"]
    assert "314 1/s" in text and "0.80 per excitation period" in text and "floor 0.20" in text
    assert "time unit" not in text
    multi = [b for b in f["bands"] if b["quantity"] == "multi-frequency forced motion"]
    assert [(b["from"], b["to"], b["severity"], b["metric"], b["threshold"]) for b in multi] == \
        [(300.0, 400.0, "fine", "motion_class", 6)]
    assert check_bands_recompute(arrays, f) >= 2


def test_summary_jumps_honour_resolution_and_errors():
    """summary.json's jumps_up / jumps_down (analyses/sweep/sweep.py) follow the same rule as the
    findings' jump events: 5 nm steps on a 5 nm span are jumps only above the resolution
    and the batch-means errors."""
    from vibrogear.analyses.sweep.sweep import jumps

    p = np.arange(5) * 100.0
    q = np.array([1.49, 1.49, 1.495, 1.495, 1.49]) * 1e-6
    assert jumps(p, q) == []                        # 0.3 % of the level: no jump
    assert jumps(p, q, level=0.0) == [150.0, 350.0]
    assert jumps(p, q, res=np.full(5, 1e-8), level=0.0) == []
    assert jumps(p, q, res=np.full(5, 1e-9), err=np.full(5, 3e-9), level=0.0) == []
    assert jumps(p, q, res=np.full(5, 1e-9), err=np.full(5, np.nan), level=0.0) == \
        [150.0, 350.0]


def test_band_margins_are_written_largest_first_and_never_over_one_another():
    """Ten short bands 10 rpm apart on one row, each with its margin: the labels (each about
    40 rpm wide at this scale) would overlap; the largest margin is written, and no two
    written labels share a pixel.  Another row's label at the same speed is kept."""
    from vibrogear.report.figure import new_figure
    from vibrogear.report.writers.findings import _place_margins

    fig = new_figure(figsize=(10, 3))
    ax = fig.add_subplot(111)
    ax.set_xlim(1500, 3000)
    ax.set_ylim(-1, 2)
    margins = [(0.01 * k, 0, 2000 + 10 * k, f"+{k}.0 %") for k in range(10)]
    margins.append((0.05, 1, 2000, "+5.0 %"))
    _place_margins(fig, ax, margins)
    r = fig.canvas.get_renderer()
    texts = [(t.get_text(), t.get_position()[1], t.get_window_extent(r)) for t in ax.texts]
    row0 = [(s, box) for s, y, box in texts if y == 0]
    assert "+9.0 %" in [s for s, _ in row0] and len(row0) < 10
    assert all(not a.overlaps(b) for i, (_, a) in enumerate(row0) for _, b in row0[i + 1:])
    assert [s for s, y, _ in texts if y == 1] == ["+5.0 %"]
