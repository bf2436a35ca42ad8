"""Converging statistics of a record (solvers/sequential/record_metrics.py:
deformation_statistics) against closed forms: the RMS and the spectral lines of a trigonometric polynomial, a zero
batch-means error on a periodic record, and on a random record an error bar that agrees
with the spread of independent repetitions."""
from __future__ import annotations

import numpy as np

from vibrogear.solvers.sequential.record_metrics import batch_blocks, deformation_statistics


def test_trigonometric_polynomial_exact():
    S, P = 32, 24
    t = np.arange(S * P) / S                       # in periods
    a1, a2, a3, mean = 2.0, 0.7, 0.3, 5.0
    x = mean + a1 * np.cos(2 * np.pi * t + 0.4) + a2 * np.sin(4 * np.pi * t) \
        + a3 * np.cos(6 * np.pi * t - 1.0) + 0.9 * np.cos(2 * np.pi * 5 * t)
    st = deformation_statistics(x, S, period_n=1)
    rms = np.sqrt((a1 ** 2 + a2 ** 2 + a3 ** 2 + 0.9 ** 2) / 2)
    assert abs(st["rms"] - rms) < 1e-12 * rms
    for h, a in ((1, a1), (2, a2), (3, a3)):
        assert abs(st[f"line_{h}x"] - a) < 1e-12
        assert st[f"line_{h}x_err"] < 1e-12          # every block holds the same periods
    assert st["rms_err"] < 1e-12


def test_batch_means_error_matches_repetitions():
    """White noise of variance 1: the RMS's batch-means error bar agrees with the spread of
    the RMS over independent records (within the sampling scatter of 400 records)."""
    rng = np.random.default_rng(7)
    S, P = 16, 64
    vals, bars = [], []
    for _ in range(400):
        st = deformation_statistics(rng.standard_normal(S * P), S)
        vals.append(st["rms"])
        bars.append(st["rms_err"])
    spread = np.std(vals, ddof=1)
    assert 0.8 < np.mean(bars) / spread < 1.2
    # the closed form of the spread of a sample standard deviation: 1 / sqrt(2 N)
    assert abs(spread * np.sqrt(2 * S * P) - 1.0) < 0.1


def test_blocks_are_whole_multiples_of_the_period():
    assert batch_blocks(64, 0) == (8, 8)
    assert batch_blocks(20, 0) == (2, 10)
    L, B = batch_blocks(64, 3)
    assert L % 3 == 0 and B >= 2 and L * B <= 64
    assert batch_blocks(5, 8)[1] < 2               # too short: no error bar
