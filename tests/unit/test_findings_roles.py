"""Meshes judged by their role (issue 40): a loaded mesh by its dynamic factor kv and its
contact-loss share, an idle mesh by its rattle level in dB; the verdict's windows (where to
run); ``states`` alone judges its attractors' impacts; ``vibrogear compare``.  Hand-made
arrays whose bands are known from the documented rules (docs/findings.md)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from vibrogear.analyses.findings.compare import compare_findings, read_findings
from vibrogear.analyses.findings.findings import derive_findings, windows
from vibrogear.analyses.findings.iso_resonance import iso_resonances
from vibrogear.analyses.mesh_loads import level_db, mesh_judgement_arrays
from vibrogear.config.base import build
from vibrogear.config.sections.findings import FindingsConfig
from vibrogear.report.writers.compare import compare_lines, write_compare_html

from test_findings import check_bands_recompute

GRID = np.arange(1, 11) * 100.0          # 100 ... 1000 rpm


def _sweep(**per_mesh) -> dict:
    """Up and down on GRID with the same values both ways; ``per_mesh``: name -> (10,)."""
    n = GRID.size
    out = {"param": np.concatenate([GRID, GRID[::-1]]),
           "direction": np.array(["up"] * n + ["down"] * n), "ok": np.ones(2 * n, bool),
           "qmin": np.zeros(2 * n), "qmax": np.full(2 * n, 1e-5),
           "period_n": np.ones(2 * n, int)}
    for k, v in per_mesh.items():
        v = np.asarray(v, float)
        out[k] = np.concatenate([v, v[::-1]])
    return out


def _loaded_idle(kv, cf1, db2, back2=None):
    return _sweep(kv_G1=kv, contact_fraction_G1=cf1, impacts_back_G1=np.zeros(10),
                  impacts_drive_G1=np.zeros(10), contact_fraction_G2=np.full(10, 0.5),
                  impacts_back_G2=np.ones(10) if back2 is None else back2,
                  impacts_drive_G2=np.ones(10), rattle_db_G2=db2)


LOAD_PATH = {"meshes": [{"name": "G1", "role": "loaded", "normal_force_N": 1600.0},
                        {"name": "G2", "role": "idle", "normal_force_N": 12.0}]}


def test_loaded_mesh_by_kv_and_loss_share_idle_mesh_by_rattle_level():
    """G1: kv 1.5 at 400-500 rpm (caution, 15 % past 1.3), out of contact 0.5 % of the time
    at 600 rpm (below the 1 % share: no avoid) and 3 % at 900 rpm (avoid).  G2 (idle,
    out of contact half the time everywhere): levels 100 dB ... 110 dB at 800 rpm; caution
    above 104 dB, never avoid without a limit; its quietest speeds named."""
    kv = np.full(10, 1.1)
    kv[3:5] = 1.5
    cf = np.ones(10)
    cf[5] = 0.995
    cf[8] = 0.97
    db = np.array([100.0, 101, 102, 103, 105, 106, 107, 110, 104.5, 100.5])
    arrays = _loaded_idle(kv, cf, db)
    f = derive_findings({"sweep.npz": arrays}, {}, FindingsConfig(), load_path=LOAD_PATH)
    got = {(b["quantity"], b["where"], b["from"], b["to"], b["severity"])
           for b in f["bands"]}
    assert ("dynamic factor", "G1", 400.0, 500.0, "caution") in got
    assert ("contact loss", "G1", 900.0, 900.0, "avoid") in got
    assert not any(q == "contact loss" and w == "G2" for q, w, *_ in got)   # idle: no loss band
    assert ("rattle", "G2", 500.0, 900.0, "caution") in got                   # > 104 dB
    assert ("quietest rattle", "G2", 100.0, 400.0, "fine") in got             # <= 103 dB
    assert ("quietest rattle", "G2", 1000.0, 1000.0, "fine") in got
    assert not any(s == "avoid" and w == "G2" for *_, w, _a, _b, s in
                   [(q, w, a, b, s) for q, w, a, b, s in got])
    kvb, = [b for b in f["bands"] if b["quantity"] == "dynamic factor"]
    assert kvb["margin"] == pytest.approx(1.5 / 1.3 - 1)
    rb, = [b for b in f["bands"] if b["quantity"] == "rattle"]
    assert rb["margin"] == pytest.approx(110 - 104) and rb["margin_unit"] == "dB"
    assert check_bands_recompute(arrays, f) >= 5
    assert [(m["name"], m["role"], m["static_force_N"]) for m in f["meshes"]] == \
        [("G1", "loaded", 1600.0), ("G2", "idle", 12.0)]
    assert f["meshes"][0]["kv_peak"] == 1.5 and f["meshes"][1]["rattle_db_max"] == 110.0
    # the verdict: fine at 100-300 rpm (no G1 band, G2 below 104 dB), then avoid / caution
    assert f["verdict"].startswith("Run at 100–300, 1000 rpm: no band to avoid or watch")
    assert "G2 rattles least at 100–400, 1000 rpm" in f["verdict"]
    # a limit makes the loud speeds "avoid"
    limited = derive_findings({"sweep.npz": arrays}, {},
                              build(FindingsConfig, {"rattle_limit_db": 106.5}),
                              load_path=LOAD_PATH)
    above, = [b for b in limited["bands"] if b["quantity"] == "rattle above the limit"]
    assert (above["from"], above["to"], above["severity"]) == (700.0, 800.0, "avoid")


def test_least_severe_windows_when_no_speed_is_fine():
    """kv above 1.3 everywhere, by 1.35 at 100-300 and 2.0 elsewhere: no fine window;
    the least severe is 100-300 rpm, limited by G1's dynamic factor; no 'whole range'
    avoid, since nothing fails."""
    kv = np.full(10, 2.0)
    kv[:3] = 1.35
    arrays = _loaded_idle(kv, np.ones(10), np.zeros(10))
    f = derive_findings({"sweep.npz": arrays}, {}, FindingsConfig(), load_path=LOAD_PATH)
    # two kv bands can't be told apart by the same limit set: one window, margin the worst
    assert f["windows"][0]["status"] == "caution"
    assert f["windows"][0]["limits"] == ["G1 dynamic factor"]
    assert f["verdict"].startswith("No speed is free of findings; least severe: 100–1000 rpm "
                                   "(limited by G1 dynamic factor")
    # a loaded mesh losing contact over the whole range: nothing left to run at
    lost = _loaded_idle(np.full(10, 2.5), np.full(10, 0.8), np.zeros(10))
    g = derive_findings({"sweep.npz": lost}, {}, FindingsConfig(), load_path=LOAD_PATH)
    assert g["windows"] == []
    assert g["verdict"].startswith("No speed to run at: the whole range 100–1000 rpm")


def test_windows_split_where_the_limits_change():
    bands = [{"severity": "caution", "from": 100.0, "to": 500.0, "quantity": "dynamic factor",
              "where": "G1", "margin": 0.5},
             {"severity": "caution", "from": 400.0, "to": 1000.0, "quantity": "rattle",
              "where": "G2", "margin": 1.0}]
    w = windows(bands, GRID)
    assert [(x["from"], x["to"], x["limits"]) for x in w] == \
        [(100.0, 300.0, ["G1 dynamic factor"]), (600.0, 1000.0, ["G2 rattle"]),
         (400.0, 500.0, ["G1 dynamic factor", "G2 rattle"])]


def test_states_alone_reports_the_impacts_of_its_states():
    """A states run without a sweep: at 5000 rpm the only state of the loaded G1 hits both
    flanks every mesh period (2 onsets, 2 J); at 5500 rpm one of two states does."""
    arrays = {"attractor_param": np.array([5000.0, 5500.0, 5500.0, 6000.0]),
              "attractor_class": np.array([1, 1, 1, 1]),
              "attractor_period_n": np.array([1, 1, 1, 1]),
              "attractor_impacts_G1": np.array([2.0, 0.0, 1.0, 0.0]),
              "attractor_rattle_G1": np.array([2.0, 0.0, 0.5, 0.0]),
              "attractor_kv_G1": np.array([2.6, 1.1, 1.8, 1.2])}
    f = derive_findings({"states.npz": arrays}, {}, FindingsConfig(),
                        load_path={"meshes": [{"name": "G1", "role": "loaded"}]})
    hits = [(b["quantity"], b["from"], b["to"], b["severity"]) for b in f["bands"]
            if b["quantity"] == "impacts in a state"]
    assert hits == [("impacts in a state", 5000.0, 5000.0, "avoid"),
                    ("impacts in a state", 5500.0, 5500.0, "caution")]
    kv = [(b["from"], b["to"], b["severity"]) for b in f["bands"]
          if b["quantity"] == "dynamic factor in a state"]
    assert kv == [(5000.0, 5500.0, "caution")]                 # max over the states > 1.3
    assert "No speed to avoid or watch" not in f["verdict"]
    assert f["verdict"].startswith("Run at 6000 rpm")
    assert "2000 mJ" in [b for b in f["bands"] if b["from"] == 5000.0][0]["evidence"]


def test_judgement_arrays_from_their_definitions():
    """kv = largest force / static force; 10 log10(P / 1 pW) with 0 dB for no impacts;
    an idle mesh with zero static force gets no kv."""
    metrics = {"max_force_G1": np.array([2000.0, 3000.0]),
               "rattle_power_G1": np.array([0.0, 1e-3]),
               "max_force_G2": np.array([5.0, 9.0])}
    out = mesh_judgement_arrays(metrics, {"G1": 1500.0, "G2": 0.0})
    assert out["kv_G1"] == pytest.approx([2000 / 1500, 2.0])
    assert out["rattle_db_G1"] == pytest.approx([0.0, 90.0])
    assert np.all(np.isnan(out["kv_G2"]))
    assert level_db(1.0) == pytest.approx(120.0)


def test_iso_resonance_speed_by_the_standard():
    """gear_pair's G1 (spur, z 40 / 80, m 2 mm, b 25 mm, bores 45 / 50 mm, steel 7850,
    3.5e8 N/m): n_E1 = 30 / (pi z1) sqrt(c b / m_red) from the pitch-diameter discs, by
    hand here."""
    from vibrogear.config import load_scene
    scene = load_scene("configs/gear_pair.toml")
    iso = iso_resonances(scene.gearbox)["meshes"][0]
    alpha = math.radians(20.0)
    J1 = 7850 * math.pi * 0.025 * (0.080 ** 4 - 0.045 ** 4) / 32
    J2 = 7850 * math.pi * 0.025 * (0.160 ** 4 - 0.050 ** 4) / 32
    rb1, rb2 = 0.040 * math.cos(alpha), 0.080 * math.cos(alpha)
    m_red = J1 * J2 / (J1 * rb2 ** 2 + J2 * rb1 ** 2)
    n = 30 / (math.pi * 40) * math.sqrt(3.5e8 / m_red)
    assert iso["m_red_kg"] == pytest.approx(m_red, rel=1e-9)
    assert iso["n_E1_rpm"] == pytest.approx(n, rel=1e-9)
    assert iso["main_range_rpm"] == pytest.approx([0.85 * n, 1.15 * n])


def _run(tmp_path, name, findings):
    d = tmp_path / name
    d.mkdir()
    (d / "summary.json").write_text(json.dumps({"scene": {"name": name},
                                                "findings": findings}))
    return d


def test_compare_lists_bands_added_removed_and_moved(tmp_path):
    """A: G1 contact loss 300-500 (avoid), chaos 800 rpm; B: the loss moved to 400-600, the
    chaos gone, a G2 rattle added; kv peak 2.1 -> 1.6."""
    def band(q, w, a, b, sev="avoid"):
        return {"quantity": q, "where": w, "from": a, "to": b, "severity": sev,
                "direction": "both", "edge_err": 50.0, "evidence": "e", "metric": "m",
                "op": ">", "threshold": 1.0, "margin": 0.2, "margin_unit": "relative"}
    A = {"verdict": "va", "bands": [band("contact loss", "G1", 300.0, 500.0),
                                     band("chaotic motion", "gearbox", 800.0, 800.0,
                                          "caution")],
         "meshes": [{"name": "G1", "role": "loaded", "kv_peak": 2.1}], "param_unit": "rpm"}
    B = {"verdict": "vb", "bands": [band("contact loss", "G1", 400.0, 600.0),
                                     band("rattle", "G2", 100.0, 200.0, "caution")],
         "meshes": [{"name": "G1", "role": "loaded", "kv_peak": 1.6}], "param_unit": "rpm"}
    c = compare_findings(read_findings(_run(tmp_path, "a", A)),
                         read_findings(_run(tmp_path, "b", B)))
    assert [b["quantity"] for b in c["bands"]["added"]] == ["rattle"]
    assert [b["quantity"] for b in c["bands"]["removed"]] == ["chaotic motion"]
    moved, = c["bands"]["moved"]
    assert (moved["from_change"], moved["to_change"]) == (100.0, 100.0)
    assert c["meshes"][0]["kv_peak"] == [2.1, 1.6]
    lines = compare_lines(c)
    assert lines[1] == "A: va" and lines[2] == "B: vb"
    assert any(line.startswith("  moved   avoid G1 contact loss: 300–500 rpm -> 400–600")
               for line in lines)
    assert "kv peak 2.10 -> 1.60 (-0.50)" in "\n".join(lines)
    page = write_compare_html(c, tmp_path / "b" / "compare.html").read_text()
    assert "Findings compared" in page and "removed" in page


def test_compare_refuses_a_folder_without_findings(tmp_path):
    from vibrogear.cli import main
    (tmp_path / "a").mkdir()
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "a")]) == 2


def test_an_idle_meshs_rattle_band_states_its_rattle_threshold_ratio_there():
    """The rattle band of G2 at 500-900 rpm quotes the ratio's values at those speeds only
    (5 ... 9, not the run's 1 ... 10); findings.meshes holds the run's range."""
    db = np.array([100.0, 101, 102, 103, 105, 106, 107, 110, 104.5, 100.5])
    arrays = _loaded_idle(np.full(10, 1.1), np.ones(10), db)
    arrays.update(_sweep(rattle_threshold_G2=np.arange(1.0, 11.0)))
    f = derive_findings({"sweep.npz": arrays}, {}, FindingsConfig(), load_path=LOAD_PATH)
    rb, = [b for b in f["bands"] if b["quantity"] == "rattle"]
    assert "inertia torque to follow the mesh is 5.0-9.0 x its drag torque there" in rb["evidence"]
    g2 = f["meshes"][1]
    assert (g2["rattle_threshold_min"], g2["rattle_threshold_max"]) == (1.0, 10.0)
    assert "rattle_threshold_max" not in f["meshes"][0]         # loaded: judged by kv
