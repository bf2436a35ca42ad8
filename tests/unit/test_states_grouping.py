"""Grouping of non-periodic settled motions into attractors (issue 33's over-split): records
drawn from known laws, so that the answer is known.

* One chaotic law (the logistic map x -> 4 x (1 - x), whose exponent is ln 2 per iterate)
  sampled by short records, each with its own scatter: one attractor, whatever classes and
  extrema the short records show.
* A quiet quasi-periodic torus (a rotation by the golden mean, no impacts) beside that
  rattling chaotic state: two.
* Two tori with the same impacts and rattle within their errors but extrema 3.8 apart
  (gear_pair at 5250 rpm): two.
* The extrema gap threshold splits one law's values at most 1 % of the time.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from vibrogear.analyses.states.cluster import cluster_point, group_class
from vibrogear.analyses.states.gaps import gap_ratio, gap_threshold, split_by_extrema
from vibrogear.solvers.sequential.motion import CHAOTIC, NOT_SETTLED, QUASI_PERIODIC
from vibrogear.solvers.sequential.record_metrics import batch_blocks
from vibrogear.solvers.sequential.sweep_point import PointRecord

P, S = 32, 8          # record periods, samples per period
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


def _batch(values_per_period) -> tuple[float, float]:
    """Mean and batch-means error of per-period values (8 blocks, as the sweep point)."""
    v = np.asarray(values_per_period, float)
    L, B = batch_blocks(v.size)
    blocks = v[:L * B].reshape(B, L).mean(axis=1)
    return float(v.mean()), float(blocks.std(ddof=1) / math.sqrt(B))


def _record(k, d, *, lam, lam_half, cls=None, gap=0.75):
    """A non-periodic record of the dense deformation ``d`` (P x S samples): Poincare
    samples at the period starts, extrema, impacts (samples above ``gap``, entering) and
    rattle (excess squared) per period with batch-means errors, exponent interval."""
    d = np.asarray(d, float).reshape(P, S)
    above = d > gap
    onsets = above & ~np.roll(above, 1, axis=None).reshape(P, S)
    imp, imp_err = _batch(onsets.sum(axis=1))
    rat, rat_err = _batch(np.where(above, (d - gap) ** 2, 0.0).sum(axis=1))
    lo, hi = lam - lam_half, lam + lam_half
    if cls is None:
        cls = CHAOTIC if lo > 0 else QUASI_PERIODIC
    metrics = {"impacts_drive_G1": imp, "impacts_drive_G1_err": imp_err,
               "impacts_back_G1": 0.0, "impacts_back_G1_err": 0.0,
               "rattle_G1": rat, "rattle_G1_err": rat_err}
    return PointRecord("start", k, 1.0, float(d.min()), float(d.max()), d[:, 0].copy(), 0,
                       imp, math.nan, 0, 0, "ok", np.zeros(2), motion_class=cls,
                       lyapunov=lam, lyapunov_ci=(lo, hi), metrics=metrics)


def _logistic(seed):
    """P x S iterates of the logistic map after a burn-in (invariant density 1/(pi
    sqrt(x (1 - x)))); an iterate that rounds onto the fixed point 0 restarts at random
    (floating point collapses 4 x (1 - x) onto 0 within a few hundred iterates)."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.05, 0.95)
    out = np.empty(P * S + 100)
    for i in range(out.size):
        x = 4 * x * (1 - x)
        if not 1e-12 < x < 1 - 1e-12:
            x = rng.uniform(0.05, 0.95)
        out[i] = x
    return out[100:]


def _chaotic(k, seed):
    """The deformation: a moving average over 4 iterates of the map (a filtered response:
    its extremes are rare, so short records' extrema scatter), flank at 0.75."""
    x = _logistic(seed)
    d = np.convolve(np.concatenate([x, x[:3]]), np.full(4, 0.25), mode="valid")[:x.size]
    # the exponent of this record: mean log|f'| over 8 blocks, Student-t 95 % half-width
    g = np.log(np.abs(4 * (1 - 2 * x))).reshape(8, -1).mean(axis=1)   # per iterate
    half = 2.365 * g.std(ddof=1) / math.sqrt(8)
    return _record(k, d, lam=float(g.mean()), lam_half=float(half), gap=0.75)


def _torus(k, phase, amp=0.3, mid=0.45):
    n = np.arange(P * S)
    d = mid + amp * np.cos(2 * np.pi * (GOLDEN * n / S + phase))
    return _record(k, d, lam=0.0, lam_half=0.01)


