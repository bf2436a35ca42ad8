"""Compiled right-hand side of a ReducedModel, its Jacobian action and parameter derivative.

Everything works on a :data:`ModelArrays` named tuple (plain arrays) so that numba
compiles one loop for every model.  The linear part is modal diagonal + low-rank
coupling; contacts act on delta = C x - e(t).  The contact *mode* (-1, 0, +1) is
an input, not recomputed from the sign: the integrator switches it at located
events, so that every step sees one smooth vector field.

The contact force is the one law of :mod:`vibrogear.models.contact_law`, inlined.
The arrays and the structure they expose (single-entry rows of P, nonzero column ranges,
harmonic flags) are packed by :mod:`vibrogear.solvers.integrator.kernel_pack`; cos / sin of the
harmonics are computed once per call.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...models.contact_law import contact_force, contact_mode, resolve_mode
from .kernel_pack import ModelArrays, model_arrays

__all__ = ["ModelArrays", "model_arrays", "FAST", "accel", "contact_modes", "harmonics",
           "error_and_rate", "range_dot", "row_axpy", "project_coupling", "scatter_coupling"]

#: safe fast-math: reassociation (vectorised reductions) but no finite-math assumptions
FAST = {"reassoc", "contract", "arcp", "nsz"}


@njit(cache=True, inline="always", _nrt=False)
def harmonics(hmul, t, Om, cs, sn):
    """cs[h] = cos(n_h Om t), sn[h] = sin(n_h Om t), n_h = hmul[h] (the model's harmonic
    orders: 1, 2, ..., H unless an order is fractional)."""
    for h in range(cs.shape[0]):
        a = hmul[h] * Om * t
        cs[h] = np.cos(a)
        sn[h] = np.sin(a)


@njit(cache=True, inline="always", _nrt=False)
def error_and_rate(A, j, Om, cs, sn):
    """Kinematic error e_j(t) and its rate e_j'(t) from precomputed harmonics."""
    e = 0.0
    ed = 0.0
    for h in range(cs.shape[0]):
        w = A.hmul[h] * Om
        e += A.ec[j, h] * cs[h] + A.es[j, h] * sn[h]
        ed += w * (-A.ec[j, h] * sn[h] + A.es[j, h] * cs[h])
    return e, ed


# Index only with loop counters that start at 0 (range(n)) and slice for offsets:
# numba wraps negative indices, and an index it cannot prove non-negative (m + i,
# lo + i) keeps that select in the loop, which then does not vectorise.  Every loop
# over a slice lives in one of the small branch-free helpers below: a loop over slices
# taken inside a branch or a data-dependent loop of the caller does not vectorise
# (measured: 4-8x slower).

@njit(cache=True, inline="always", _nrt=False, fastmath=FAST)
def axpy_range(M, k, lo, hi, z, acc):
    """acc[lo:hi] -= z M[k, lo:hi]."""
    Mr = M[k, lo:hi]
    ac = acc[lo:hi]
    for i in range(hi - lo):
        ac[i] -= Mr[i] * z


@njit(cache=True, inline="always", _nrt=False, fastmath=FAST)
def range_dot(M, k, lo, hi, p):
    """M[k, lo:hi] . p[lo:hi]."""
    s = 0.0
    Mr = M[k, lo:hi]
    pr = p[lo:hi]
    for i in range(hi - lo):
        s += Mr[i] * pr[i]
    return s


@njit(cache=True, inline="always", _nrt=False, fastmath=FAST)
def _dot2x2(G, ga, gb, lo, hi, x, v):
    """(G[ga] . x, G[ga] . v, G[gb] . x, G[gb] . v) over [lo, hi): x, v loaded once."""
    G0 = G[ga, lo:hi]
    G1 = G[gb, lo:hi]
    X = x[lo:hi]
    V = v[lo:hi]
    a0 = 0.0
    a1 = 0.0
    b0 = 0.0
    b1 = 0.0
    for i in range(hi - lo):
        xi = X[i]
        vi = V[i]
        c0 = G0[i]
        c1 = G1[i]
        a0 += c0 * xi
        b0 += c0 * vi
        a1 += c1 * xi
        b1 += c1 * vi
    return a0, b0, a1, b1


