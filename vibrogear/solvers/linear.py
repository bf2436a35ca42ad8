"""Linearisation of a ReducedModel about a static state, and its damped modes.

The tangent stiffness and damping at x0 (zero velocity, mean mesh stiffness, no
transmission error) are

    K_t = diag(w^2) + P^T Kc(s) P + sum_j k'_j(delta_j) c_j c_j^T
    D_t = diag(2 zeta w) + P^T Bc(s) P + sum_{j in contact} c_j c_j^T damping_j

with k'_j the slope of contact j's force law at delta_j = c_j . x0 (0 in its dead zone):
the "linearised reduced model" of paper section II.B.  Everything is in the model's units
(time unit 1/omega_ref for a gearbox).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..models.contact_law import evaluate_set
from ..models.reduced import ReducedModel

__all__ = ["tangent_matrices", "contact_slopes", "LinearModes", "linear_modes"]


def contact_slopes(model: ReducedModel, x0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(k'_j, in_contact_j) of every contact at the static state x0 (the contact law at
    zero velocity, mean stiffness, modes from the sign)."""
    law = evaluate_set(model.contacts, model.contacts.directions @ x0)
    return law.stiffness, law.mode != 0


def tangent_matrices(model: ReducedModel, x0, param: float) -> tuple[np.ndarray, np.ndarray]:
    """(K_t, D_t), both m x m, at the static state x0 and parameter ``param``."""
    x0 = np.asarray(x0, dtype=float)[:model.n_modes]
    cp, ct = model.coupling, model.contacts
    s = model.spin_per_param * param
    K = np.diag(model.omega2).astype(float)
    D = np.diag(model.damping).astype(float)
    if cp.P.shape[0]:
        K += cp.P.T @ (cp.Kc0 + s * cp.Kc1) @ cp.P
        D += cp.P.T @ (cp.Bc0 + s * cp.Bc1) @ cp.P
    if ct.count:
        law = evaluate_set(ct, ct.directions @ x0)
        C = ct.directions
        K += C.T @ (law.stiffness[:, None] * C)
        D += C.T @ (law.damping[:, None] * C)
    return K, D


@dataclass(frozen=True, eq=False)
class LinearModes:
    frequency: np.ndarray       # natural frequencies |lambda| / 2 pi (model time units)
    damping_ratio: np.ndarray
    vectors: np.ndarray         # (m, n) displacement parts of the eigenvectors (complex)
    undamped: np.ndarray        # undamped frequencies sqrt(eig(K_t)) / 2 pi (same units)
    undamped_vectors: np.ndarray


def linear_modes(model: ReducedModel, x0, param: float) -> LinearModes:
    """Modes of the linearised model: the undamped problem (K_t symmetric part) and the
    damped, gyroscopic state-space problem; one entry per conjugate pair, ascending."""
    K, D = tangent_matrices(model, x0, param)
    m = model.n_modes
    lam_u, vec_u = sla.eigh(0.5 * (K + K.T))
    undamped = np.sqrt(np.clip(lam_u, 0.0, None)) / (2 * np.pi)
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-K, -D]])
    lam, vec = sla.eig(A)
    keep = lam.imag > 1e-12 * max(1.0, float(np.max(np.abs(lam))))
    lam, vec = lam[keep], vec[:m, keep]
    order = np.argsort(lam.imag)
    lam, vec = lam[order], vec[:, order]
    freq = np.abs(lam) / (2 * np.pi)
    zeta = -lam.real / np.maximum(np.abs(lam), 1e-300)
    return LinearModes(freq, zeta, vec, undamped, vec_u)
