"""Contact deformations and forces of a ReducedModel along a sampled trajectory (numpy).

Post-processing of integrator output: delta_j(t) = c_j . x - e_j(t), its rate, and the
force of each contact law (same law as the compiled kernel, mode taken from the sign of
the deformation).  Forces are in the model's units (a gearbox's: N / omega_ref^2).
"""
from __future__ import annotations

import numpy as np

from ..models.reduced import ReducedModel

__all__ = ["contact_history"]


def contact_history(model: ReducedModel, param: float, t, states):
    """(delta, delta_dot, force), each (n_contacts, len(t)), for states (len(t), 2m)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    states = np.atleast_2d(states)
    ct, m = model.contacts, model.n_modes
    W = model.excitation_frequency(param)
    H = ct.error_cos.shape[1]
    h = np.arange(1, H + 1)[:, None] * W * t[None, :]          # (H, nt)
    cos, sin = np.cos(h), np.sin(h)
    hW = np.arange(1, H + 1)[:, None] * W
    e = ct.error_cos @ cos + ct.error_sin @ sin
    e_dot = ct.error_cos @ (-hW * sin) + ct.error_sin @ (hW * cos)
    kfac = 1.0 + ct.stiffness_cos @ cos + ct.stiffness_sin @ sin
    delta = ct.directions @ states[:, :m].T - e
    delta_dot = ct.directions @ states[:, m:].T - e_dot
    p = ct.exponent[:, None]
    up = delta > ct.gap_hi[:, None]
    lo = delta < ct.gap_lo[:, None]
    s_up = np.where(up, delta - ct.gap_hi[:, None], 0.0)
    s_lo = np.where(lo, ct.gap_lo[:, None] - delta, 0.0)
    force = kfac * (ct.k_hi[:, None] * s_up ** p - ct.k_lo[:, None] * s_lo ** p)
    force += np.where(up | lo, ct.damping[:, None] * delta_dot, 0.0)
    return delta, delta_dot, force
