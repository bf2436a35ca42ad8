"""The ``report`` analysis (work-precision against the exact impact-pair solution) through the CLI."""
import csv
import json
import math

import numpy as np
import pytest

from vibrogear.cli import main

SCENE = "configs/impact_pair.toml"


@pytest.fixture(scope="module")
def report_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    rc = main(["run", SCENE, "--quiet", "--out", str(out),
               "--set", 'scene.analyses=["report"]',
               "--set", "report.rtols=[1e-4, 1e-6, 1e-8]",
               "--set", "report.shooting_tols=[1e-4, 1e-8]",
               "--set", "report.periods=6",
               "--set", "report.repeats=1"])
    assert rc == 0
    return out


def _csv(path):
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def test_files_written(report_dir):
    for name in ("work_precision.csv", "shooting_precision.csv", "summary.json",
                 "work_precision.png", "work_precision.svg",
                 "shooting_precision.png", "shooting_precision.svg"):
        assert (report_dir / name).stat().st_size > 0, name


def test_work_precision_numbers(report_dir):
    wp = _csv(report_dir / "work_precision.csv")
    assert np.all(np.isfinite(np.column_stack(list(wp.values()))))
    assert list(wp["rtol"]) == [1e-4, 1e-6, 1e-8]
    assert np.all(np.diff(wp["error"]) < 0)          # tighter rtol, smaller error
    assert np.all(np.diff(wp["steps"]) > 0)
    assert np.all(wp["events"] > 0)                  # the orbit does switch
    # tolerance proportionality within a factor 30 of rtol
    assert np.all(wp["error"] < 30 * wp["rtol"]) and np.all(wp["error"] > wp["rtol"] / 30)


def test_summary_slopes_and_no_nan(report_dir):
    summary = json.loads((report_dir / "summary.json").read_text())
    assert summary["status"] == "ok"
    rep = summary["results"]["report"]
    assert 3.5 <= rep["slopes"]["order"] <= 6.5
    assert 0.7 <= rep["slopes"]["error_vs_rtol"] <= 1.3
    assert rep["errors_decrease"] is True

    def walk(x):
        if isinstance(x, dict):
            for v in x.values():
                walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)
        else:
            assert x is not None and not (isinstance(x, float) and not math.isfinite(x))

    walk(rep)


def test_shooting_precision(report_dir):
    sh = _csv(report_dir / "shooting_precision.csv")
    assert np.all(np.isfinite(np.column_stack(list(sh.values()))))
    assert np.all(sh["converged"] == 1)
    assert np.all(sh["residual"] < sh["tol"])
    # the orbit error follows the tolerance (the integrator rtol is matched to it)
    assert sh["u0_error"][-1] < 1e-3 * sh["u0_error"][0]
    assert np.all(sh["u0_error"] < 30 * sh["tol"])
    assert np.all(sh["floquet_error"] < 30 * sh["tol"])


def test_report_subcommand_same_analysis(tmp_path):
    """``vibrogear report`` runs only the report analysis."""
    rc = main(["report", SCENE, "--quiet", "--out", str(tmp_path),
               "--set", "report.rtols=[1e-5, 1e-7]", "--set", "report.shooting_tols=[1e-6, 1e-9]",
               "--set", "report.periods=3", "--set", "report.repeats=1"])
    assert rc == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["analyses"] == ["report"]
    assert summary["results"]["report"]["work_precision"]["rtol"] == [1e-5, 1e-7]