@njit(cache=True, inline="always", _nrt=False, fastmath=FAST)
def rows_project(A, g0, g1, x, v, ox, ov):
    """ox[d] = G[g] . x, ov[d] = G[g] . v (d = gdst[g]) for the rows g0 <= g < g1 of G,
    over their nonzero column ranges, two rows per pass (an odd last row pairs with
    itself).  Branch-free for loop: a while loop or a branch around the pass measured
    up to 2x slower."""
    for p in range((g1 - g0 + 1) // 2):
        ga = g0 + 2 * p
        gb = min(ga + 1, g1 - 1)
        lo = min(A.glo[ga], A.glo[gb])
        hi = max(A.ghi[ga], A.ghi[gb])
        a0, b0, a1, b1 = _dot2x2(A.G, ga, gb, lo, hi, x, v)
        ox[A.gdst[ga]] = a0
        ov[A.gdst[ga]] = b0
        ox[A.gdst[gb]] = a1
        ov[A.gdst[gb]] = b1


@njit(cache=True, inline="always", _nrt=False, fastmath=FAST)
def row_axpy(A, g, z, acc):
    """acc -= z G[g] over the nonzero column range of row g of G."""
    axpy_range(A.G, g, A.glo[g], A.ghi[g], z, acc)


@njit(cache=True, inline="always", _nrt=False, fastmath=FAST)
def project_coupling(A, x, v, px, pv):
    """px = P x, pv = P v: single-entry rows of P by one product, dense rows through G."""
    r = A.P.shape[0]
    for k in range(r):
        if A.pg[k] < 0:
            c = A.pcol[k]
            px[k] = A.pval[k] * x[c]
            pv[k] = A.pval[k] * v[c]
    rows_project(A, A.C.shape[0], A.G.shape[0], x, v, px, pv)


@njit(cache=True, inline="always", _nrt=False, fastmath=FAST)
def scatter_coupling(A, WT, wlo, whi, Kc, Bc, klo, khi, blo, bhi, q, acc, scale):
    """acc -= scale * P^T (Kc px + Bc pv), q = [px; pv]: the low-rank linear coupling force.
    Single-entry rows of P: one axpy per nonzero q[l] with column l of WT (no reductions);
    dense rows of P: Kc, Bc row by row over their nonzero ranges, scattered through G."""
    r = A.P.shape[0]
    px = q[:r]
    pv = q[r:2 * r]
    for l in range(2 * r):
        z = q[l] * scale
        if z != 0.0:
            axpy_range(WT, l, wlo[l], whi[l], z, acc)
    for d in range(A.pdk.shape[0]):
        k = A.pdk[d]
        z = range_dot(Kc, k, klo[k], khi[k], px) + range_dot(Bc, k, blo[k], bhi[k], pv)
        z *= scale
        if z != 0.0:
            row_axpy(A, A.pg[k], z, acc)


@njit(cache=True)
def contact_modes(A, t, Om, x, mode):
    """Contact modes from the sign of delta - gap (used for the initial state only)."""
    H = A.Fc.shape[0]
    cs = np.empty(H)
    sn = np.empty(H)
    harmonics(A.hmul, t, Om, cs, sn)
    m = A.w2.shape[0]
    for j in range(A.C.shape[0]):
        d = 0.0
        for i in range(m):
            d += A.C[j, i] * x[i]
        e, _ = error_and_rate(A, j, Om, cs, sn)
        mode[j] = contact_mode(d - e, A.g_hi[j], A.g_lo[j])


@njit(cache=True, _nrt=False, fastmath=FAST)
def accel(t, y, mode, A, Om, cs, sn, out, Cx, Cv, kd, cd, tmp):
    """out[:m] = x', out[m:] = x'' at state y = [x, v] with contact modes ``mode``.

    Also fills Cx[j] = c_j . x, Cv[j] = c_j . v (raw projections), kd[j] = df_j/ddelta,
    cd[j] = df_j/ddelta' (0 out of contact), for the Jacobian and the dense output.
    ``tmp``: workspace of at least 2 r entries (r = rows of P).
    """
    m = A.w2.shape[0]
    harmonics(A.hmul, t, Om, cs, sn)    # once per call, shared by forcing and every contact
    H = cs.shape[0]
    x = y[:m]
    v = y[m:2 * m]
    acc = out[m:2 * m]
    w2 = A.w2
    damp = A.damp
    F0 = A.F0
    for i in range(m):
        out[i] = v[i]
        acc[i] = F0[i] - damp[i] * v[i] - w2[i] * x[i]
    for h in range(H):
        if A.fharm[h] != 0.0:
            c_ = cs[h]
            s_ = sn[h]
            Fc = A.Fc[h]
            Fs = A.Fs[h]
            for i in range(m):
                acc[i] += Fc[i] * c_ + Fs[i] * s_
    # projections c_j . x, c_j . v (rows of G over their nonzero ranges); the coupling
    # P x, P v: single-entry (identity) rows of P by one product, dense rows through G
    nc = A.C.shape[0]
    r = A.P.shape[0]
    rows_project(A, 0, nc, x, v, Cx, Cv)
    if r > 0:
        project_coupling(A, x, v, tmp[:r], tmp[r:2 * r])
        scatter_coupling(A, A.WT, A.wlo, A.whi, A.Kc, A.Bc, A.klo, A.khi, A.blo, A.bhi,
                         tmp[:2 * r], acc, 1.0)
    for j in range(nc):
        sx = Cx[j]
        sv = Cv[j]
        md = mode[j]
        if md == 0 and A.smooth[j] == 0.0:
            kd[j] = 0.0
            cd[j] = 0.0
            continue
        e, ed = error_and_rate(A, j, Om, cs, sn) if A.eharm[j] != 0.0 else (0.0, 0.0)
        delta = sx - e
        md = resolve_mode(md, A.smooth[j] != 0.0, delta, A.g_hi[j], A.g_lo[j])
        if md == 0:
            kd[j] = 0.0
            cd[j] = 0.0
            continue
        mod = 1.0
        if A.kharm[j] != 0.0:
            for h in range(H):
                mod += A.kmc[j, h] * cs[h] + A.kms[j, h] * sn[h]
        f, kdj, cdj = contact_force(md, delta, sv - ed, A.k_hi[j], A.k_lo[j], A.g_hi[j],
                                    A.g_lo[j], A.expo[j], A.cdamp[j], mod)
        kd[j] = kdj
        cd[j] = cdj
        if f != 0.0:
            row_axpy(A, j, f, acc)
