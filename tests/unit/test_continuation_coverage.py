"""A continuation whose branches stop on the method (a step below ds_min, the point limit)
before the end of the range says ``partial``, with the covered share of the range; one whose
branches end by themselves says ``ok`` (analyses/continuation.py, :func:`coverage`)."""
from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from vibrogear.analyses.continuation import coverage
from vibrogear.cli import main
from vibrogear.status import Status

ROOT = Path(__file__).resolve().parents[2]


def _branch(params, status, n=1):
    return SimpleNamespace(points=tuple(SimpleNamespace(param=p) for p in params),
                           status=status, n_periods=n)


def test_coverage_by_hand():
    # range 1000-3000: [1600, 3000] and [1200, 1500] (1700 of 2000), the period-2 branch
    # inside the first, a from-sweep half reaching below the range (clipped)
    br = [_branch([3000, 2400, 1600], Status.DS_TOO_SMALL),
          _branch([1800, 1900], Status.REJOINED, 2),
          _branch([1500, 1200], Status.LEFT_RANGE),
          _branch([], Status.NO_START)]
    c = coverage(br, 1000.0, 3000.0)
    assert c["intervals"] == [[1200.0, 1500.0], [1600.0, 3000.0]]
    assert c["fraction"] == pytest.approx(1700 / 2000)
    assert c["ended_early"] == [
        {"branch": 0, "n_periods": 1, "status": "ds_too_small", "ended_at": 1600.0},
        {"branch": 3, "n_periods": 1, "status": "no_start", "ended_at": None}]
    done = coverage([_branch([3000, 1000], Status.LEFT_RANGE),
                     _branch([1000.0 - 1e-9, 900], Status.LEFT_RANGE)], 1000.0, 3000.0)
    assert done["fraction"] == 1.0 and done["ended_early"] == []


def _continue(tmp_path, *overrides):
    out = tmp_path / "out"
    args = ["continue", str(ROOT / "configs" / "impact_pair.toml"), "--quiet", "--out", str(out)]
    for o in overrides:
        args += ["--set", o]
    assert main(args) == 0
    s = json.loads((out / "summary.json").read_text())["results"]["continuation"]
    with np.load(out / "branch.npz") as z:
        return s, z["param"].copy(), z["branch"].copy()


def test_branch_stopped_on_ds_min_is_partial(tmp_path):
    """The impact pair from Omega = 3 down with steps held at 0.05 and two corrector
    iterations: the branch cannot turn at the primary resonance's fold and stops on ds_min
    there.  The covered share is recomputed from branch.npz: (3 - lowest Omega) / 2.9."""
    s, param, _ = _continue(tmp_path, "continuation.ds=0.05", "continuation.ds_min=0.05",
                            "continuation.max_corrector_iter=2")
    assert [b["status"] for b in s["branches"]] == ["ds_too_small"]
    assert s["status"] == "partial"
    cov = s["coverage"]
    assert cov["fraction"] == pytest.approx((3.0 - param.min()) / 2.9, rel=1e-12)
    assert 0.5 < cov["fraction"] < 0.95
    assert cov["ended_early"][0]["ended_at"] == pytest.approx(param.min(), rel=1e-12)
    assert s["message"].startswith("1 of 1 branches stopped before the end of the range "
                                   "(ds_too_small at Omega = ")
    assert f"cover {100 * cov['fraction']:.0f} % of Omega = 0.1-3;" in s["message"]