def _group(recs):
    atts, n_ok, _ = cluster_point(recs, 0, 1.0, n_modes=1, cluster_tol=1e-3, stat_tol=0.05)
    return sorted(sorted(a.members) for a in atts), atts, n_ok


def test_short_records_of_one_chaotic_law_are_one_attractor():
    """16 records of 32 periods of the logistic map: extrema, impacts and rattle scatter from
    record to record; they are one attractor in at least 18 of 20 censuses (measured: 19;
    the former rule, extrema within 5 % of the spread and one class: 10)."""
    ones = 0
    for c in range(20):
        recs = [_chaotic(k, seed=1000 * c + k) for k in range(16)]
        groups, atts, _ = _group(recs)
        ones += len(groups) == 1
    assert ones >= 18
    # its exponent: the members' mean, an interval around ln 2 (per iterate here)
    a = atts[0]
    assert a.class_name == "chaotic" and a.lyapunov_ci[0] < math.log(2) < a.lyapunov_ci[1]
    assert a.qmin == min(r.qmin for r in recs) and a.qmax == max(r.qmax for r in recs)


def test_short_chaotic_records_classed_quasi_periodic_by_chance_join_the_chaotic_ones():
    """Exponent intervals that straddle 0 (a short record) are consistent with the chaotic
    members' exponent: one attractor, chaotic (5 of 8 members chaotic: a torus gives that
    with probability ~1e-7); its exponent the members' mean with the combined interval."""
    recs = []
    for k in range(8):
        r = _chaotic(k, seed=77 + k)
        lam = 0.06 + 0.02 * (k % 3 - 1)
        half = 0.07 if k < 3 else 0.05          # the first three straddle 0
        cls = QUASI_PERIODIC if k < 3 else CHAOTIC
        recs.append(PointRecord(**{**r.__dict__, "lyapunov": lam,
                                   "lyapunov_ci": (lam - half, lam + half),
                                   "motion_class": cls}))
    groups, atts, _ = _group(recs)
    assert groups == [list(range(8))]
    assert atts[0].class_name == "chaotic"
    assert atts[0].member_classes == {"quasi-periodic": 3, "chaotic": 5}
    lo, hi = atts[0].lyapunov_ci
    assert atts[0].lyapunov == pytest.approx(np.mean([r.lyapunov for r in recs]))
    assert hi - lo == pytest.approx(2 * 1.959964 * math.sqrt(
        sum(((0.07 if k < 3 else 0.05) / 1.959964) ** 2 for k in range(8))) / 8, rel=1e-5)


def test_a_quiet_torus_and_a_rattling_chaotic_state_stay_two():
    recs = []
    for k in range(12):
        recs.append(_torus(k, phase=0.37 * k) if k % 3 == 0 else _chaotic(k, seed=500 + k))
    groups, atts, n_ok = _group(recs)
    torus = [k for k in range(12) if k % 3 == 0]
    assert groups == sorted([torus, [k for k in range(12) if k % 3]])
    quiet = next(a for a in atts if sorted(a.members) == torus)
    assert quiet.metrics["G1"]["impacts"] == 0.0 and quiet.class_name == "quasi-periodic"
    assert quiet.fraction == pytest.approx(4 / 12)


def test_a_chaotic_state_and_a_periodic_orbit_never_merge():
    cyc = np.array([[0.5, 0.0]])
    per = PointRecord("start", 9, 1.0, 0.0, 1.0, np.full(P, 0.5), 1, 0.0, 0.0, 1, 0, "ok",
                      cyc[-1], states=cyc, motion_class=1)
    recs = [_chaotic(k, seed=900 + k) for k in range(4)] + [per]
    groups, _, _ = _group(recs)
    assert groups == [[0, 1, 2, 3], [9]]


def test_two_tori_with_overlapping_statistics_but_separate_extrema_stay_two():
    """gear_pair at 5250 rpm: two groups of settled tori with impacts and rattle within
    their batch-means errors of each other, ranges overlapping over 90 %, but minima at
    -27.7 +- 0.2 and -31.5 +- 0.2 (um): two attractors."""
    rng = np.random.default_rng(3)
    recs = []
    for k in range(16):
        first = k % 2 == 0
        d = _torus(k, phase=rng.uniform())
        qmin = (-27.7 if first else -31.5) + 0.2 * rng.standard_normal()
        qmax = 27.2 + 0.2 * rng.standard_normal()
        rat = (0.042 if first else 0.037) + 0.001 * rng.standard_normal()
        m = {"impacts_drive_G1": 0.95, "impacts_drive_G1_err": 0.05, "impacts_back_G1": 0.0,
             "impacts_back_G1_err": 0.0, "rattle_G1": rat, "rattle_G1_err": 0.0025}
        recs.append(PointRecord(**{**d.__dict__, "qmin": qmin, "qmax": qmax, "metrics": m}))
    groups, _, _ = _group(recs)
    assert groups == [list(range(0, 16, 2)), list(range(1, 16, 2))]


