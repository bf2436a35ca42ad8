"""Floquet multipliers and the bifurcation test functions of periodic orbits.

Test functions are evaluated through signs and distances rather than raw products,
so they neither overflow nor underflow for hundreds of multipliers:

- LP (fold): the parameter component of the branch tangent.
- PD (period doubling): sign(det(M + I)) = prod over real mu of sign(mu + 1),
  magnitude min |mu + 1|.
- NS (Neimark-Sacker): sign of prod_{i<j}(mu_i mu_j - 1) (the bialternate product),
  magnitude min over complex pairs of ||mu| - 1|; valid only with a complex pair.

Every Floquet multiplier in the package comes from :func:`floquet_multipliers` (and the
flip eigenvector at a period doubling from :func:`flip_vector`); :func:`liouville_error`
checks a set of multipliers against Liouville's formula det M = exp(integral of tr J).
"""
from __future__ import annotations

import numpy as np

__all__ = ["floquet_multipliers", "flip_vector", "liouville_error", "test_functions",
           "stability", "NEUTRAL_MARGIN"]

_IMAG_TOL = 1e-9


def floquet_multipliers(monodromy: np.ndarray) -> np.ndarray:
    """The Floquet multipliers: eigenvalues of the monodromy matrix (complex)."""
    return np.linalg.eigvals(monodromy)


def flip_vector(monodromy: np.ndarray) -> np.ndarray:
    """Unit real eigenvector of the multiplier nearest -1 (the period-doubling direction)."""
    mu, vecs = np.linalg.eig(monodromy)
    w = np.real(vecs[:, int(np.argmin(np.abs(mu + 1.0)))])
    return w / np.linalg.norm(w)


def liouville_error(model, param: float, period: float, multipliers) -> float | None:
    """|prod mu - exp(tr J T)| / exp(tr J T): Liouville's formula det M = exp(integral of
    tr J), exact when the trace of the Jacobian is constant along the orbit, i.e. when no
    contact has damping (the trace is then -sum of the modal damping - tr(P^T Bc(s) P)).
    None where a contact is damped (the formula then needs the orbit's contact times)."""
    if np.any(model.contacts.damping != 0.0):
        return None
    cp = model.coupling
    s = model.spin_per_param * param
    tr = -float(np.sum(model.damping))
    if cp.P.shape[0]:
        tr -= float(np.trace(cp.P.T @ (cp.Bc0 + s * cp.Bc1) @ cp.P))
    ref = np.exp(tr * period)
    return abs(float(np.prod(multipliers).real) - ref) / ref


#: multipliers within this distance of the unit circle count as neutral, not stable (an
#: undamped orbit has |mu| = 1 up to round-off)
NEUTRAL_MARGIN = 1e-9


def stability(multipliers: np.ndarray, margin: float = NEUTRAL_MARGIN) -> bool:
    """Asymptotically stable: every multiplier inside the unit circle by ``margin``."""
    return bool(np.all(np.abs(multipliers) < 1.0 - margin))


def test_functions(monodromy: np.ndarray, tangent: np.ndarray) -> dict:
    mu = floquet_multipliers(monodromy)
    scale = max(1.0, float(np.max(np.abs(mu))))
    is_real = np.abs(mu.imag) <= _IMAG_TOL * scale
    real = mu.real[is_real]
    pairs = mu[(~is_real) & (mu.imag > 0)]
    pd_sign = float(np.prod(np.sign(real + 1.0))) if real.size else 1.0
    pd_mag = float(np.min(np.abs(real + 1.0))) if real.size else 1.0
    ns_sign = float(np.prod(np.sign(np.abs(pairs) ** 2 - 1.0))) if pairs.size else 1.0
    if real.size > 1:
        prod = np.outer(real, real)[np.triu_indices(real.size, 1)] - 1.0
        ns_sign *= float(np.prod(np.sign(prod)))
    ns_mag = float(np.min(np.abs(np.abs(pairs) - 1.0))) if pairs.size else 1.0
    return {
        "LP": float(tangent[-1]),
        "PD": pd_sign * max(pd_mag, 1e-300),
        "NS": ns_sign * max(ns_mag, 1e-300),
        "NS_valid": bool(pairs.size) and ns_mag < 0.05,
        "multipliers": mu,
    }
