"""Variational equations of the compiled integrator: the Dormand-Prince step of the
tangent matrix Phi = [d u / d u0, d u / d param] with the stages of the state's accepted
step, and the saltation at contact switches.

The Jacobian acts through the model's structure (:mod:`vibrogear.solvers.integrator.jacobian`): by
BLAS on the selected rows of G for models where that pays (``use_blas``, decided by the
loop from the size), by loops otherwise.  The step combines the stages row by row (a row
of Phi and of each stage stays in L1 while it is used: the same operations per entry as
one whole-matrix axpy per stage, one pass over memory) and skips the last stage: b_6 = 0,
and with the FSAL tableau its Jacobian action would only be the first stage of the next
step, which recomputes it.
"""
from __future__ import annotations

from numba import njit

from .jacobian import accel_dparam, jac_times, jac_times_blas, row_axpy_1d
from .kernels import harmonics
from .tableau import DP_A, DP_B, DP_C

__all__ = ["BLAS_MIN_WORK", "variational_step", "saltation"]

#: the Jacobian action goes through BLAS from this many entries m (n + 1) of the tangent's
#: position half on (measured per J Phi, loops / BLAS: gear pair m = 34, 2346 entries, 26 /
#: 31 us; single stage m = 80, 12880 entries, 119 / 89 us; two stage m = 146, 1.35x)
BLAS_MIN_WORK = 4096


@njit(cache=True, _nrt=False, inline="always")
def _stage_input(s, h, Phi, KP, Ph):
    """Ph = Phi + h sum_{k < s} a_sk KP[k], row by row (the same operations per entry as
    one whole-matrix axpy per stage, so the same numbers, with one pass over memory)."""
    for i in range(Phi.shape[0]):
        phr = Ph[i]
        pir = Phi[i]
        for c in range(phr.shape[0]):
            phr[c] = pir[c]
        for k in range(s):
            a = h * DP_A[s, k]
            if a != 0.0:
                row_axpy_1d(a, KP[k, i], phr)


@njit(cache=True)
def variational_step(A, t, h_used, Om, dOm, dspin, mode, Phi, KP, Ph, Ys, kdS, cdS, cs, sn,
                     dfp, tmp, W, WS, use_blas, pcol):
    """Advance Phi (columns of [d u / d u0, d u / d param]; ``pcol``: the index of the
    parameter column in Phi, -1 if Phi does not hold it) with the stages of the accepted
    step (stage data Ys, kdS, cdS of the state's step; stage 6 is not needed: b_6 = 0)."""
    n = Phi.shape[0]
    for s in range(6):
        _stage_input(s, h_used, Phi, KP, Ph)
        if use_blas:
            jac_times_blas(Ph, mode, A, kdS[s], cdS[s], KP[s], WS)
        else:
            jac_times(Ph, mode, A, kdS[s], cdS[s], KP[s], W)
        if pcol >= 0:
            ts = t + DP_C[s] * h_used
            harmonics(A.hmul, ts, Om, cs, sn)
            accel_dparam(ts, Ys[s], mode, A, Om, dOm, dspin, cs, sn, kdS[s], cdS[s], dfp,
                         tmp)
            for i in range(n):
                KP[s, i, pcol] += dfp[i]
    for i in range(n):
        pir = Phi[i]
        for k in range(6):
            a = h_used * DP_B[k]
            if a != 0.0:
                row_axpy_1d(a, KP[k, i], pir)


@njit(cache=True, _nrt=False)
def saltation(A, j, t, Om, dOm, rate, f_new, f_old, Phi, cs, sn, pcol):
    """Phi += (f+ - f-) (c_j . Phi_x + d h / d param e_param) / rate at a switch of contact j
    (switching function h = c_j . x - e_j(t; Om) - gap, rate = dh/dt); ``pcol``: the
    parameter column of Phi (-1: none)."""
    m = A.w2.shape[0]
    n = Phi.shape[0]
    ncol = Phi.shape[1]
    harmonics(A.hmul, t, Om, cs, sn)
    # d h / d param at fixed (t, x)
    dh = 0.0
    for hh in range(cs.shape[0]):
        nn = A.hmul[hh]
        dh -= nn * t * (-A.ec[j, hh] * sn[hh] + A.es[j, hh] * cs[hh])
    dh *= dOm
    for c in range(ncol):
        g = 0.0
        for i in range(m):
            g += A.C[j, i] * Phi[i, c]
        if c == pcol:
            g += dh
        g /= rate
        for i in range(n):
            Phi[i, c] += (f_new[i] - f_old[i]) * g
