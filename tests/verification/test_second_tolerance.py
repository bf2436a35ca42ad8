"""[sweep] second_tolerance: the record window integrated again at rtol / 10 from the same
settled state; the change of each statistic is its tolerance error (``<name>_tol_err``).

* On a stable periodic impact-pair orbit the true error of the extrema and impact speeds
  (against the exact piecewise-linear orbit: closed form region by region, switch times by
  root finding) is what the tolerance error says, within a factor 2.
* On the chaotic impact pair the two records diverge, so the difference of a statistic is
  a sampling difference: within 4 sqrt(2) batch-means errors.
* Off (the default) no ``_tol_err`` is added and nothing else changes.
"""
from __future__ import annotations

import dataclasses
import numpy as np

from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.sequential.sweep import sweep
from vibrogear.config.options import SweepOptions
from reference import impact_exact as ex  # the flow and the periodic orbits

#: tests/verification/test_sweep_evidence.py's double-sided orbit and chaotic pair
P_A = (0.05, 0.5, 0.2, 0.2, 0.5)
CHAOS = (0.015, 0.0, 0.1, 0.3, 1.0)
LOOSE = IntegrationOptions(rtol=1e-6, atol=1e-8)


def test_tolerance_error_matches_the_true_error_on_a_periodic_orbit():
    Om = 0.8
    model = impact_pair_model(*P_A)
    fine = IntegrationOptions(rtol=1e-11, atol=1e-13)
    guess = integrate(model, Om, np.zeros(2), 0.0, 400 * 2 * np.pi / Om, options=fine).u_end
    orb = ex.periodic_orbit(ex.ImpactParams(*P_A, 0.0), Om, guess)
    assert orb.converged and orb.stable
    fl = orb.flow
    v = np.abs(fl.switch_states[fl.switch_to != 0, 1])
    s = sweep(model, [Om], SweepOptions(directions=("up",), transient_periods=0, record_periods=8, max_period=4, second_tolerance=True, extra_transient_periods=0), options=LOOSE, u0=orb.u0)
    g = s.metrics
    assert s.period_n[0] == 1
    true = {"impact_velocity_max_clearance": abs(g["impact_velocity_max_clearance"][0] - v.max()),
            "rattle_clearance": abs(g["rattle_clearance"][0] - np.sum(0.5 * v ** 2))}
    for k, err in true.items():
        tol = g[f"{k}_tol_err"][0]
        assert err > 1e-12 and 0.5 * err <= tol <= 2.0 * err, (k, err, tol)
    assert g["impacts_drive_clearance_tol_err"][0] == 0.0      # counts do not change
    assert np.isfinite(g["qmax_tol_err"][0]) and np.isfinite(g["qmin_tol_err"][0])


def test_chaotic_tolerance_error_is_a_sampling_difference():
    model, Om = impact_pair_model(*CHAOS), 1.0
    u = integrate(model, Om, np.zeros(2), 0.0, 300 * 2 * np.pi / Om, options=LOOSE).u_end
    kw = dict(u0=u, options=LOOSE)
    base = SweepOptions(directions=("up",), transient_periods=0, extra_transient_periods=0,
                        record_periods=128, lyapunov=False, shoot=False)
    on = sweep(model, [Om], dataclasses.replace(base, second_tolerance=True), **kw)
    off = sweep(model, [Om], base, **kw)
    assert on.period_n[0] == 0
    for k in ("impacts_drive", "contact_fraction", "impact_velocity_rms", "rattle"):
        key = f"{k}_clearance"
        err, tol = on.metrics[f"{key}_err"][0], on.metrics[f"{key}_tol_err"][0]
        assert err > 0 and tol <= 4 * np.sqrt(2) * err, (k, tol, err)
        assert on.metrics[key][0] == off.metrics[key][0]       # the first record is unchanged
    assert not any(k.endswith("_tol_err") for k in off.metrics)
