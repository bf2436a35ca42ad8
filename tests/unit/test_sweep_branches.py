"""Windows of a sweep that branches start from (analyses/sweep/branches.py), on arrays
built by hand: runs of equal period per direction, the up and down sweep on one orbit
merged, coexisting orbits of the same period kept apart, failed points ending a run; a
branch's value at a parameter by linear interpolation, through a fold too."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from vibrogear.analyses.sweep.branches import branch_value_at, on_branch, period_windows


def _data():
    p = np.arange(10.0)
    up_n = [1, 1, 1, 0, 2, 2, 0, 0, 1, 1]
    dn_n = [1, 1, 1, 0, 2, 2, 2, 0, 1, 1]
    up_q = [1.0, 1.1, 1.2, 5, 3.0, 3.1, 7, 7, 2.0, 2.1]
    dn_q = [1.0, 1.1, 1.2, 5, 3.0, 3.1, 3.2, 7, 4.0, 4.1]   # 8, 9: another period-1 orbit
    status = np.zeros(20, int)
    status[0] = -3                                       # a failed point (up, p = 0)
    return {"param": np.concatenate([p, p[::-1]]),
            "direction": np.array(["up"] * 10 + ["down"] * 10),
            "period_n": np.array(up_n + dn_n[::-1]), "qmax": np.array(up_q + dn_q[::-1]),
            "status": status, "u_end": np.arange(40.0).reshape(20, 2)}


def test_windows_merged_and_kept_apart():
    w = period_windows(_data(), 2)
    got = sorted((x.n, x.lo, x.hi, x.direction) for x in w)
    # down: [0,2] P1, [4,6] P2, [8,9] P1 (the other orbit); up: [1,2] P1 and [4,5] P2 are
    # the down sweep's orbits (same maxima), [8,9] P1 is a different orbit (2.0 vs 4.0)
    assert got == [(1, 0.0, 2.0, "down"), (1, 8.0, 9.0, "down"), (1, 8.0, 9.0, "up"),
                   (2, 4.0, 6.0, "down")]
    mid = next(x for x in w if x.n == 2)
    assert mid.param == 5.0 and mid.qmax == 3.1 and mid.points == 3
    assert np.array_equal(mid.u0, _data()["u_end"][14])    # down sweep, p = 5
    assert period_windows(_data(), 3) == []                 # another model's states


def _pt(p, q, stable=True):
    return SimpleNamespace(param=p, qmax=q, stable=stable)


def test_branch_value_through_a_fold():
    br = SimpleNamespace(n_periods=1, points=[_pt(0.0, 0.0), _pt(2.0, 2.0), _pt(1.0, 3.0, False),
                                              _pt(3.0, 5.0, False)])
    vals = sorted(branch_value_at(br, 1.5))
    assert vals == [(1.5, True, 2.0), (2.5, False, 1.0), (3.5, False, 2.0)]
    assert on_branch([br], 1, 1.5, 2.5 * (1 + 5e-4), 1e-3)
    assert on_branch([br], 1, 1.5, 2.74, 1e-3)           # within a quarter of the change
    assert not on_branch([br], 1, 1.5, 2.1, 1e-3)
    assert not on_branch([br], 1, 1.5, 2.95, 1e-3)
    assert not on_branch([br], 2, 1.5, 2.5, 1e-3)
