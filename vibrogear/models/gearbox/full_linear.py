"""The full (non-reduced) linear gearbox: sparse block assembly, lowest modes, MAC pairing.

A reference for the accuracy of the modal synthesis (paper eqs. (4)-(7)): the subsystems'
full matrices (housing from :func:`.housing_run.housing_matrices`, free-free shafts, ...) are
concatenated block-diagonally and joined by rank-one springs k c c^T (bearing and mesh
stiffnesses linearised about an operating point), then the lowest modes of the assembled
system are compared with those of the reduced model by MAC.  numpy/scipy only.

Conventions: N = total DOF; block s occupies ``offsets[s]:offsets[s + 1]`` in the given order;
mode vectors are columns (N, m), mass-normalised (X^T M X = I), frequencies ascending in Hz.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["FullLinearModel", "assemble_full", "coupling_vector", "lowest_modes_full", "mac_matrix",
           "pair_modes"]


@dataclass(frozen=True, eq=False)
class FullLinearModel:
    """K, M (N, N) CSR, symmetric; D (N, N) CSR or None; ``offsets`` (n_blocks + 1,) int."""
    offsets: np.ndarray
    K: sp.csr_matrix
    M: sp.csr_matrix
    D: sp.csr_matrix | None = None

    @property
    def n_dofs(self) -> int:
        return int(self.offsets[-1])

    def block(self, s: int) -> slice:
        """The global DOF range of block ``s``."""
        return slice(int(self.offsets[s]), int(self.offsets[s + 1]))


def coupling_vector(c, n: int) -> sp.csc_matrix:
    """A coupling vector as an (n, 1) CSC column.  ``c``: a scipy sparse row (1, n) or column (n, 1),
    an ``(indices, values)`` pair over the global DOF, or a dense (n,) array."""
    if sp.issparse(c):
        if c.shape == (1, n):
            c = c.T
        if c.shape != (n, 1):
            raise ValueError(f"coupling vector of shape {c.shape}, expected (1, {n}) or ({n}, 1)")
        return sp.csc_matrix(c, dtype=float)
    if isinstance(c, tuple) and len(c) == 2:
        idx, val = np.atleast_1d(np.asarray(c[0], dtype=np.int64)), np.atleast_1d(np.asarray(c[1], dtype=float))
        if idx.shape != val.shape or (idx.size and (idx.min() < 0 or idx.max() >= n)):
            raise ValueError(f"(indices, values) coupling vector does not fit {n} DOF")
        return sp.csc_matrix((val, (idx, np.zeros_like(idx))), shape=(n, 1))
    arr = np.asarray(c, dtype=float).ravel()
    if arr.size != n:
        raise ValueError(f"dense coupling vector of length {arr.size}, expected {n}")
    return sp.csc_matrix(arr[:, None])


def assemble_full(blocks: Sequence[tuple], rank_one_terms: Sequence[tuple] = (), *,
                  damping_blocks: Sequence | None = None) -> FullLinearModel:
    """Block-diagonal K, M (and D) of the subsystems plus K += sum k c c^T.

    ``blocks``: (K_s, M_s) per subsystem (sparse or dense, square, equal sizes; K_s may be singular).
    ``rank_one_terms``: (c, k) or (c, k, d): coupling vector ``c`` (see :func:`coupling_vector`) over
    the concatenated DOF, stiffness ``k`` (K += k c c^T) and optional damping ``d`` (D += d c c^T).
    ``damping_blocks``: D_s per subsystem (None entries: zero), or None for no block damping.
    """
    if not blocks:
        raise ValueError("no blocks")
    sizes = []
    for s, (Ks, Ms) in enumerate(blocks):
        if Ks.shape != Ms.shape or Ks.shape[0] != Ks.shape[1]:
            raise ValueError(f"block {s}: K {Ks.shape} and M {Ms.shape} must be square and equal")
        sizes.append(Ks.shape[0])
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    n = int(offsets[-1])
    K = sp.block_diag([sp.csr_matrix(b[0], dtype=float) for b in blocks], format="csr")
    M = sp.block_diag([sp.csr_matrix(b[1], dtype=float) for b in blocks], format="csr")
    D = None
    if damping_blocks is not None:
        if len(damping_blocks) != len(blocks):
            raise ValueError(f"{len(damping_blocks)} damping blocks for {len(blocks)} blocks")
        D = sp.block_diag([sp.csr_matrix((m, m)) if Ds is None else sp.csr_matrix(Ds, dtype=float)
                           for Ds, m in zip(damping_blocks, sizes)], format="csr")
    if rank_one_terms:
        C = sp.hstack([coupling_vector(t[0], n) for t in rank_one_terms], format="csc")
        k = np.array([float(t[1]) for t in rank_one_terms])
        K = (K + C @ sp.diags(k) @ C.T).tocsr()
        d = np.array([float(t[2]) if len(t) > 2 else 0.0 for t in rank_one_terms])
        if np.any(d != 0.0):
            D = ((sp.csr_matrix((n, n)) if D is None else D) + C @ sp.diags(d) @ C.T).tocsr()
    return FullLinearModel(offsets=offsets, K=K, M=M, D=D)


def _normalise(X: np.ndarray, M) -> np.ndarray:
    """Mass-normalise the columns and make the largest-magnitude entry of each positive."""
    X = X / np.sqrt(np.einsum("ij,ij->j", X, M @ X))
    piv = np.abs(X).argmax(axis=0)
    return X * np.sign(X[piv, np.arange(X.shape[1])])


def lowest_modes_full(model: FullLinearModel, f_max_hz: float, max_count: int = 400, *,
                      shift_fraction: float = 1e-2, start: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """All modes of K x = omega^2 M x with f <= ``f_max_hz`` (at most ``max_count``).

    Shift-and-invert Lanczos (ARPACK) at sigma = -``shift_fraction`` (2 pi f_max)^2 < 0, so that
    K - sigma M is definite even where K is singular (rigid-body modes of an unsupported system);
    K - sigma M is factored once (SuperLU) and the number of requested modes doubles until one
    above the cut-off is found.  Dense ``eigh`` where the request reaches N - 1 (ARPACK's limit).
    Returns freqs_hz (m,) ascending (rigid-body modes: round-off lambda < 0 clipped to 0 Hz) and
    vectors (N, m), mass-normalised, largest entry positive.  Warns when ``max_count`` modes all lie
    below the cut-off."""
    if not f_max_hz > 0:
        raise ValueError(f"f_max_hz must be positive, got {f_max_hz}")
    K, M, n = model.K, model.M, model.n_dofs
    lam_cut = (2 * np.pi * f_max_hz) ** 2
    sigma = -shift_fraction * lam_cut
    k = min(start, max_count)
    lu = None
    while True:
        if k >= n - 1:
            lam, X = sla.eigh(K.toarray(), M.toarray())
            break
        if lu is None:
            lu = spla.splu(sp.csc_matrix(K - sigma * M))
            opinv = spla.LinearOperator((n, n), matvec=lu.solve, dtype=float)
        lam, X = spla.eigsh(K, k=k, M=M, sigma=sigma, which="LM", OPinv=opinv)
        if lam.max() > lam_cut or k >= max_count:
            break
        k = min(2 * k, max_count)
    order = np.argsort(lam)
    lam, X = lam[order], X[:, order]
    keep = np.flatnonzero(lam <= lam_cut)[:max_count]
    if keep.size == max_count and (lam.size == keep.size or lam[keep[-1] + 1] <= lam_cut):
        warnings.warn(f"max_count = {max_count} modes all lie below f_max = {f_max_hz:g} Hz", stacklevel=2)
    lam, X = lam[keep], X[:, keep]
    return np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi), _normalise(X, M)


def mac_matrix(phi_a: np.ndarray, phi_b: np.ndarray, weight=None) -> np.ndarray:
    """MAC_ij = |a_i^H W b_j|^2 / ((a_i^H W a_i)(b_j^H W b_j)), (m_a, m_b); columns are vectors
    (a 1-D array is one vector); W = I by default (sparse or dense, Hermitian positive)."""
    A = np.asarray(phi_a)
    B = np.asarray(phi_b)
    A = A[:, None] if A.ndim == 1 else A
    B = B[:, None] if B.ndim == 1 else B
    WB = B if weight is None else weight @ B
    WA = A if weight is None else weight @ A
    cross = A.conj().T @ WB
    na = np.real(np.einsum("ij,ij->j", A.conj(), WA))
    nb = np.real(np.einsum("ij,ij->j", B.conj(), WB))
    return np.abs(cross) ** 2 / np.outer(na, nb)


def pair_modes(freqs_ref: np.ndarray, vec_ref: np.ndarray, freqs: np.ndarray, vec: np.ndarray,
               weight=None, *, f_floor: float | None = None) -> list[tuple[int, int, float, float]]:
    """For each reference mode i, the candidate j of the largest MAC: [(i, j, mac, rel_freq_error)],
    rel_freq_error = (f_j - f_ref_i) / max(f_ref_i, f_floor) (signed; ``f_floor`` defaults to 1e-6 x
    the largest reference frequency, so rigid-body modes at ~0 Hz give an error relative to it).
    Several reference modes may pick the same candidate (degenerate pairs): check j if it matters."""
    fr, f = np.asarray(freqs_ref, dtype=float), np.asarray(freqs, dtype=float)
    mac = mac_matrix(vec_ref, vec, weight)
    floor = 1e-6 * (fr.max() if fr.size else 1.0) if f_floor is None else f_floor
    out = []
    for i in range(fr.size):
        j = int(np.argmax(mac[i]))
        out.append((i, j, float(mac[i, j]), float((f[j] - fr[i]) / max(fr[i], floor))))
    return out
