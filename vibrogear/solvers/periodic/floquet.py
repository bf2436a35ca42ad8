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

Neutral directions.  A DOF without restoring force (a free gear floating in its backlash
for the whole period, a shaft in its bearing clearance) makes the orbit one of a family:
shifting that coordinate maps an orbit onto an orbit, so M v = v exactly and the
multiplier 1 is *trivial*.  :func:`neutral_directions` finds them (right vectors v, the
family's directions, and left vectors b spanning what M - I cannot reach) for the
shooting solver's phase condition; :func:`split_trivial` removes the trivial multipliers
before stability and the test functions are evaluated, so LP / PD / NS detection sees
only the multipliers that can cross the unit circle.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

__all__ = ["floquet_multipliers", "flip_vector", "liouville_error", "test_functions",
           "stability", "NEUTRAL_MARGIN", "neutral_directions", "split_trivial",
           "NEUTRAL_RTOL"]

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


#: a direction v with |(M - I) v| <= NEUTRAL_RTOL max(1, |M - I|) is neutral: the
#: variational equations map it onto itself up to round-off (a genuine fold or a multiplier
#: that merely passes near 1 is many orders of magnitude above this)
NEUTRAL_RTOL = 1e-9


def neutral_directions(monodromy: np.ndarray, omega2: np.ndarray | None = None,
                       rtol: float = NEUTRAL_RTOL) -> tuple[np.ndarray, np.ndarray]:
    """(V, B): orthonormal right null vectors V (n x k) of M - I that are neutral
    directions of the orbit family, and left null vectors B (n x k) of M - I (bordering
    columns: B is not in the range of M - I, V is the phase condition's normal).

    Structurally a neutral direction is a rigid shift: positions of modes without
    stiffness (``omega2`` = 0), velocities zero.  With ``omega2`` given, only that
    subspace is searched (a model without zero-frequency modes has none, at no cost);
    without it, any singular value of M - I at round-off relative to the largest counts.
    k = 0 gives empty (n x 0) arrays."""
    n = monodromy.shape[0]
    empty = np.zeros((n, 0))
    if omega2 is not None:
        w2 = np.abs(np.asarray(omega2, dtype=float))
        rigid = np.flatnonzero(w2 <= 1e-10 * max(float(np.max(w2, initial=0.0)), 1e-300))
        if rigid.size == 0:
            return empty, empty
    A = monodromy - np.eye(n)
    scale = max(1.0, float(np.linalg.norm(A)))      # Frobenius: >= the largest singular value
    if omega2 is not None:
        E = np.zeros((n, rigid.size))
        E[rigid, np.arange(rigid.size)] = 1.0
        _, s, vt = np.linalg.svd(A @ E)
        V = E @ vt[s <= rtol * scale].T if s.size else empty
    else:
        _, s, vt = np.linalg.svd(A)
        V = vt[s <= rtol * scale].T
    k = V.shape[1]
    if k == 0:
        return empty, empty
    # left null vectors: the last k columns of Q of a rank-revealing QR, A P = Q R (rank
    # n - k with a gap of many orders: they span the complement of A's range); a third of
    # the cost of the SVD's U
    q, _, _ = scipy.linalg.qr(A, pivoting=True)
    return V, q[:, n - k:]


def split_trivial(multipliers: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """(nontrivial, trivial): the ``k`` multipliers nearest 1 are the trivial ones of a
    ``k``-parameter orbit family (see :func:`neutral_directions`)."""
    mu = np.asarray(multipliers)
    if k <= 0:
        return mu, mu[:0]
    order = np.argsort(np.abs(mu - 1.0), kind="stable")
    keep = np.sort(order[k:])
    return mu[keep], mu[np.sort(order[:k])]


def stability(multipliers: np.ndarray, margin: float = NEUTRAL_MARGIN, trivial: int = 0) -> bool:
    """Asymptotically stable: every multiplier inside the unit circle by ``margin``, except
    the ``trivial`` multipliers 1 of an orbit family (orbital stability of the family)."""
    mu, _ = split_trivial(multipliers, trivial)
    return bool(np.all(np.abs(mu) < 1.0 - margin))


def test_functions(monodromy: np.ndarray, tangent: np.ndarray, trivial: int = 0,
                   multipliers: np.ndarray | None = None) -> dict:
    """LP / PD / NS test values (see the module docstring); the ``trivial`` multipliers 1
    of an orbit family are left out (they would flip the NS product at round-off).
    ``multipliers``: the monodromy's, where already computed."""
    if multipliers is None:
        multipliers = floquet_multipliers(monodromy)
    mu, _ = split_trivial(multipliers, trivial)
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
