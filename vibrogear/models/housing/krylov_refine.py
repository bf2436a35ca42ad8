"""Rayleigh-Ritz on the block Krylov space of a previous variant's modes, and the fresh solve's
acceptance criterion (the housing geometry sweep's eigen-solve, :mod:`.sweep`).  Pure numpy:
the factor's solves and the distributed Gram products come in as functions."""
from __future__ import annotations

import numpy as np

__all__ = ["krylov_refine", "ritz_criterion"]


def ritz_criterion(Z: np.ndarray, AZ: np.ndarray, lam: np.ndarray, mdiag: np.ndarray, reduce=lambda a: a) -> np.ndarray:
    """SLEPc's criterion per Ritz pair, est_i = ||A z_i - z_i / lam_i||_M lam_i (A = K^-1 M, ``AZ`` =
    A Z, ``Z`` M-orthonormal columns, M = diag(``mdiag``)): some eigenvalue lambda of K x = lambda M x
    lies within |lam_i - lambda| <= est_i lambda (Weinstein's bound for the M-self-adjoint A at
    1 / lam_i).  ``reduce`` sums the local column sums over all processes."""
    D = AZ - Z / lam
    return np.sqrt(np.maximum(reduce(np.einsum("ij,ij->j", D, mdiag[:, None] * D)), 0.0)) * lam


def krylov_refine(X0: np.ndarray, *, solve, mdiag: np.ndarray, gram, nev: int, tol: float, max_blocks: int = 4,
                  reduce=lambda a: a):
    """The lowest modes of K x = lambda M x (M = diag(``mdiag``)) from approximate ones ``X0`` (n x p).

    Rayleigh-Ritz on a growing basis S = [Y_1, W_1, W_2, ..] with A = K^-1 M (``solve``(B) = K^-1 B,
    the variant's own factor): Y_1 = A X0, then W_j = A z for the wanted Ritz vectors z of span(S)
    not yet accepted.  Each such A z is exactly what the fresh solve's criterion (SLEPc's,
    :func:`ritz_criterion`) needs,

        est = ||A z - z / lambda||_M lambda <= tol   (||z||_M = 1),

    which puts an eigenvalue lambda_i within |lambda - lambda_i| <= est lambda_i; so the check of
    one basis is the next block, and a block has as many columns as pairs still missing ``tol``
    (the first: the ``nev`` wanted).  K is never multiplied: every block B of S has K B = M P with
    P known (X0 for Y_1, the Ritz vectors z for W_j), so both projected matrices are M-products,
    S^T K S = S^T M P, and all but the new block's M-products follow from the earlier ones.  A
    pair's bound carries over to the larger basis's pair of the same index: the Ritz values only
    fall, and stay above the eigenvalue of that index (Courant-Fischer), so the new one is at least
    as close.  The basis is M-orthonormalised by the eigen-decomposition of its Gram matrix scaled to
    a unit diagonal (directions below 1e-12 of the largest dropped).  ``gram``(A, B) = A^T B over all
    processes; ``reduce``: sums over all processes.  ``max_blocks``: blocks in S at most.

    Returns (lam (p,) ascending, Z (n x p, M-orthonormal), est (p,): each pair's bound (nan where none
    was computed), blocks in S, right-hand sides solved, Zp): K Z = M Zp for the first ``nev``
    columns, so the residual check needs no product with K."""
    import scipy.linalg as sla
    from scipy.linalg.blas import dgemm

    p = X0.shape[1]
    S = [solve(np.asfortranarray(mdiag[:, None] * X0))]     # Y_1 = A X0, K Y_1 = M X0
    P = [np.asfortranarray(X0)]
    n_rhs = p
    MS = mdiag[:, None] * S[0]
    Mg = reduce(S[0].T @ MS)                    # S^T M S
    Kg = gram(MS, P[0])                         # S^T K S = S^T M P
    del MS

    def times(blocks, C):                       # [B_1 B_2 ..] C, block by block, in place
        out, r = None, 0
        for B in blocks:
            out = dgemm(1.0, B, np.asfortranarray(C[r:r + B.shape[1]]), beta=0.0 if out is None else 1.0,
                        c=out, overwrite_c=True)
            r += B.shape[1]
        return out

    bound = np.full(p, np.inf)
    todo = np.arange(nev)
    while True:
        d = 1.0 / np.sqrt(np.diag(Mg))
        ev, U = np.linalg.eigh(0.5 * (Mg + Mg.T) * d[:, None] * d[None, :])
        keep = ev > 1e-12 * ev.max()
        T = d[:, None] * U[:, keep] / np.sqrt(ev[keep])
        lam, Q = sla.eigh(T.T @ (0.5 * (Kg + Kg.T)) @ T)
        lam, C = lam[:p], T @ Q[:, :p]          # z = S C, M-orthonormal
        Zt = times(S, C[:, todo])
        W = solve(np.asfortranarray(mdiag[:, None] * Zt))     # A z, K W = M z
        n_rhs += todo.size
        bound[todo] = np.minimum(bound[todo], ritz_criterion(Zt, W, lam[todo], mdiag, reduce))
        if np.all(bound[:nev] <= tol) or len(S) == max_blocks:
            break
        sel = np.nonzero(bound[todo] > tol)[0]
        todo, W, Zt, Cn = todo[sel], np.asfortranarray(W[:, sel]), Zt[:, sel], C[:, todo[sel]]
        # the new block's M-products: S^T M W and W^T M W; its K-products from them, K W = M S Cn
        MW = mdiag[:, None] * W
        SMW = np.vstack([gram(B, MW) for B in S])
        WMW = reduce(W.T @ MW)
        del MW
        Mg = np.block([[Mg, SMW], [SMW.T, WMW]])
        SKW = Mg[:-todo.size, :-todo.size] @ Cn             # S^T K W = S^T M S Cn
        WKW = SMW.T @ Cn                                   # W^T K W = W^T M S Cn
        Kg = np.block([[Kg, SKW], [SKW.T, 0.5 * (WKW + WKW.T)]])
        S.append(W)
        P.append(Zt)
    bound[~np.isfinite(bound)] = np.nan
    return lam, times(S, C), bound, len(S), n_rhs, times(P, C[:, :nev])
