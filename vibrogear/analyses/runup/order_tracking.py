"""Computed order tracking and the waterfall of a signal under a varying speed.

Order tracking: the signal is resampled uniformly in the reference shaft's angle (cubic
spline; a run of :mod:`vibrogear.solvers.sequential.ramp` is sampled uniformly in that angle
already, so the resampling leaves it as it is), cut into windows of whole revolutions
(``window_revs``, overlapping by ``overlap``), Hann-windowed and Fourier-transformed
(``numpy.fft.rfft``).  Order o (cycles per revolution) lies on the bin o * window_revs; the
amplitude of a harmonic of order o is 2 |X| / sum(w), exact for a stationary harmonic on a
bin.  An order off the bins is read by the same sum evaluated at the exact order (no
scalloping; a neighbouring order closer than about 2 / window_revs leaks into it).

Waterfall: the signal resampled uniformly in time and passed to
``scipy.signal.spectrogram`` (Hann segments), amplitude spectrum per segment against the
speed at the segment's centre.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["OrderTracks", "order_tracks", "Waterfall", "waterfall"]


def _resample(s, x, grid) -> np.ndarray:
    """``x`` sampled at ``s`` (increasing) at the points ``grid`` (cubic spline: linear
    interpolation leaves images of the signal at the beat of the two sample rates)."""
    from scipy.interpolate import CubicSpline

    return CubicSpline(s, x)(np.clip(grid, s[0], s[-1]))


@dataclass(frozen=True, eq=False)
class OrderTracks:
    orders: np.ndarray          # (no,) orders tracked [cycles / revolution]
    revs: np.ndarray            # (nw,) reference angle at the window centres [revolutions]
    amplitude: np.ndarray       # (no, nw) amplitude of each order per window
    spectrum: np.ndarray        # (nw, nbins) amplitude spectrum of each window
    order_axis: np.ndarray      # (nbins,) order of each bin
    window_revs: int
    samples_per_rev: int


def order_tracks(revs, signal, orders, *, samples_per_rev: int, window_revs: int = 8,
                 overlap: float = 0.5) -> OrderTracks:
    """Amplitude of each of ``orders`` over sliding windows of ``window_revs`` whole
    revolutions of the reference angle ``revs`` (revolutions, increasing) of ``signal``."""
    revs = np.asarray(revs, dtype=float)
    x = np.asarray(signal, dtype=float)
    orders = np.atleast_1d(np.asarray(orders, dtype=float))
    if revs.ndim != 1 or revs.shape != x.shape or np.any(np.diff(revs) <= 0):
        raise ValueError("revs must be increasing and have the signal's shape")
    if not 0.0 <= overlap < 1.0:
        raise ValueError("overlap must lie in [0, 1)")
    n_total = int(np.floor((revs[-1] - revs[0]) * samples_per_rev + 1e-9)) + 1
    grid = revs[0] + np.arange(n_total) / samples_per_rev
    y = _resample(revs, x, grid)
    N = window_revs * samples_per_rev
    hop = max(1, int(round(N * (1.0 - overlap))))
    starts = np.arange(0, n_total - N + 1, hop)
    w = np.hanning(N + 1)[:-1]            # periodic Hann: exact on the bins
    norm = 2.0 / w.sum()
    if starts.size == 0:
        empty = np.zeros((0, N // 2 + 1))
        return OrderTracks(orders, np.zeros(0), np.zeros((orders.size, 0)), empty,
                           np.arange(N // 2 + 1) / window_revs, window_revs, samples_per_rev)
    frames = np.lib.stride_tricks.sliding_window_view(y, N)[starts]
    frames = frames - frames.mean(axis=1, keepdims=True)
    X = np.fft.rfft(frames * w, axis=1)
    spectrum = norm * np.abs(X)
    amp = np.empty((orders.size, starts.size))
    theta = np.arange(N) / samples_per_rev
    for i, o in enumerate(orders):
        b = o * window_revs
        if abs(b - round(b)) < 1e-9 and round(b) <= N // 2:
            amp[i] = spectrum[:, int(round(b))]
        else:
            kernel = w * np.exp(-2j * np.pi * o * theta)
            amp[i] = norm * np.abs(frames @ kernel)
    centre = grid[starts] + 0.5 * window_revs
    return OrderTracks(orders, centre, amp, spectrum, np.arange(N // 2 + 1) / window_revs,
                       window_revs, samples_per_rev)


@dataclass(frozen=True, eq=False)
class Waterfall:
    frequency_hz: np.ndarray    # (nf,)
    time_s: np.ndarray          # (ns,) segment centres
    amplitude: np.ndarray       # (nf, ns) amplitude spectrum


def waterfall(time_s, signal, *, segment_s: float, fs: float | None = None,
              f_max: float | None = None) -> Waterfall:
    """Spectrogram (``scipy.signal.spectrogram``, Hann, half overlap) of ``signal`` sampled
    at increasing ``time_s``, resampled at ``fs`` (default: the finest sample spacing)."""
    from scipy.signal import spectrogram

    t = np.asarray(time_s, dtype=float)
    x = np.asarray(signal, dtype=float)
    if fs is None:
        fs = 1.0 / float(np.min(np.diff(t)))
    n = int(np.floor((t[-1] - t[0]) * fs)) + 1
    grid = t[0] + np.arange(n) / fs
    y = _resample(t, x, grid)
    nper = max(8, min(n, int(round(segment_s * fs))))
    f, ts, S = spectrogram(y, fs=fs, window="hann", nperseg=nper, noverlap=nper // 2,
                           detrend="constant", scaling="spectrum", mode="magnitude")
    # mode="magnitude", scaling="spectrum": |X| / sum(w); one-sided amplitude doubles it
    A = 2.0 * S
    A[0] *= 0.5
    if f_max is not None:
        keep = f <= f_max
        f, A = f[keep], A[keep]
    return Waterfall(frequency_hz=f, time_s=t[0] + ts, amplitude=A)
