"""What the figures show: one panel per mesh, motion rows per direction, special-point
names that do not overprint, legends that list only what is drawn, plain titles, physical
colour-bar references, resonance speeds (report/*_plots.py)."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from vibrogear.report.plots.branch import branch_legend, draw_branches, label_special_points
from vibrogear.report.figure import mode_count_note, new_figure, plain_title, save_figure


def _branches():
    """A period-1 branch, unstable everywhere, with special points bunched as in the
    two-stage gearbox (folds and a PD within a few rpm of each other) and one far off."""
    p = np.linspace(3000.0, 1500.0, 61)
    q = 8.0 + 6.0 * np.exp(-((p - 1870.0) / 80.0) ** 2)
    label = np.full(p.size, "", dtype="<U2")
    stable = np.zeros(p.size, bool)
    at = {"LP": [1856.0, 1862.0], "PD": [1859.0, 1945.0], "NS": [1864.0, 2400.0]}
    xs, ys, labs = list(p), list(q), list(label)
    for lab, where in at.items():
        for x in where:
            xs.append(x)
            ys.append(8.0 + 6.0 * np.exp(-((x - 1870.0) / 80.0) ** 2))
            labs.append(lab)
    n = len(xs)
    return {"param": np.array(xs), "qmax": np.array(ys), "qmin": np.array(ys) - 10.0,
            "label": np.array(labs), "stable": np.zeros(n, bool), "branch": np.zeros(n, int),
            "n_periods": np.ones(n, int)}


def _boxes(fig, texts):
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    return [t.get_window_extent(r) for t in texts]


def test_special_point_names_do_not_overlap():
    arrays = _branches()
    fig = new_figure((8.0, 5.0))
    ax = fig.add_subplot(111)
    draw_branches(ax, arrays, "qmax")
    ax.set_xlim(1480.0, 3020.0)
    fig.tight_layout()
    texts = label_special_points(ax, arrays, "qmax")
    boxes = _boxes(fig, texts)
    for a, b in itertools.combinations(boxes, 2):
        assert not a.overlaps(b), (a, b)
    words = " ".join(t.get_text() for t in texts)
    # every special point is named, with its speed
    for lab, x in (("LP", "1856"), ("LP", "1862"), ("PD", "1859"), ("PD", "1945"),
                   ("NS", "1864"), ("NS", "2400")):
        assert lab in words and x in words, (lab, x, words)


def test_branch_legend_lists_only_what_is_drawn():
    arrays = _branches()                       # unstable everywhere, period 1
    labels = [h.get_label() for h in branch_legend(arrays)]
    assert "period-1 branch unstable" in labels
    assert not any("stable" in s and "unstable" not in s for s in labels)
    assert not any("period-2" in s for s in labels)
    assert {"LP", "PD", "NS"} <= set(labels) and "BP" not in labels


def test_branch_figure_legend_has_no_stable_entry(tmp_path):
    from vibrogear.report.plots.branch import plot_branches

    arrays = _branches()
    svg = save_figure(plot_branches(arrays, title="two_stage: m = 146 (21+25+100)"),
                      tmp_path / "branch_max", formats=("svg",))[0].read_text()
    assert "period-1 branch unstable" in svg
    assert "period-1 stable" not in svg and "branch stable" not in svg
    assert "m = 146" not in svg


def test_titles_lose_the_mode_count_and_the_caption_gets_it():
    t = "two_stage: m = 146 (21+25+100)"
    assert plain_title(t) == "two_stage"
    assert plain_title(t + "\nbackbone") == "two_stage\nbackbone"
    assert plain_title("impact pair: zeta=0.05") == "impact pair: zeta=0.05"
    assert "m = 146" in mode_count_note(t) and "21 + 25 + 100" in mode_count_note(t)
    assert mode_count_note("impact pair: zeta=0.05") == ""


def _sweep(n=8):
    """Two meshes: G1 in contact throughout, G2 rattling (back-flank impacts)."""
    p = np.tile(np.linspace(1500.0, 3000.0, n), 2)
    d = np.array(["up"] * n + ["down"] * n)
    z = np.zeros(2 * n)
    return {"param": p, "direction": d, "qmin": 1.0 + z, "qmax": 5.0 + z,
            "poincare": np.full((2 * n, 4), 3.0), "period_n": np.zeros(2 * n, int),
            "status": np.zeros(2 * n, int), "motion_class": np.full(2 * n, 3),
            "motion_class_G1": np.ones(2 * n, int), "period_n_G1": np.ones(2 * n, int),
            "motion_class_G2": np.full(2 * n, 3), "period_n_G2": np.zeros(2 * n, int),
            "motion_class_bearing:A": np.ones(2 * n, int),
            "period_n_bearing:A": np.ones(2 * n, int),
            "impacts_drive_G1": z, "impacts_back_G1": z, "contact_fraction_G1": 1.0 + z,
            "rattle_G1": z, "impacts_drive_G2": 0.2 + z, "impacts_back_G2": 0.4 + z,
            "contact_fraction_G2": 0.1 + z, "rattle_G2": 1e-3 + z}


def test_bifurcation_has_a_panel_per_mesh_and_rows_per_direction(tmp_path):
    from vibrogear.report.plots.sweep import plot_bifurcation

    svg = save_figure(plot_bifurcation(_sweep(), title="two_stage: m = 146 (21+25+100)"),
                      tmp_path / "b", formats=("svg",))[0].read_text()
    assert "G1: impacts" in svg and "G2: impacts" in svg       # both meshes, G2 rattles
    assert "out of contact" in svg and "back-flank impacts" in svg
    assert "G1 up" not in svg and "bearing:A up" not in svg    # rows per direction only
    assert "Poincare" in svg and "m = 146" not in svg
    asked = save_figure(plot_bifurcation(_sweep(), per_contact_rows=True), tmp_path / "c",
                        formats=("svg",))[0].read_text()
    for row in ("G1 up", "G1 down", "bearing:A down"):         # differ from the whole
        assert row in asked
    assert "G2 up" not in asked                                # same class as the whole


def test_waterfall_levels_in_physical_references():
    from vibrogear.report.plots.nvh import levels_db

    lev, ref = levels_db([1e-6, 1e-5, 3.16227766e-8], "m")         # amplitudes: 20 log10
    assert ref == "1 \u00b5m" and lev == pytest.approx([0.0, 20.0, -30.0], abs=1e-6)
    lev, ref = levels_db([10.0], "N")
    assert ref == "1 N" and lev == pytest.approx([20.0])
    lev, ref = levels_db([1e-12, 1e-9], "W", power=True)          # powers: 10 log10
    assert ref == "1 pW" and lev == pytest.approx([0.0, 30.0])


def test_waterfall_marks_identified_lines_and_states_the_unidentified_share(tmp_path):
    from vibrogear.report.plots.nvh import plot_waterfall, unidentified_note

    kinds = np.array(["mesh", "unidentified", "unidentified", "shaft"])
    amps = np.array([4.0, 2.0, np.sqrt(5.0), 0.0])
    note = unidentified_note((np.ones(4), np.ones(4), kinds, amps))
    assert "36 %" in note and "2 of 4" in note                    # (4 + 5) / 25
    alt = np.array(["", "G1 mesh 1x; mode 3", "", ""])
    note = unidentified_note((np.ones(4), np.ones(4), kinds, amps, alt))
    assert "44 % of that with candidate" in note                  # 4 / 9
    rpm = np.array([1000.0, 2000.0])
    order = np.arange(0, 64) / 8.0
    freq = np.outer(rpm / 60.0 * 40, order)
    amp = np.full((2, order.size), 1e-7)
    amp[:, 8] = 2e-6
    fig = plot_waterfall(rpm, freq, amp, label="DTE", unit="m",
                         max_hz=5000.0, mesh_hz=np.outer(rpm, [40 / 60.0]),
                         shaft_hz=np.outer(rpm, [1 / 60.0]), max_order=3,
                         title="two_stage: m = 146 (21+25+100)",
                         lines=(np.array([667.0, 900.0]), rpm, np.array(["mesh", "unidentified"]),
                                np.array([2e-6, 1e-6])),
                         unstable=np.array([True, False]))
    path = save_figure(fig, tmp_path / "w.png", formats=("png",))[0]
    assert path.stat().st_size > 10_000


def test_resonance_map_draws_every_mesh_and_its_resonance_speeds(tmp_path):
    from vibrogear.config.scene import load_scene
    from vibrogear.analyses.gearbox_modes import mesh_orders_per_rpm, resonance_crossings
    from vibrogear.report.plots.gearbox import plot_resonance_map
    from pathlib import Path

    gb = load_scene(Path(__file__).resolve().parents[2] / "configs/two_stage.toml").gearbox
    orders = dict(mesh_orders_per_rpm(gb))
    # G1: z1 (40 teeth) on the driving shaft; G2: z3 (55 teeth), also on the driving shaft
    assert orders == pytest.approx({"G1": 40 / 60.0, "G2": 55 / 60.0})
    f = np.array([1000.0, 2000.0, 2500.0])
    mesh = np.array([[0.3, 0.0, 0.01], [0.0, 0.2, 0.01]])          # mode 2 has no share
    cross = resonance_crossings(f, mesh.max(axis=0), list(orders.items()), 1000.0, 3000.0)
    got = {(c["mesh"], c["mesh_order"], round(c["rpm"], 6)) for c in cross}
    # rpm = 60 f / (h z): modes 0 and 1 (share > 5 %) with each mesh's 1x and 2x, in range
    want = {("G1", 1, 1500.0), ("G2", 1, round(1000 * 60 / 55, 6)),          # mode 0
            ("G1", 1, 3000.0), ("G1", 2, 1500.0), ("G2", 1, round(2000 * 60 / 55, 6)),
            ("G2", 2, round(2000 * 60 / 110, 6))}                            # mode 1
    assert got == want
    svg = save_figure(plot_resonance_map(f, mesh, 40, 1000.0, 3000.0,
                                         orders=list(orders.items()), crossings=cross,
                                         title="two_stage: m = 146 (21+25+100)"),
                      tmp_path / "r", formats=("svg",))[0].read_text()
    assert "G2 1x mesh frequency" in svg and "G1 2x mesh frequency" in svg
    assert "1500 rpm" in svg and "2182 rpm" in svg and "m = 146" not in svg


def test_captions_say_what_to_look_at_and_carry_the_mode_count():
    from vibrogear.report.page.captions import CAPTIONS, caption

    for name in ("bifurcation.png", "fig2.png", "branch_max.png", "resonance_map.png",
                 "nvh_waterfall_dte.png", "erp.png", "gearbox.png", "time_response.png"):
        assert len(CAPTIONS[name].split()) >= 10, name
    t = "two_stage: m = 146 (21+25+100)"
    assert caption("out/two_stage/map_rattle_G2.png", t).startswith("Impact energy")
    assert "m = 146" in caption("out/two_stage/bifurcation.png", t)
    assert "m = " not in caption("bifurcation.png", "impact pair: zeta=0.05")
    assert caption("unknown.png") == ""


def _branch_result(stable):
    from types import SimpleNamespace

    P, K = 4, 33
    rpm = np.linspace(1500.0, 3000.0, P)
    order = np.arange(K) / 8.0
    amp = np.full((P, 1, K), 1e-7)
    b = SimpleNamespace(rpm=rpm, branch=np.zeros(P, int), index=np.arange(P),
                        stable=np.asarray(stable, bool), n_periods=np.ones(P, int),
                        closure=np.zeros(P), first_pass=np.ones(P, bool), order=order,
                        freq_hz=np.outer(rpm * 40 / 60.0, order), amplitudes={"dte": amp},
                        parseval={"dte": 0.0}, erp_per_bin=None)
    r = SimpleNamespace(branch=b, channels={"dte": ["G1"]}, mesh_hz=np.outer(rpm, [40 / 60.0]),
                        shaft_hz=np.outer(rpm, [1 / 60.0]), rpm=rpm, shaft_names=("driving",),
                        units={"dte": "m"})
    return SimpleNamespace(nvh=SimpleNamespace(max_order=3.0)), r


def test_branch_waterfall_not_drawn_for_an_orbit_unstable_everywhere(tmp_path):
    from vibrogear.report.writers.nvh import write_branch

    scene, r = _branch_result([False] * 4)
    files = write_branch(scene, r, tmp_path, 3000.0, "two_stage")
    assert "waterfall_branch_dte" not in files and (tmp_path / "spectra_branch.npz").exists()
    assert not (tmp_path / "nvh_waterfall_branch_dte.png").exists()
    scene, r = _branch_result([True, True, False, False])
    files = write_branch(scene, r, tmp_path, 3000.0, "two_stage")
    assert (tmp_path / "nvh_waterfall_branch_dte.png").stat().st_size > 10_000
