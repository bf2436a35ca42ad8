"""The Jacobian action J Phi of a ReducedModel's right-hand side on a tangent matrix and
the parameter derivative d f / d param, for the variational equations.

The Jacobian is applied through the model's structure, never as a dense matrix: modal
diagonal, the low-rank coupling P^T (Kc P Phi_x + Bc P Phi_v) (single-entry rows of P by
one product, dense rows through G) and one rank-1 term per active contact (kd, cd from
the state's stage).  Every product runs along the contiguous rows of Phi (length n + 1).
Two implementations of the same products: :func:`jac_times` (loops; for small models,
where a BLAS call costs more than the product) and :func:`jac_times_blas` (the rank-k
projections and their scatter as dgemm on the selected rows of G: 1.3-1.4x faster on
the two-stage gearbox, m = 146-162).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...models.contact_law import contact_force, resolve_mode
from .kernels import FAST, project_coupling, range_dot, row_axpy, scatter_coupling

__all__ = ["jac_workspace", "jac_times", "jac_blas_workspace", "jac_times_blas", "accel_dparam",
           "row_axpy_1d"]


@njit(cache=True, _nrt=False, inline="always", fastmath=FAST)
def row_axpy_1d(a, x, y):
    """y += a x for one row."""
    for c in range(x.shape[0]):
        y[c] += a * x[c]


@njit(cache=True, _nrt=False, inline="always", fastmath=FAST)
def _rows_combine(M, k, lo, hi, Q, z):
    """z += sum_l M[k, l] Q[l] over the nonzeros of M[k, lo:hi] (rows of Q contiguous)."""
    Mr = M[k, lo:hi]
    Qs = Q[lo:hi]
    ncol = z.shape[0]
    for l in range(hi - lo):
        w = Mr[l]
        if w != 0.0:
            q = Qs[l]
            for c in range(ncol):
                z[c] += w * q[c]


@njit(cache=True, _nrt=False, inline="always", fastmath=FAST)
def _rows_scatter(A, g, OV, z):
    """OV[i] -= G[g, i] z over the nonzeros of row g of G (rows of OV contiguous)."""
    lo = A.glo[g]
    hi = A.ghi[g]
    Gr = A.G[g, lo:hi]
    OVs = OV[lo:hi]
    ncol = z.shape[0]
    for i in range(hi - lo):
        w = Gr[i]
        if w != 0.0:
            o = OVs[i]
            for c in range(ncol):
                o[c] -= w * z[c]


def jac_workspace(A, ncol: int) -> np.ndarray:
    """Workspace for :func:`jac_times` on ``ncol`` columns."""
    return np.empty((3 * A.P.shape[0] + 1, ncol))


@njit(cache=True, _nrt=False, inline="always", fastmath=FAST)
def _modal_part(X, V, OX, OV, w2, damp):
    """The modal diagonal of J Phi: OX = V, OV = -w2 X - damp V (row by row)."""
    for i in range(w2.shape[0]):
        a = w2[i]
        b = damp[i]
        xi = X[i]
        vi = V[i]
        oxi = OX[i]
        ovi = OV[i]
        for c in range(X.shape[1]):
            oxi[c] = vi[c]
            ovi[c] = -a * xi[c] - b * vi[c]


@njit(cache=True, _nrt=False, fastmath=FAST)
def jac_times(Phi, mode, A, kd, cd, out, W):
    """out = J Phi for the Jacobian J at a state whose kd, cd were filled by ``accel``.

    Phi, out: (2 m, ncol) C-contiguous; every product runs along the contiguous rows
    (length ncol).  W: workspace of shape (3 r + 1, ncol) (:func:`jac_workspace`)."""
    m = A.w2.shape[0]
    ncol = Phi.shape[1]
    X = Phi[:m]
    V = Phi[m:2 * m]
    OX = out[:m]
    OV = out[m:2 * m]
    _modal_part(X, V, OX, OV, A.w2, A.damp)
    r = A.P.shape[0]
    if r > 0:
        QX = W[:r]
        QV = W[r:2 * r]
        Z = W[2 * r:3 * r]
        # Q = P Phi
        for k in range(r):
            qx = QX[k]
            qv = QV[k]
            g = A.pg[k]
            if g < 0:
                val = A.pval[k]
                xc = X[A.pcol[k]]
                vc = V[A.pcol[k]]
                for c in range(ncol):
                    qx[c] = val * xc[c]
                    qv[c] = val * vc[c]
                continue
            for c in range(ncol):
                qx[c] = 0.0
                qv[c] = 0.0
            lo = A.glo[g]
            hi = A.ghi[g]
            Gr = A.G[g, lo:hi]
            Xs = X[lo:hi]
            Vs = V[lo:hi]
            for i in range(hi - lo):
                w = Gr[i]
                if w != 0.0:
                    xi = Xs[i]
                    vi = Vs[i]
                    for c in range(ncol):
                        qx[c] += w * xi[c]
                        qv[c] += w * vi[c]
        # out[m:] -= P^T (Kc QX + Bc QV)
        for k in range(r):
            z = Z[k]
            for c in range(ncol):
                z[c] = 0.0
            _rows_combine(A.Kc, k, A.klo[k], A.khi[k], QX, z)
            _rows_combine(A.Bc, k, A.blo[k], A.bhi[k], QV, z)
            g = A.pg[k]
            if g < 0:
                val = A.pval[k]
                if val != 0.0:
                    o = OV[A.pcol[k]]
                    for c in range(ncol):
                        o[c] -= val * z[c]
                continue
            _rows_scatter(A, g, OV, z)
    S = W[3 * r]
    for j in range(A.C.shape[0]):
        a = kd[j]
        b = cd[j]
        if a == 0.0 and b == 0.0:
            continue
        lo = A.glo[j]
        hi = A.ghi[j]
        Gr = A.G[j, lo:hi]
        Xs = X[lo:hi]
        Vs = V[lo:hi]
        for c in range(ncol):
            S[c] = 0.0
        for i in range(hi - lo):
            w = Gr[i]
            if w != 0.0:
                xi = Xs[i]
                if b == 0.0:
                    wa = w * a
                    for c in range(ncol):
                        S[c] += wa * xi[c]
                else:
                    vi = Vs[i]
                    wa = w * a
                    wb = w * b
                    for c in range(ncol):
                        S[c] += wa * xi[c] + wb * vi[c]
        _rows_scatter(A, j, OV, S)


@njit(cache=True, _nrt=False, inline="always", fastmath=FAST)
def accel_dparam(t, y, mode, A, Om, dOm, dspin, cs, sn, kd, cd, out, tmp):
    """out = d f / d param at fixed (t, y): forcing, transmission error, mesh stiffness, spin."""
    m = A.w2.shape[0]
    H = cs.shape[0]
    x = y[:m]
    v = y[m:2 * m]
    acc = out[m:2 * m]
    for i in range(2 * m):
        out[i] = 0.0
    if dOm != 0.0:
        for h in range(H):
            if A.fharm[h] == 0.0:
                continue
            w = A.hmul[h] * t * dOm
            Fc = A.Fc[h]
            Fs = A.Fs[h]
            c_ = cs[h]
            s_ = sn[h]
            for i in range(m):
                acc[i] += w * (-Fc[i] * s_ + Fs[i] * c_)
    r = A.P.shape[0]
    if r > 0 and dspin != 0.0:
        # projections once (not once per row of Kc1): O(r m), not O(r^2 m)
        project_coupling(A, x, v, tmp[:r], tmp[r:2 * r])
        scatter_coupling(A, A.W1T, A.w1lo, A.w1hi, A.Kc1, A.Bc1, A.k1lo, A.k1hi, A.b1lo, A.b1hi,
                         tmp[:2 * r], acc, dspin)
    if dOm == 0.0:
        return
    for j in range(A.C.shape[0]):
        md = mode[j]
        sx = range_dot(A.G, j, A.glo[j], A.ghi[j], x)
        e = 0.0
        for h in range(H):
            e += A.ec[j, h] * cs[h] + A.es[j, h] * sn[h]
        md = resolve_mode(md, A.smooth[j] != 0.0, sx - e, A.g_hi[j], A.g_lo[j])
        if md == 0:
            continue
        de = 0.0     # d e / d Om
        ded = 0.0    # d e' / d Om
        dmod = 0.0   # d mod / d Om
        for h in range(H):
            n = A.hmul[h]
            w = n * Om
            s_ = -A.ec[j, h] * sn[h] + A.es[j, h] * cs[h]
            c_ = -A.ec[j, h] * cs[h] - A.es[j, h] * sn[h]
            de += n * t * s_
            ded += n * s_ + w * n * t * c_
            dmod += n * t * (-A.kmc[j, h] * sn[h] + A.kms[j, h] * cs[h])
        # stiffness force / k(t) (no modulation, no damping), to differentiate the modulation
        fk = contact_force(md, sx - e, 0.0, A.k_hi[j], A.k_lo[j], A.g_hi[j], A.g_lo[j],
                           A.expo[j], 0.0, 1.0)[0]
        df = fk * dmod - kd[j] * de - cd[j] * ded
        df *= dOm
        if df != 0.0:
            row_axpy(A, j, df, acc)


@njit(cache=True)
def jac_blas_workspace(A, ncol):
    """Workspaces of :func:`jac_times_blas` on ``ncol`` columns: (selected rows of G, their
    X and V projections, coupling forces by row of P, contact / coupling forces by selected
    row, the scattered product)."""
    m = A.w2.shape[0]
    ng = A.G.shape[0]
    r = A.P.shape[0]
    return (np.empty((ng, m)), np.empty((ng, ncol)), np.empty((ng, ncol)), np.empty((r, ncol)),
            np.empty((ng, ncol)), np.empty((m, ncol)), np.empty(ng, np.int64),
            np.empty(ng, np.int64), np.empty((ng, m)))


@njit(cache=True, fastmath=FAST)
def jac_times_blas(Phi, mode, A, kd, cd, out, WS):
    """out = J Phi (as :func:`jac_times`), the rank-k products by BLAS (dgemm): the X
    projections on the dense rows of P and the active contacts, the V projections on
    the dense rows of P and the damped active contacts, and the scatter of their forces;
    the single-entry rows of P and the sparse Kc, Bc as in :func:`jac_times`.  Same
    numbers up to round-off (the sums run in BLAS's order)."""
    Gs, YX, YV, ZP, ZS, T, sel, vsel, Gv = WS
    m = A.w2.shape[0]
    ncol = Phi.shape[1]
    X = Phi[:m]
    V = Phi[m:2 * m]
    OX = out[:m]
    OV = out[m:2 * m]
    _modal_part(X, V, OX, OV, A.w2, A.damp)
    r = A.P.shape[0]
    nc = A.C.shape[0]
    # rows of G taking part: the dense rows of P, then the active contacts
    na = 0
    nb = 0
    for d in range(A.pdk.shape[0]):
        sel[na] = A.pg[A.pdk[d]]
        na += 1
    npd = na
    for d in range(npd):
        vsel[nb] = sel[d]
        nb += 1
    for j in range(nc):
        if kd[j] != 0.0 or cd[j] != 0.0:
            sel[na] = j
            na += 1
            if cd[j] != 0.0:
                vsel[nb] = j
                nb += 1
    if na == 0 and r == 0:
        return
    for a in range(na):
        Gs[a] = A.G[sel[a]]
    for a in range(nb):
        Gv[a] = A.G[vsel[a]]
    if na > 0:
        np.dot(Gs[:na], X, YX[:na])
    if nb > 0:
        np.dot(Gv[:nb], V, YV[:nb])
    # coupling forces ZP[k] = sum_l Kc[k, l] QX[l] + Bc[k, l] QV[l]
    for k in range(r):
        z = ZP[k]
        for c in range(ncol):
            z[c] = 0.0
    for k in range(r):
        z = ZP[k]
        for l in range(A.klo[k], A.khi[k]):
            w = A.Kc[k, l]
            if w != 0.0:
                _acc_q(w, l, A, X, YX, z, True)
        for l in range(A.blo[k], A.bhi[k]):
            w = A.Bc[k, l]
            if w != 0.0:
                _acc_q(w, l, A, V, YV, z, False)
    # single-entry rows of P scatter directly; dense rows through the selected rows
    for k in range(r):
        if A.pg[k] < 0:
            val = A.pval[k]
            if val != 0.0:
                row_axpy_1d(-val, ZP[k], OV[A.pcol[k]])
    for d in range(npd):
        ZS[d] = ZP[A.pdk[d]]
    b = npd
    for a in range(npd, na):
        j = sel[a]
        zs = ZS[a]
        yx = YX[a]
        kj = kd[j]
        for c in range(ncol):
            zs[c] = kj * yx[c]
        if cd[j] != 0.0:
            row_axpy_1d(cd[j], YV[b], zs)
            b += 1
    if na > 0:
        np.dot(Gs[:na].T, ZS[:na], T)
        for i in range(m):
            row_axpy_1d(-1.0, T[i], OV[i])


@njit(cache=True, _nrt=False, inline="always", fastmath=FAST)
def _acc_q(w, l, A, X, Y, z, is_x):
    """z += w Q[l], Q = P X: row l of P single-entry (one scaled row of X) or dense (its
    projection: row pg[l] - nc of Y, the dense rows of P coming first in the selection,
    in pdk order)."""
    g = A.pg[l]
    if g < 0:
        src = X[A.pcol[l]]
        wv = w * A.pval[l]
        for c in range(z.shape[0]):
            z[c] += wv * src[c]
    else:
        src = Y[g - A.C.shape[0]]
        for c in range(z.shape[0]):
            z[c] += w * src[c]
