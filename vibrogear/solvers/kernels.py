"""Compiled right-hand side of a ReducedModel, its Jacobian action and parameter derivative.

Everything works on a :data:`ModelArrays` named tuple (plain arrays) so that numba
compiles one loop for every model.  The linear part is modal diagonal + low-rank
coupling; contacts act on delta = C x - e(t).  The contact *mode* (-1, 0, +1) is
an input, not recomputed from the sign: the integrator switches it at located
events, so that every step sees one smooth vector field.
"""
from __future__ import annotations

import weakref
from collections import namedtuple

import numpy as np
from numba import njit

__all__ = ["ModelArrays", "model_arrays", "FAST", "effective_mode", "accel", "jac_times", "accel_dparam",
           "contact_modes", "harmonics", "error_and_rate"]

ModelArrays = namedtuple("ModelArrays", [
    "w2", "damp", "P", "Kc", "Bc", "Kc1", "Bc1", "F0", "Fc", "Fs",
    "C", "k_hi", "k_lo", "g_hi", "g_lo", "expo", "cdamp", "kmc", "kms", "ec", "es", "smooth",
    "harm", "Ct", "Pt",
])

#: safe fast-math: reassociation (vectorised reductions) but no finite-math assumptions
FAST = {"reassoc", "contract", "arcp", "nsz"}


_STATIC: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def model_arrays(model, param: float) -> tuple:
    """Pack ``model`` at ``param`` into ModelArrays plus (Omega, spin, dOmega/dp, dspin/dp).

    The parameter-free arrays are packed once per model (models are immutable) and reused."""
    arrs = _STATIC.get(model)
    if arrs is None:
        arrs = _STATIC[model] = _pack(model)
    spin = model.spin_per_param * param
    cp = model.coupling
    if spin != 0.0 and cp.P.shape[0]:
        arrs = arrs._replace(Kc=np.ascontiguousarray(cp.Kc0 + spin * cp.Kc1, dtype=np.float64),
                             Bc=np.ascontiguousarray(cp.Bc0 + spin * cp.Bc1, dtype=np.float64))
    return arrs, model.omega_per_param * param, spin, model.omega_per_param, model.spin_per_param


def _pack(model) -> tuple:
    cp, fo, ct = model.coupling, model.forcing, model.contacts
    f64 = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731
    return ModelArrays(
        f64(model.omega2), f64(model.damping), f64(cp.P), f64(cp.Kc0), f64(cp.Bc0),
        f64(cp.Kc1), f64(cp.Bc1),
        f64(fo.F0), f64(fo.Fc), f64(fo.Fs),
        f64(ct.directions), f64(ct.k_hi), f64(ct.k_lo), f64(ct.gap_hi), f64(ct.gap_lo),
        f64(ct.exponent), f64(ct.damping), f64(ct.stiffness_cos), f64(ct.stiffness_sin),
        f64(ct.error_cos), f64(ct.error_sin),
        # C1 contacts (Hertzian exponent > 1, no damping) switch without located events
        f64((ct.exponent > 1.0) & (ct.damping == 0.0)),
        # contacts with mesh-stiffness or transmission-error harmonics
        f64(np.any(np.hstack([ct.stiffness_cos, ct.stiffness_sin, ct.error_cos,
                              ct.error_sin]) != 0.0, axis=1) if ct.count else np.zeros(0)),
        f64(ct.directions.T), f64(cp.P.T),     # column-wise copies for the projections
    )


@njit(cache=True, inline="always", _nrt=False)
def harmonics(t, Om, cs, sn):
    """cs[h] = cos((h+1) Om t), sn[h] = sin((h+1) Om t)."""
    for h in range(cs.shape[0]):
        a = (h + 1) * Om * t
        cs[h] = np.cos(a)
        sn[h] = np.sin(a)


@njit(cache=True, inline="always", _nrt=False)
def error_and_rate(A, j, Om, cs, sn):
    """Kinematic error e_j(t) and its rate e_j'(t) from precomputed harmonics."""
    e = 0.0
    ed = 0.0
    for h in range(cs.shape[0]):
        w = (h + 1) * Om
        e += A.ec[j, h] * cs[h] + A.es[j, h] * sn[h]
        ed += w * (-A.ec[j, h] * sn[h] + A.es[j, h] * cs[h])
    return e, ed


@njit(cache=True, inline="always", _nrt=False)
def power(s, p):
    """s**p for s > 0, with the common contact exponents done without pow()."""
    if p == 1.5:
        return s * np.sqrt(s)
    if p == 2.0:
        return s * s
    return np.exp(p * np.log(s))


