"""Block Lanczos for the lowest modes of K x = lambda M x with a factorised K.

Pure numpy/scipy: the operators (K^-1 Y through the factorisation, M W, and the global
inner products) come in as callables, so the PETSc/MPI side stays in
:mod:`vibrogear.models.housing.fe`.  One pass through the factor serves a whole block of
right-hand sides, which is what makes it faster than single-vector Krylov-Schur here.
"""
from __future__ import annotations

import time

import numpy as np
import scipy.linalg as sla
from scipy.linalg.blas import dgemm

__all__ = ["Breakdown", "block_lanczos"]


class Breakdown(RuntimeError):
    """The block Lanczos basis lost rank or would exceed its size limit."""


def block_lanczos(n: int, *, solve, mmul, gram, want, max_dim: int, tol: float, block: int = 16,
                  smooth: int = 2, seed: int = 20261122, start: np.ndarray | None = None, extra: int = 0):
    """Block Lanczos for A = K^-1 M (self-adjoint in the M inner product), full two-pass block
    Gram-Schmidt reorthogonalisation, no restarts: the basis grows by one block per step until
    ``want(theta)`` says enough leading Ritz values theta = 1/lambda have converged, with SLEPc's
    criterion ||A x - theta x||_M / theta < tol.  The converged Ritz vectors then get one step of
    subspace iteration (x <- A x, Rayleigh-Ritz on (K, M)): it damps their high-frequency error by
    lambda_i / lambda_k, so ||K x - lambda M x|| / ||K x|| ends near tol, as with SLEPc.

    The operators come as callables on local rows (n of them): ``solve(Y)`` = K^-1 Y,
    ``mmul(W)`` = M W, ``gram(A, B)`` = A^T B summed over all processes.  ``seed`` seeds
    the random start block (add the process rank under MPI).

    ``start`` (local rows, n x b): the start block instead of a smoothed random one, e.g. the modes of
    a neighbouring problem (the housing sweep's previous variant); the block size is then its column
    count.  ``extra``: that many Ritz vectors beyond the ``want``-ed ones come back as well (not
    checked for convergence: a start block for the next problem).

    Returns (lam ascending, X local rows, statistics).  Raises Breakdown when the basis would
    exceed ``max_dim`` columns or loses rank."""
    stats = {"n_rhs": 0, "steps": 0, "t_solve": 0.0, "t_orth": 0.0, "t_mmul": 0.0}
    _solve, _mmul = solve, mmul

    def solve(Y):
        t = time.perf_counter()
        out = _solve(Y)
        stats["t_solve"] += time.perf_counter() - t
        stats["n_rhs"] += Y.shape[1]
        return out

    def mmul(W):
        t = time.perf_counter()
        out = _mmul(W)
        stats["t_mmul"] += time.perf_counter() - t
        return out

    def orthonormalize(W, Z):
        """M-orthonormalise W (Z = M W) by Cholesky-QR twice: W_in = W_out R."""
        R = np.eye(W.shape[1])
        for _ in range(2):
            G = gram(W, Z)
            G = 0.5 * (G + G.T)
            try:
                L = np.linalg.cholesky(G)
            except np.linalg.LinAlgError:
                try:
                    L = np.linalg.cholesky(G + 1e-14 * np.trace(G) * np.eye(len(G)))
                except np.linalg.LinAlgError:
                    raise Breakdown("block Lanczos basis lost rank") from None
            Li = sla.solve_triangular(L, np.eye(len(G)), lower=True)
            W, Z, R = W @ Li.T, Z @ Li.T, L.T @ R
        return W, Z, R

    b = block if start is None else start.shape[1]
    cap = b * (max_dim // b + 1)
    alloc = min(cap, 4 * b * 8)
    V = np.zeros((n, alloc + b), order="F")
    MV = np.zeros_like(V)
    H = np.zeros((cap + b, cap))
    if start is None:
        rng = np.random.default_rng(seed)
        W = rng.standard_normal((n, b))
        for _ in range(max(1, smooth)):        # into the range of A, and smoother
            W = solve(mmul(W))
    else:
        W = np.array(start, dtype=float, order="F")
    t = time.perf_counter()
    W, Z, _ = orthonormalize(W, mmul(W))
    stats["t_orth"] += time.perf_counter() - t
    V[:, :b], MV[:, :b] = W, Z
    j = 0
    while True:
        if j + 2 * b > V.shape[1]:                 # grow the basis storage
            extra = min(cap + b, 2 * V.shape[1]) - V.shape[1]
            V = np.concatenate([V, np.zeros((n, extra))], axis=1, dtype=float)
            V = np.asfortranarray(V)
            MV = np.asfortranarray(np.concatenate([MV, np.zeros((n, extra))], axis=1))
        W = np.asfortranarray(solve(MV[:, j:j + b]))  # A V_j
        t = time.perf_counter()
        for _ in range(2):                     # classical Gram-Schmidt, twice
            C = gram(MV[:, :j + b], W)
            W = dgemm(-1.0, V[:, :j + b], C, 1.0, W, overwrite_c=True)  # in place: 3x numpy's W -= V @ C
            H[:j + b, j:j + b] += C
        stats["t_orth"] += time.perf_counter() - t
        Z = mmul(W)
        t = time.perf_counter()
        W, Z, R = orthonormalize(W, Z)
        stats["t_orth"] += time.perf_counter() - t
        V[:, j + b:j + 2 * b], MV[:, j + b:j + 2 * b] = W, Z
        H[j + b:j + 2 * b, j:j + b] = R
        j += b
        stats["steps"] += 1
        T = H[:j, :j]
        theta, Y = np.linalg.eigh(0.5 * (T + T.T))
        theta, Y = theta[::-1].copy(), np.ascontiguousarray(Y[:, ::-1])
        est = np.linalg.norm(H[j:j + b, j - b:j] @ Y[j - b:j, :], axis=0) / np.abs(theta)
        nconv = int(np.argmin(est < tol)) if not np.all(est < tol) else len(est)
        k = want(theta[:nconv])
        if k is not None:
            break
        if j + b > max_dim:
            raise Breakdown(f"block Lanczos: {nconv} Ritz values converged in {j} basis vectors")
    stats["basis"] = j
    if k == 0:
        return np.zeros(0), np.zeros((n, 0), order="F"), stats
    k = min(k + extra, j)
    t = time.perf_counter()
    X = V[:, :j] @ Y[:, :k]
    del V, MV
    stats["t_orth"] += time.perf_counter() - t
    # one subspace-iteration step + Rayleigh-Ritz: K (A X) = M X, so Kp needs no K product
    MX = mmul(X)
    Xa = solve(MX)
    MXa = mmul(Xa)
    Kp, Mp = gram(Xa, MX), gram(Xa, MXa)
    lam, Q = sla.eigh(0.5 * (Kp + Kp.T), 0.5 * (Mp + Mp.T))
    return lam, np.asfortranarray(Xa @ Q), stats
