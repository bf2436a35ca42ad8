"""Compiled adaptive Dormand-Prince 5(4) loop with dense output, contact events and
variational equations (monodromy + parameter sensitivity) with saltation matrices.

The loop runs entirely in numba.  Contact modes switch only at located events:
after an accepted step the switching functions are sampled on the dense output; the
earliest crossing is located by bisection on the interpolant and the step is retaken
to end exactly there, so each step integrates one smooth vector field and the method
keeps its order.  All loops are bounded (max_steps, max consecutive events).

The once-per-step helpers (event search, dense output, extrema, tangent step, saltation)
are compiled functions of their own, not inlined into the loop: the first compilation
took 53 s with them inlined, 22 s without, at the same run time and the same numbers.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import njit

from .dense_output import dense_eval, event_search, monitor_extrema
from .kernels import FAST, accel, contact_modes, error_and_rate, harmonics, range_dot
from .tableau import DP_A as _A
from .tableau import DP_C as _C
from .tableau import DP_E as _E
from .jacobian import jac_blas_workspace
from .variational import BLAS_MIN_WORK, saltation, variational_step

__all__ = ["dopri_loop", "loop_inputs", "LoopResult", "JAC_AUTO", "JAC_LOOPS", "JAC_BLAS"]

# status codes returned by the loop (numba has no enums): the values of the integrator
# members of vibrogear.status.Status, which maps them (from_code)
_OK, _MAX_STEPS, _NONFINITE, _CHATTERING, _STEP_TOO_SMALL, _GRAZING = 0, -1, -2, -3, -4, -5

PI_BETA = 0.08  # PI step-size controller


@njit(cache=True, _nrt=False, inline="always", fastmath=FAST)
def _axpy1(a, x, y):
    """y += a x (a branch-free helper: loops written inside a branch of the caller do not
    always vectorise)."""
    for i in range(x.shape[0]):
        y[i] += a * x[i]


@njit(cache=True, _nrt=False, fastmath=FAST)
def _stages(t, y, h, K, Ys, mode, A, Om, cs, sn, CxS, CvS, kdS, cdS, tmp, y1):
    """Fill stages 1..6 (stage 0 given), y1 and the FSAL stage 6."""
    n = y.shape[0]
    for s in range(1, 7):
        ys = Ys[s]
        for i in range(n):
            ys[i] = y[i]
        for k in range(s):               # axpy per earlier stage: vectorises
            a = h * _A[s, k]
            if a != 0.0:
                _axpy1(a, K[k], ys)
        accel(t + _C[s] * h, Ys[s], mode, A, Om, cs, sn, K[s], CxS[s], CvS[s], kdS[s], cdS[s], tmp)
    for i in range(n):
        y1[i] = Ys[6, i]


@njit(cache=True, _nrt=False, inline="always")
def _error_norm(K, y, y1, h, rtol, atol):
    n = y.shape[0]
    err = 0.0
    finite = True
    for i in range(n):
        e = (_E[0] * K[0, i] + _E[2] * K[2, i] + _E[3] * K[3, i] + _E[4] * K[4, i]
             + _E[5] * K[5, i] + _E[6] * K[6, i])
        sc = atol + rtol * max(abs(y[i]), abs(y1[i]))
        q = h * e / sc
        err += q * q
        if not np.isfinite(y1[i]):
            finite = False
    return np.sqrt(err / n), finite


@njit(cache=True, _nrt=False, inline="always")
def _local_error(K, h):
    """RMS norm of the embedded 4th-order local error estimate h sum_i E_i K_i (state units)."""
    n = K.shape[1]
    err = 0.0
    for i in range(n):
        e = h * (_E[0] * K[0, i] + _E[2] * K[2, i] + _E[3] * K[3, i] + _E[4] * K[4, i]
                 + _E[5] * K[5, i] + _E[6] * K[6, i])
        err += e * e
    return np.sqrt(err / n)


@njit(cache=True, _nrt=False, inline="always")
def _fsal(y, K, Ys, CxS, CvS, kdS, cdS):
    """First stage of the next step = last stage of this one."""
    for i in range(y.shape[0]):
        Ys[0, i] = y[i]
        K[0, i] = K[6, i]
    for j in range(CxS.shape[1]):
        CxS[0, j] = CxS[6, j]
        CvS[0, j] = CvS[6, j]
        kdS[0, j] = kdS[6, j]
        cdS[0, j] = cdS[6, j]


#: the loop's scalar inputs, packed by :func:`loop_inputs`: floats (FLOATS) and integers (INTS)
FLOATS = ("Om", "dOm", "dspin", "t0", "t1", "rtol", "atol", "h0", "hmax", "rec_t0")
INTS = ("max_steps", "max_events", "variational", "mon", "ev_cap", "jacobian", "col0", "col1")
#: jacobian: how the variational equations apply the Jacobian; col0, col1: the columns
#: [col0, col1) of the tangent [d u / d u0 | d u / d p] (n + 1 in all) that the loop carries
JAC_AUTO, JAC_LOOPS, JAC_BLAS = -1, 0, 1

#: what the loop returns: status code, end time and state, tangent [d u / d u0 | d u / d p],
#: dense output, counters (steps, rejected, rhs calls, events, losses of the monitored
#: contact), event log (time, contact, new mode), monitored extrema, final modes, u' at
#: the end, sum of the local error estimates, the step the controller proposes next (the
#: last step before it was cut to end at t1: a run that continues this one starts there),
#: and the event log's rates (``ev_r``: d delta / dt of the switching contact there)
LoopResult = namedtuple("LoopResult", [
    "status", "t", "y", "Phi", "u_eval", "counters", "ev_t", "ev_j", "ev_m", "mon_min",
    "mon_max", "mode", "f_end", "err_sum", "h_next", "ev_r"])


def loop_inputs(**kw) -> tuple:
    """(floats, ints) arrays of the loop's scalar inputs, by name (FLOATS, INTS)."""
    return (np.array([float(kw[k]) for k in FLOATS]),
            np.array([int(kw[k]) for k in INTS], dtype=np.int64))