@njit(cache=True, inline="always", _nrt=False, fastmath=FAST)
def project(Mt, y, px, pv):
    """px = Mt^T y[:m], pv = Mt^T y[m:] for Mt (m x k), column-wise (vectorises)."""
    m = Mt.shape[0]
    k = Mt.shape[1]
    for j in range(k):
        px[j] = 0.0
        pv[j] = 0.0
    for i in range(m):
        xi = y[i]
        vi = y[m + i]
        for j in range(k):
            c = Mt[i, j]
            px[j] += c * xi
            pv[j] += c * vi


@njit(cache=True, inline="always", _nrt=False, fastmath=FAST)
def scatter_coupling(A, Kc, Bc, px, pv, out, scale):
    """out[m:] -= scale * P^T (Kc px + Bc pv): the low-rank linear coupling force."""
    m = A.w2.shape[0]
    r = A.P.shape[0]
    for k in range(r):
        z = 0.0
        for l in range(r):
            z += Kc[k, l] * px[l] + Bc[k, l] * pv[l]
        z *= scale
        if z != 0.0:
            for i in range(m):
                out[m + i] -= A.P[k, i] * z


@njit(cache=True, inline="always", _nrt=False)
def effective_mode(A, j, delta):
    """Contact mode from the sign of delta - gap."""
    if delta > A.g_hi[j]:
        return 1
    if delta < A.g_lo[j]:
        return -1
    return 0


@njit(cache=True)
def contact_modes(A, t, Om, x, mode):
    """Contact modes from the sign of delta - gap (used for the initial state only)."""
    H = A.Fc.shape[0]
    cs = np.empty(H)
    sn = np.empty(H)
    harmonics(t, Om, cs, sn)
    m = A.w2.shape[0]
    for j in range(A.C.shape[0]):
        d = 0.0
        for i in range(m):
            d += A.C[j, i] * x[i]
        e, _ = error_and_rate(A, j, Om, cs, sn)
        d -= e
        if d > A.g_hi[j]:
            mode[j] = 1
        elif d < A.g_lo[j]:
            mode[j] = -1
        else:
            mode[j] = 0


@njit(cache=True, _nrt=False, fastmath=FAST)
def accel(t, y, mode, A, Om, cs, sn, out, Cx, Cv, kd, cd, tmp):
    """out[:m] = x', out[m:] = x'' at state y = [x, v] with contact modes ``mode``.

    Also fills Cx[j] = c_j . x, Cv[j] = c_j . v (raw projections), kd[j] = df_j/ddelta,
    cd[j] = df_j/ddelta' (0 out of contact), for the Jacobian and the dense output.
    """
    m = A.w2.shape[0]
    harmonics(t, Om, cs, sn)
    H = cs.shape[0]
    for i in range(m):
        out[i] = y[m + i]
        out[m + i] = A.F0[i] - A.damp[i] * y[m + i] - A.w2[i] * y[i]
    for h in range(H):
        c_ = cs[h]
        s_ = sn[h]
        for i in range(m):
            out[m + i] += A.Fc[h, i] * c_ + A.Fs[h, i] * s_
    # projections c_j . x, c_j . v, p_k . x, p_k . v in one column-wise pass each
    # (vectorises without reductions; the row-wise scatter below uses C and P)
    nc = A.C.shape[0]
    r = A.P.shape[0]
    project(A.Ct, y, Cx, Cv)
    if r > 0:
        project(A.Pt, y, tmp[:r], tmp[r:2 * r])
        scatter_coupling(A, A.Kc, A.Bc, tmp[:r], tmp[r:2 * r], out, 1.0)
    for j in range(nc):
        sx = Cx[j]
        sv = Cv[j]
        md = mode[j]
        if md == 0 and A.smooth[j] == 0.0:
            kd[j] = 0.0
            cd[j] = 0.0
            continue
        e, ed = error_and_rate(A, j, Om, cs, sn) if A.harm[j] != 0.0 else (0.0, 0.0)
        if A.smooth[j] != 0.0:
            md = effective_mode(A, j, sx - e)
            if md == 0:
                kd[j] = 0.0
                cd[j] = 0.0
                continue
        mod = 1.0
        if A.harm[j] != 0.0:
            for h in range(H):
                mod += A.kmc[j, h] * cs[h] + A.kms[j, h] * sn[h]
        delta = sx - e
        ddot = sv - ed
        if md > 0:
            sgn = 1.0
            s = delta - A.g_hi[j]
            kt = A.k_hi[j] * mod
        else:
            sgn = -1.0
            s = A.g_lo[j] - delta
            kt = A.k_lo[j] * mod
        p = A.expo[j]
        if p == 1.0:
            f = sgn * kt * s
            kd[j] = kt
        elif s > 0.0:
            fs = kt * power(s, p)
            f = sgn * fs
            kd[j] = p * fs / s
        else:
            f = 0.0
            kd[j] = 0.0
        f += A.cdamp[j] * ddot
        cd[j] = A.cdamp[j]
        if f != 0.0:
            for i in range(m):
                out[m + i] -= A.C[j, i] * f


