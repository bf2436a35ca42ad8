"""Contact deformations and forces of a ReducedModel along a sampled trajectory (numpy).

Post-processing of integrator output: delta_j(t) = c_j . x - e_j(t), its rate, the
stiffness modulation mu_j(t) and the force of each contact by the one contact law
(:mod:`vibrogear.models.contact_law`), every mode taken from the sign of the deformation
(post-processing has no integrator mode).  Forces are in the model's units (a
gearbox's: N / omega_ref^2).
"""
from __future__ import annotations

import numpy as np

from ...models.contact_law import evaluate_set, harmonic_series
from ...models.reduced import ReducedModel

__all__ = ["contact_kinematics", "contact_history"]


def contact_kinematics(model: ReducedModel, param: float, t, states, rows=None):
    """(delta, delta_dot, mu), each (n_rows, len(t)), for states (len(t), 2m); ``rows``:
    the contacts to evaluate (default all)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    states = np.atleast_2d(states)
    ct, m = model.contacts, model.n_modes
    rows = np.arange(ct.count) if rows is None else np.asarray(rows, dtype=int)
    W = model.excitation_frequency(param)
    e, e_dot = harmonic_series(ct.error_cos[rows], ct.error_sin[rows], W, t,
                               orders=model.harmonic_orders)
    mu = 1.0 + harmonic_series(ct.stiffness_cos[rows], ct.stiffness_sin[rows], W, t,
                               orders=model.harmonic_orders)[0]
    delta = ct.directions[rows] @ states[:, :m].T - e
    delta_dot = ct.directions[rows] @ states[:, m:].T - e_dot
    return delta, delta_dot, mu


def contact_history(model: ReducedModel, param: float, t, states):
    """(delta, delta_dot, force), each (n_contacts, len(t)), for states (len(t), 2m)."""
    delta, delta_dot, mu = contact_kinematics(model, param, t, states)
    force = evaluate_set(model.contacts, delta, delta_dot, mu).force
    return delta, delta_dot, force
