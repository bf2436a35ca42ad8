"""Contact switches of an orbit and the grazing note (solvers/periodic/special_points.py), on the
impact pair against its exact piecewise-linear orbits: where the exact orbit stays inside
the clearance (q_max < b_r) the integrated orbit switches nothing; where it crosses the
clearance on both sides it switches twice per contact interval, and the note names the
change."""
from __future__ import annotations

import numpy as np

from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.periodic.special_points import grazing_note, switch_counts
from vibrogear.verification.impact_exact import ImpactParams
from vibrogear.verification.impact_orbits import periodic_orbit

PAR = dict(zeta=0.05, kappa=0.5, f_m=0.2, f_p=0.3, b_r=1.0)
OPT = IntegrationOptions(rtol=1e-10, atol=1e-12)


def _orbit_switches(model, om):
    ex = periodic_orbit(ImpactParams(**PAR), om)
    assert ex.converged
    tr = integrate(model, om, ex.u0, 0.0, 2 * np.pi / om, options=OPT)
    return ex, switch_counts(model, tr)


def test_switches_follow_the_exact_orbit_and_the_note_names_the_change():
    model = impact_pair_model(**PAR)
    inside, none = _orbit_switches(model, 2.0)      # far above resonance: no impact
    hitting, two = _orbit_switches(model, 0.75)     # near resonance (kappa^0.5)
    b = PAR["b_r"]
    assert -b < inside.q_min and inside.q_max < b
    # the exact orbit crosses the clearance on both sides: one interval per side
    assert hitting.q_min < -b and hitting.q_max > b
    assert none.tolist() == [0] and two.tolist() == [4]
    assert grazing_note(model, none, two) == "clearance: 0 -> 4 contact switches per orbit"
    assert grazing_note(model, two, two) == ""
