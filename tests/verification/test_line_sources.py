"""Line sources on integrated models: a linear forced oscillator's steady response has lines
only at the forcing, its free vibration is named by its natural frequency, and a chaotic
impact pair is broadband (its stroboscopic samples too)."""
from __future__ import annotations

import math

import numpy as np

from vibrogear.config.options import IntegrationOptions, SweepOptions
from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.sequential.strob_evidence import spectral_evidence
from vibrogear.solvers.integrator.integrate import integrate
from vibrogear.solvers.sequential.motion import CHAOTIC
from vibrogear.solvers.sequential.spectral_lines import (Source, broadband_fraction,
                                                         find_lines, identify)
from vibrogear.solvers.sequential.spectrum import amplitude_spectrum
from vibrogear.solvers.sequential.sweep import sweep

OPT = IntegrationOptions(rtol=1e-10, atol=1e-12)
#: tests/verification/test_sweep_evidence.py's chaotic impact pair (Omega = 1.1)
CHAOS = (0.015, 0.0, 0.1, 0.3, 1.0)


def _record(model, Om, u0, R, S=32):
    T = 2 * np.pi / Om
    t = np.arange(R * S) * (T / S)
    tr = integrate(model, Om, u0, 0.0, R * T, t_eval=t, options=OPT)
    s = amplitude_spectrum(tr.u[:, 0], R * T)
    return s.freq, s.amplitude, R * S


def _sources(Om, zeta):
    """The forcing's harmonics and the natural frequency sqrt(1 - zeta^2) (kappa = 1), in
    cycles per model time unit."""
    return [Source("forcing", Om / (2 * np.pi), "mesh", 8),
            Source("natural", math.sqrt(1 - zeta ** 2) / (2 * np.pi), "mode")]


def test_linear_forced_response_has_lines_only_at_the_forcing():
    zeta, Om = 0.02, 0.37                    # b_r = 100: the clearance is never reached
    model = impact_pair_model(zeta, 1.0, 0.1, 0.3, 100.0)
    T = 2 * np.pi / Om
    u = integrate(model, Om, np.zeros(2), 0.0, 200 * T, options=OPT).u_end  # e^-35 decayed
    freq, amp, n = _record(model, Om, u, 64)
    ln = identify(find_lines(freq, amp), _sources(Om, zeta), 0.5 * freq[1], f1=freq[64])
    assert ln.source == ("forcing 1x",)
    # steady amplitude of the forced linear oscillator, 0.3 / |1 - Om^2 + 2 i zeta Om|
    assert ln.amp[0] == amp[64] and abs(ln.offset[0]) < 1e-12
    assert abs(ln.amp[0] - 0.3 / abs(1 - Om ** 2 + 2j * zeta * Om)) < 1e-6
    assert broadband_fraction(amp, n, ln.bin) < 1e-8


def test_free_vibration_is_named_by_the_natural_frequency():
    zeta, Om = 0.001, 0.37                   # from rest: the transient rings at ~1/(2 pi)
    model = impact_pair_model(zeta, 1.0, 0.0, 0.3, 100.0)
    freq, amp, _ = _record(model, Om, np.zeros(2), 64)
    ln = identify(find_lines(freq, amp), _sources(Om, zeta), 0.5 * freq[1], f1=freq[64])
    named = dict(zip(ln.source, ln.freq))
    assert set(named) <= {"forcing 1x", "natural", "unidentified"}
    assert "forcing 1x" in named and "natural" in named
    assert abs(named["natural"] - math.sqrt(1 - zeta ** 2) / (2 * np.pi)) < 0.5 * freq[1]


def test_chaotic_impact_pair_is_broadband():
    model, Om = impact_pair_model(*CHAOS), 1.1
    T = 2 * np.pi / Om
    u = integrate(model, Om, np.zeros(2), 0.0, 300 * T, options=OPT).u_end
    freq, amp, n = _record(model, Om, u, 256)
    ln = identify(find_lines(freq, amp), _sources(Om, CHAOS[0])[:1], 0.5 * freq[1],
                  f1=freq[256])
    bb = broadband_fraction(amp, n, ln.bin[ln.identified])
    assert bb > 0.5, bb
    # a periodic impact pair (test_impact_vs_exact.py's P_A at Omega = 0.8, period 1) is
    # not: what lies outside its lines is its harmonics below the 1 % threshold (measured
    # 6.6e-6 of the power)
    model2, Om2 = impact_pair_model(0.05, 0.5, 0.2, 0.2, 0.5), 0.8     # P_A: period 1
    u2 = integrate(model2, Om2, np.zeros(2), 0.0, 400 * 2 * np.pi / Om2, options=OPT).u_end
    freq2, amp2, n2 = _record(model2, Om2, u2, 64)
    ln2 = identify(find_lines(freq2, amp2), _sources(Om2, 0.05)[:1], 0.5 * freq2[1],
                   f1=freq2[64])
    assert all(k == "mesh" for k in ln2.kind)
    assert broadband_fraction(amp2, n2, ln2.bin) < 1e-4
    # the sweep's stroboscopic evidence of the chaotic point: broadband, no base pair
    s = sweep(model, [Om], SweepOptions(directions=("up",), transient_periods=0,
                                        record_periods=64, extra_transient_periods=0),
              options=OPT, u0=u)
    assert s.motion_class[0] == CHAOTIC
    ev = spectral_evidence(s)
    assert ev["strob_flatness"][0] > 0.2 and ev["base_f2_order"][0] == 0.0