@njit(cache=True)
def dopri_loop(A, y0, t_eval, fin, iin):
    """Integrate from (t0, y0) to t1 (inputs packed by :func:`loop_inputs`) -> the fields
    of a LoopResult, as a tuple."""
    Om, dOm, dspin, t0, t1, rtol, atol, h0, hmax, rec_t0 = (
        fin[0], fin[1], fin[2], fin[3], fin[4], fin[5], fin[6], fin[7], fin[8], fin[9])
    max_steps, max_events, variational, mon, ev_cap, jacobian, col0, col1 = (
        iin[0], iin[1], iin[2] != 0, iin[3], iin[4], iin[5], iin[6], iin[7])
    n = y0.shape[0]
    m = n // 2
    nc = A.C.shape[0]
    H = A.Fc.shape[0]
    r = A.P.shape[0]
    cs = np.empty(H)
    sn = np.empty(H)
    tmp = np.empty(2 * r + 1)
    K = np.empty((7, n))
    Ys = np.empty((7, n))
    CxS = np.empty((7, nc))
    CvS = np.empty((7, nc))
    kdS = np.empty((7, nc))
    cdS = np.empty((7, nc))
    y = y0.copy()
    y1 = np.empty(n)
    mode = np.zeros(nc, np.int64)
    contact_modes(A, t0, Om, y0[:m], mode)
    ncol = col1 - col0
    Phi = np.zeros((n, ncol))
    pcol = n - col0 if col0 <= n < col1 else -1     # the parameter column, if carried
    if variational:
        for c in range(ncol):
            if col0 + c < n:
                Phi[col0 + c, c] = 1.0
    KP = np.empty((6, n, ncol)) if variational else np.empty((1, 1, 1))   # stages 0..5
    Ph = np.empty((n, ncol)) if variational else np.empty((1, 1))
    W = np.empty((3 * r + 1, ncol)) if variational else np.empty((1, 1))   # jac_times workspace
    use_blas = variational and (jacobian == JAC_BLAS or (
        jacobian == JAC_AUTO and m * ncol >= BLAS_MIN_WORK))
    WS = jac_blas_workspace(A, ncol if use_blas else 1)
    dfp = np.empty(n)
    bw = np.empty(7)
    pk = np.empty(7)
    qk = np.empty(7)
    ne = t_eval.shape[0]
    u_eval = np.zeros((ne, n))
    ie = 0
    ev_t = np.zeros(ev_cap)
    ev_j = np.zeros(ev_cap, np.int64)
    ev_m = np.zeros(ev_cap, np.int64)
    ev_r = np.zeros(ev_cap)
    # counters: steps, rejected, rhs calls, events, losses of the monitored contact after rec_t0
    steps = 0
    rejected = 0
    nfev = 0
    nev = 0
    losses = 0
    ext = np.array([np.inf, -np.inf])
    status = _OK
    err_sum = 0.0     # sum of the local error estimates of the accepted steps
    consecutive = 0
    err_old = 1e-4
    t = t0
    Ys[0, :] = y
    accel(t, y, mode, A, Om, cs, sn, K[0], CxS[0], CvS[0], kdS[0], cdS[0], tmp)
    nfev += 1
    h = h0
    h_free = h0       # the last step as the controller proposed it (before a cut at t1)
    while ie < ne and t_eval[ie] <= t0:
        u_eval[ie] = y
        ie += 1
    while t < t1:
        if steps >= max_steps:
            status = _MAX_STEPS
            break
        if h > hmax:
            h = hmax
        h_free = h
        last = False
        if t + h >= t1 or t + 1.01 * h >= t1:
            h = t1 - t
            last = True
        if h <= 1e-14 * (abs(t) + 1.0) and not last:
            status = _STEP_TOO_SMALL
            break
        _stages(t, y, h, K, Ys, mode, A, Om, cs, sn, CxS, CvS, kdS, cdS, tmp, y1)
        nfev += 6
        err, finite = _error_norm(K, y, y1, h, rtol, atol)
        if not finite or not np.isfinite(err):
            if h > 1e-12 * (abs(t) + 1.0):
                h *= 0.1
                rejected += 1
                steps += 1
                continue
            status = _NONFINITE
            break
        if err > 1.0:
            h *= max(0.2, 0.9 * err ** -0.2)
            rejected += 1
            steps += 1
            continue
        # PI step-size control (Hairer's DOPRI5, beta = 0.08): smooth steps near the
        # stability boundary of the stiff modal part instead of accept/reject cycling
        if err == 0.0:
            fac = 10.0
        else:
            fac = min(10.0, max(0.2, 0.9 * err ** -(0.2 - 0.75 * PI_BETA) * err_old ** PI_BETA))
        err_old = max(err, 1e-4)
        h_next = h * fac
        # ---- event search on the dense output of this accepted step ----
        theta_ev, j_ev, m_ev = event_search(A, t, h, Om, mode, CxS, CvS, cs, sn, bw, pk)
        event = theta_ev <= 1.0
        if event and theta_ev < 1.0:
            hs = theta_ev * h
            if hs > 0.0:
                _stages(t, y, hs, K, Ys, mode, A, Om, cs, sn, CxS, CvS, kdS, cdS, tmp, y1)
                nfev += 6
            else:
                for i in range(n):
                    y1[i] = y[i]
                    K[6, i] = K[0, i]
            h_used = hs
        else:
            h_used = h
        err_sum += _local_error(K, h_used)
        steps += 1
        # ---- recording: dense output at t_eval, extrema of the monitored deformation ----
        t_new = t + h_used if not (last and h_used == h) else t1
        if h_used > 0.0:
            ie = dense_eval(t, h_used, t_new, y, K, t_eval, ie, u_eval, bw)
            if mon >= 0 and t_new > rec_t0:
                monitor_extrema(A, t, h_used, rec_t0, mon, Om, K, CxS, CvS, cs, sn, bw, pk, qk, ext)
        if variational and h_used > 0.0:
            variational_step(A, t, h_used, Om, dOm, dspin, mode, Phi, KP, Ph, Ys, kdS, cdS,
                             cs, sn, dfp, tmp, W, WS, use_blas, pcol)
        t = t_new
        for i in range(n):
            y[i] = y1[i]
        # ---- apply the event: switch modes, saltation, fresh stage 0 ----
        if event:
            consecutive += 1
            if consecutive > max_events:
                status = _CHATTERING
                break
            j = j_ev
            newm = m_ev
            harmonics(A.hmul, t, Om, cs, sn)
            e, ed = error_and_rate(A, j, Om, cs, sn)
            rate = range_dot(A.G, j, A.glo[j], A.ghi[j], y[m:]) - ed
            if nev < ev_cap:
                ev_t[nev] = t
                ev_j[nev] = j
                ev_m[nev] = newm
                ev_r[nev] = rate
            nev += 1
            if j == mon and newm == 0 and t >= rec_t0:
                losses += 1
            mode[j] = newm
            if variational:
                # f- = K[6] (old mode), f+ = K[0] (new mode): saltation where they differ
                accel(t, y, mode, A, Om, cs, sn, K[0], CxS[0], CvS[0], kdS[0], cdS[0], tmp)
                nfev += 1
                jump = 0.0
                for i in range(n):
                    jump += abs(K[0, i] - K[6, i])
                if jump > 0.0:
                    if abs(rate) < 1e-14:
                        status = _GRAZING
                        break
                    saltation(A, j, t, Om, dOm, rate, K[0], K[6], Phi, cs, sn, pcol)
            if status != 0:
                break
            Ys[0, :] = y
            accel(t, y, mode, A, Om, cs, sn, K[0], CxS[0], CvS[0], kdS[0], cdS[0], tmp)
            nfev += 1
            if h_next > h:
                h_next = h
        else:
            consecutive = 0
            _fsal(y, K, Ys, CxS, CvS, kdS, cdS)
        h = h_next
    counters = np.array([steps, rejected, nfev, nev, losses])
    f_end = K[0].copy()
    # a plain tuple (LoopResult._make on the Python side): boxing a namedtuple runs Python
    # code, where a pending Ctrl-C raised inside numba's boxing crashed the process
    return (status, t, y, Phi, u_eval, counters, ev_t, ev_j, ev_m, ext[0], ext[1], mode, f_end,
            err_sum, max(h, h_free), ev_r)
