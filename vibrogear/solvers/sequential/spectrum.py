"""One-sided amplitude spectra of signals sampled over whole excitation periods (numpy).

A steady response sampled at N equidistant times over R whole excitation periods T
(t_n = n R T / N, the end point left out) has its excitation harmonics h / T exactly on the
bins k = h R of the discrete Fourier transform: no leakage, so no window is applied (a
window would only widen the lines).  Components that are not harmonics of 1 / T (a second
mesh with a non-integer frequency ratio, shaft orders when R is not a multiple of the
tooth count, the broadband part of chaotic rattle) leak into neighbouring bins as in any
rectangular-window DFT.

The one-sided amplitude spectrum A_k of x_n (so that x(t) = A_0 + sum_k A_k cos(2 pi f_k t
+ phi_k) for a signal made of bins only): A_0 = |X_0| / N, A_k = 2 |X_k| / N for
0 < k < N/2, A_{N/2} = |X_{N/2}| / N (even N).  Parseval in this form:
mean(x^2) = A_0^2 + sum_{0<k<N/2} A_k^2 / 2 + A_{N/2}^2, which :func:`parseval_error`
checks.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Spectrum", "amplitude_spectrum", "parseval_error", "power_from_amplitudes",
           "is_power_of_two"]


def is_power_of_two(n: int) -> bool:
    n = int(n)
    return n > 0 and n & (n - 1) == 0


@dataclass(frozen=True, eq=False)
class Spectrum:
    """Amplitudes (..., N//2 + 1) at the frequencies ``freq`` (N//2 + 1,) [1 / time unit]."""
    freq: np.ndarray
    amplitude: np.ndarray
    n_samples: int
    parseval_error: float        # max relative |mean(x^2) - sum of the spectrum's power|


def power_from_amplitudes(amp: np.ndarray, n_samples: int) -> np.ndarray:
    """mean(x^2) from the one-sided amplitudes (last axis) of ``n_samples`` samples."""
    amp = np.asarray(amp, dtype=float)
    p = amp[..., 0] ** 2 + 0.5 * np.sum(amp[..., 1:] ** 2, axis=-1)
    if n_samples % 2 == 0 and amp.shape[-1] > 1:
        p = p + 0.5 * amp[..., -1] ** 2      # the Nyquist bin counts once, not half
    return p


def parseval_error(x: np.ndarray, amp: np.ndarray) -> float:
    """Largest relative difference between mean(x^2) (last axis) and the power of the
    one-sided amplitudes ``amp``."""
    x = np.asarray(x, dtype=float)
    direct = np.mean(x ** 2, axis=-1)
    spec = power_from_amplitudes(amp, x.shape[-1])
    scale = np.maximum(np.abs(direct), np.finfo(float).tiny)
    return float(np.max(np.abs(direct - spec) / scale)) if direct.size else 0.0


def amplitude_spectrum(x, duration: float) -> Spectrum:
    """One-sided amplitude spectrum of samples ``x`` (..., N) taken at t_n = n duration / N
    (n = 0 .. N-1: the record covers ``duration`` without its end point).  No window: the
    record is meant to span whole excitation periods (module docstring)."""
    x = np.asarray(x, dtype=float)
    n = x.shape[-1]
    if n < 2:
        raise ValueError("amplitude_spectrum needs at least 2 samples")
    if not duration > 0:
        raise ValueError("duration must be > 0")
    X = np.fft.rfft(x, axis=-1)
    amp = np.abs(X) / n
    amp[..., 1:] *= 2.0
    if n % 2 == 0:
        amp[..., -1] *= 0.5
    freq = np.arange(X.shape[-1]) / float(duration)
    return Spectrum(freq=freq, amplitude=amp, n_samples=n, parseval_error=parseval_error(x, amp))