@njit(cache=True, _nrt=False, inline="always", fastmath=FAST)
def jac_times(Phi, mode, A, kd, cd, out, tmp):
    """out = J Phi for the Jacobian J at a state whose kd, cd were filled by ``accel``."""
    m = A.w2.shape[0]
    ncol = Phi.shape[1]
    for i in range(m):
        for c in range(ncol):
            out[i, c] = Phi[m + i, c]
            out[m + i, c] = -A.w2[i] * Phi[i, c] - A.damp[i] * Phi[m + i, c]
    r = A.P.shape[0]
    if r > 0:
        for c in range(ncol):
            project(A.Pt, Phi[:, c], tmp[:r], tmp[r:2 * r])
            scatter_coupling(A, A.Kc, A.Bc, tmp[:r], tmp[r:2 * r], out[:, c], 1.0)
    for j in range(A.C.shape[0]):
        if kd[j] == 0.0 and cd[j] == 0.0:
            continue
        for c in range(ncol):
            sx = 0.0
            sv = 0.0
            for i in range(m):
                sx += A.C[j, i] * Phi[i, c]
                sv += A.C[j, i] * Phi[m + i, c]
            z = kd[j] * sx + cd[j] * sv
            if z != 0.0:
                for i in range(m):
                    out[m + i, c] -= A.C[j, i] * z


@njit(cache=True, _nrt=False, inline="always", fastmath=FAST)
def accel_dparam(t, y, mode, A, Om, dOm, dspin, cs, sn, kd, cd, out, tmp):
    """out = d f / d param at fixed (t, y): forcing, transmission error, mesh stiffness, spin."""
    m = A.w2.shape[0]
    H = cs.shape[0]
    for i in range(2 * m):
        out[i] = 0.0
    if dOm != 0.0:
        for h in range(H):
            w = (h + 1) * t * dOm
            for i in range(m):
                out[m + i] += w * (-A.Fc[h, i] * sn[h] + A.Fs[h, i] * cs[h])
    r = A.P.shape[0]
    if r > 0 and dspin != 0.0:
        # projections once (not once per row of Kc1): O(r m), not O(r^2 m)
        project(A.Pt, y, tmp[:r], tmp[r:2 * r])
        scatter_coupling(A, A.Kc1, A.Bc1, tmp[:r], tmp[r:2 * r], out, dspin)
    if dOm == 0.0:
        return
    for j in range(A.C.shape[0]):
        md = mode[j]
        if A.smooth[j] != 0.0:
            sx = 0.0
            for i in range(m):
                sx += A.C[j, i] * y[i]
            e = 0.0
            for h in range(H):
                e += A.ec[j, h] * cs[h] + A.es[j, h] * sn[h]
            md = effective_mode(A, j, sx - e)
        if md == 0:
            continue
        de = 0.0     # d e / d Om
        ded = 0.0    # d e' / d Om
        dmod = 0.0   # d mod / d Om
        mod = 1.0
        for h in range(H):
            n = h + 1
            w = n * Om
            s_ = -A.ec[j, h] * sn[h] + A.es[j, h] * cs[h]
            c_ = -A.ec[j, h] * cs[h] - A.es[j, h] * sn[h]
            de += n * t * s_
            ded += n * s_ + w * n * t * c_
            dmod += n * t * (-A.kmc[j, h] * sn[h] + A.kms[j, h] * cs[h])
            mod += A.kmc[j, h] * cs[h] + A.kms[j, h] * sn[h]
        # stiffness force / k(t), to differentiate the modulation
        sx = 0.0
        for i in range(m):
            sx += A.C[j, i] * y[i]
        e = 0.0
        for h in range(H):
            e += A.ec[j, h] * cs[h] + A.es[j, h] * sn[h]
        delta = sx - e
        p = A.expo[j]
        if md > 0:
            s = delta - A.g_hi[j]
            fk = A.k_hi[j] * (s if p == 1.0 else (power(s, p) if s > 0 else 0.0))
        else:
            s = A.g_lo[j] - delta
            fk = -A.k_lo[j] * (s if p == 1.0 else (power(s, p) if s > 0 else 0.0))
        df = fk * dmod - kd[j] * de - cd[j] * ded
        df *= dOm
        if df != 0.0:
            for i in range(m):
                out[m + i] -= A.C[j, i] * df
