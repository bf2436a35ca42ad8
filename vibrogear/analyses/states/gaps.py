"""A non-periodic group of census records split where its extrema fall into two clumps:
distinct tori whose other statistics agree within their errors still differ in where their
deformation turns (docs/states.md, "Grouping non-periodic motions").  The gap between two
clumps is measured against the spread within them and compared with the quantile that one
distribution's largest gap ratio reaches by chance."""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

__all__ = ["gap_threshold", "gap_ratio", "split_by_extrema", "GAP_SIDE", "GAP_QUANTILE"]

#: an extrema gap splits a group only with at least this many members on each side
GAP_SIDE = 3
#: ... and when it exceeds this quantile of the largest gap ratio of one distribution
GAP_QUANTILE = 0.99


@lru_cache(maxsize=None)
def gap_threshold(n: int, draws: int = 4000) -> float:
    """The :data:`GAP_QUANTILE` quantile of :func:`gap_ratio` over ``n`` values drawn from
    one exponential law (a heavier tail than the Gumbel law of record extrema: one
    attractor's extrema split by chance at most 1 - GAP_QUANTILE of the time); fixed seed."""
    v = np.sort(np.random.default_rng(12345).exponential(size=(draws, n)), axis=1)
    return float(np.quantile(_gap_ratios(v)[0], GAP_QUANTILE))


def _gap_ratios(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per row of sorted ``v`` (rows, n): the largest gap between neighbours with at least
    GAP_SIDE values on each side over the larger standard deviation of the two sides, and
    the index of the first value above that gap."""
    n = v.shape[1]
    best, at = np.zeros(v.shape[0]), np.zeros(v.shape[0], int)
    v = v - v.mean(axis=1, keepdims=True)            # centred: sums of squares stay exact
    c1, c2 = np.cumsum(v, axis=1), np.cumsum(v * v, axis=1)
    for k in range(GAP_SIDE, n - GAP_SIDE + 1):
        s1, s2 = c1[:, -1] - c1[:, k - 1], c2[:, -1] - c2[:, k - 1]
        var = np.maximum((c2[:, k - 1] - c1[:, k - 1] ** 2 / k) / (k - 1),
                         (s2 - s1 ** 2 / (n - k)) / (n - k - 1))
        sd, gap = np.sqrt(np.maximum(var, 0.0)), v[:, k] - v[:, k - 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(sd > 0, gap / sd, np.where(gap > 0, np.inf, 0.0))
        at = np.where(r > best, k, at)
        best = np.maximum(best, r)
    return best, at


def gap_ratio(values) -> tuple[float, float]:
    """(ratio, cut) of ``values``: :func:`_gap_ratios` and the middle of that gap."""
    v = np.sort(np.asarray(values, dtype=float))
    if v.size < 2 * GAP_SIDE:
        return 0.0, math.nan
    best, at = (x[0] for x in _gap_ratios(v[None, :]))
    return float(best), (0.5 * float(v[at] + v[at - 1]) if best > 0 else math.nan)


def split_by_extrema(members: list) -> list[list]:
    """A non-periodic group split where its extrema (qmin or qmax over the members) fall
    into two clumps whose gap exceeds :func:`gap_threshold` (recursively; start order kept
    in each part)."""
    if len(members) < 2 * GAP_SIDE:
        return [members]
    limit = gap_threshold(len(members))
    for key in ("qmin", "qmax"):
        ratio, cut = gap_ratio([getattr(r, key) for r in members])
        if ratio > limit:
            low = [r for r in members if getattr(r, key) < cut]
            high = [r for r in members if getattr(r, key) >= cut]
            parts = split_by_extrema(low) + split_by_extrema(high)
            return sorted(parts, key=lambda ms: ms[0].index)
    return [members]