def test_not_settled_motions_join_only_when_the_budget_alone_stopped_them():
    """'Not settled' because the transient budget ran out, exponent interval around the
    others' and the same statistics: on the attractor.  'Not settled' with an exponent
    interval below 0 (the motion still converges, e.g. to an orbit): apart."""
    recs = [_chaotic(k, seed=40 + k) for k in range(3)]
    lam = recs[0].lyapunov
    budget = PointRecord(**{**recs[1].__dict__, "index": 3, "motion_class": NOT_SETTLED,
                            "lyapunov_ci": (lam - 0.8, lam + 0.8)})
    converging = PointRecord(**{**recs[2].__dict__, "index": 4, "motion_class": NOT_SETTLED,
                                "lyapunov": -0.05, "lyapunov_ci": (-0.08, -0.02)})
    groups, atts, _ = _group(recs + [budget, converging])
    assert groups == [[0, 1, 2, 3], [4]]
    big = next(a for a in atts if a.count == 4)
    assert big.class_name == "chaotic" and big.member_classes == {"chaotic": 3,
                                                                    "not settled": 1}
    assert next(a for a in atts if a.count == 1).class_name == "not settled"


@pytest.mark.parametrize("n", [6, 8, 16, 32])
def test_the_gap_threshold_splits_one_law_at_most_one_time_in_a_hundred(n):
    """Fresh draws (another seed than the threshold's) from the exponential law the
    threshold was computed for: about 1 % exceed it (binomial 3-sigma band over 3000);
    from a normal law (lighter tail): at most that."""
    lim = gap_threshold(n)
    rng = np.random.default_rng(2024 + n)
    exp = np.mean([gap_ratio(rng.exponential(size=n))[0] > lim for _ in range(3000)])
    nor = np.mean([gap_ratio(rng.standard_normal(n))[0] > lim for _ in range(3000)])
    band = 3 * math.sqrt(0.01 * 0.99 / 3000)
    assert abs(exp - 0.01) < band and nor < 0.01 + band


def test_gap_ratio_is_the_largest_gap_over_the_larger_side_spread():
    v = [1.0, 1.1, 1.2, 5.0, 5.1, 5.3]
    ratio, cut = gap_ratio(v)
    assert cut == pytest.approx(3.1)
    assert ratio == pytest.approx(3.8 / max(np.std(v[:3], ddof=1), np.std(v[3:], ddof=1)))
    assert gap_ratio(v[:5]) == (0.0, pytest.approx(math.nan, nan_ok=True))   # too few
    # a group of such records split in two, start order kept in each part
    recs = [PointRecord("start", k, 1.0, q, 10.0, np.zeros(P), 0, 0.0, 0.0, 0, 0, "ok",
                        np.zeros(2)) for k, q in zip(range(6), [5.0, 1.0, 5.1, 1.1, 5.3, 1.2])]
    assert [[r.index for r in part] for part in split_by_extrema(recs)] == [[0, 2, 4],
                                                                          [1, 3, 5]]


def test_a_group_is_chaotic_only_with_more_chaotic_members_than_a_torus_gives_by_chance():
    """A torus's record is classed chaotic (95 % interval above 0) about 2.5 % of the time:
    1 of 16 such members is chance (binomial tail 0.33), 3 of 8 is not (7e-4)."""
    def rec(k, cls):
        return PointRecord("start", k, 1.0, 0.0, 1.0, np.zeros(P), 0, 0.0, 0.0, 0, 0, "ok",
                           np.zeros(2), motion_class=cls)
    one_in_16 = [rec(k, CHAOTIC if k == 5 else QUASI_PERIODIC) for k in range(16)]
    three_in_8 = [rec(k, CHAOTIC if k < 3 else QUASI_PERIODIC) for k in range(8)]
    assert group_class(one_in_16) == QUASI_PERIODIC
    assert group_class(three_in_8) == CHAOTIC
    assert group_class([rec(0, NOT_SETTLED), rec(1, NOT_SETTLED)]) == NOT_SETTLED
