"""Compiled adaptive Dormand-Prince 5(4) loop with dense output, contact events and
variational equations (monodromy + parameter sensitivity) with saltation matrices.

The loop runs entirely in numba.  Contact modes switch only at located events:
after an accepted step the switching functions are sampled on the dense output; the
earliest crossing is located by bisection on the interpolant and the step is retaken
to end exactly there, so each step integrates one smooth vector field and the method
keeps its order.  All loops are bounded (max_steps, max consecutive events).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .kernels import (FAST, accel, accel_dparam, contact_modes, error_and_rate, harmonics, jac_times,
                      range_dot)

__all__ = ["dopri_loop"]

# status codes returned by the loop (numba has no enums): the values of the integrator
# members of solvers.status.Status, which maps them (from_code)
_OK, _MAX_STEPS, _NONFINITE, _CHATTERING, _STEP_TOO_SMALL, _GRAZING = 0, -1, -2, -3, -4, -5

_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A = np.zeros((7, 7))
_A[1, :1] = [1 / 5]
_A[2, :2] = [3 / 40, 9 / 40]
_A[3, :3] = [44 / 45, -56 / 15, 32 / 9]
_A[4, :4] = [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729]
_A[5, :5] = [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656]
_A[6, :6] = [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]
_B = _A[6].copy()
_E = np.array([-71 / 57600, 0, 71 / 16695, -71 / 1920, 17253 / 339200, -22 / 525, 1 / 40])
_P = np.array([
    [1, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
    [0, 0, 0, 0],
    [0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
    [0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
    [0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
    [0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
    [0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
])
N_SAMPLES = 4  # dense-output samples per step for switch and extremum detection
PI_BETA = 0.08  # PI step-size controller


@njit(cache=True, inline="always", _nrt=False)
def _bw(theta, b):
    """Dense-output weights b_i(theta) (sum_i b_i K_i h gives y(theta) - y0)."""
    t1 = theta
    t2 = t1 * theta
    t3 = t2 * theta
    t4 = t3 * theta
    for i in range(7):
        b[i] = _P[i, 0] * t1 + _P[i, 1] * t2 + _P[i, 2] * t3 + _P[i, 3] * t4


@njit(cache=True, inline="always", _nrt=False)
def _proj(theta, h, p0, pk, b):
    """Dense value of a projection: p0 + h sum_i b_i(theta) pk[i]."""
    _bw(theta, b)
    s = 0.0
    for i in range(7):
        s += b[i] * pk[i]
    return p0 + h * s


@njit(cache=True, inline="always", _nrt=False)
def _delta(A, j, t, Om, cx, cs, sn):
    harmonics(t, Om, cs, sn)
    e, ed = error_and_rate(A, j, Om, cs, sn)
    return cx - e


@njit(cache=True, inline="always", _nrt=False)
def _violation(A, j, md, delta):
    """Largest violation of the current mode's region (> 0: the contact left it)."""
    if md > 0:
        return A.g_hi[j] - delta
    if md < 0:
        return delta - A.g_lo[j]
    v1 = delta - A.g_hi[j]
    v2 = A.g_lo[j] - delta
    return v1 if v1 > v2 else v2


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


@njit(cache=True, _nrt=False, inline="always")
def _event_search(A, t, h, Om, mode, CxS, CvS, cs, sn, bw, pk):
    """Earliest switch in the accepted step: (theta in (0, 1] or 2, contact, new mode)."""
    nc = A.C.shape[0]
    theta_ev = 2.0
    j_ev = -1
    m_ev = 0
    for j in range(nc):
        if A.smooth[j] != 0.0:
            continue
        md = mode[j]
        for k in range(7):
            pk[k] = CvS[k, j]  # C . x' = C . v at each stage
        x0 = CxS[0, j]
        th_prev = 0.0
        for s in range(1, N_SAMPLES + 1):
            th = s / N_SAMPLES
            if th >= theta_ev:
                break
            d = _delta(A, j, t + th * h, Om, _proj(th, h, x0, pk, bw), cs, sn)
            v = _violation(A, j, md, d)
            if v > 0.0:
                lo = th_prev
                hi = th
                for _ in range(60):
                    mid = 0.5 * (lo + hi)
                    dm = _delta(A, j, t + mid * h, Om, _proj(mid, h, x0, pk, bw), cs, sn)
                    if _violation(A, j, md, dm) > 0.0:
                        hi = mid
                    else:
                        lo = mid
                    if hi - lo < 1e-15:
                        break
                    if (hi - lo) * h < 1e-15 * (abs(t) + 1.0):
                        break
                if hi < theta_ev:
                    theta_ev = hi
                    j_ev = j
                    if md != 0:
                        m_ev = 0
                    else:
                        m_ev = 1 if d - A.g_hi[j] > A.g_lo[j] - d else -1
                break
            th_prev = th
    return theta_ev, j_ev, m_ev


@njit(cache=True, _nrt=False, inline="always")
def _dense_eval(t, h_used, t_new, y, K, t_eval, ie, u_eval, bw):
    """Dense output at the requested times inside the step; returns the next index."""
    n = y.shape[0]
    ne = t_eval.shape[0]
    while ie < ne and t_eval[ie] <= t_new:
        th = (t_eval[ie] - t) / h_used
        _bw(th, bw)
        for i in range(n):
            s_ = 0.0
            for k in range(7):
                s_ += bw[k] * K[k, i]
            u_eval[ie, i] = y[i] + h_used * s_
        ie += 1
    return ie


@njit(cache=True, _nrt=False, inline="always")
def _extrema(A, t, h_used, rec_t0, mon, Om, K, CxS, CvS, cs, sn, bw, pk, qk, ext):
    """Update ext = [min, max] of the monitored deformation over the step (after rec_t0):
    samples of the dense output plus the located zeros of its rate."""
    m = A.w2.shape[0]
    for k in range(7):
        pk[k] = CvS[k, mon]
        qk[k] = range_dot(A.G, mon, A.glo[mon], A.ghi[mon], K[k, m:])
    x0 = CxS[0, mon]
    v0 = CvS[0, mon]
    th_lo = 0.0 if t >= rec_t0 else (rec_t0 - t) / h_used
    prev_rate = 0.0
    prev_th = th_lo
    for s in range(0, N_SAMPLES + 1):
        th = th_lo + (1.0 - th_lo) * s / N_SAMPLES
        harmonics(t + th * h_used, Om, cs, sn)
        e, ed = error_and_rate(A, mon, Om, cs, sn)
        d = _proj(th, h_used, x0, pk, bw) - e
        rate = _proj(th, h_used, v0, qk, bw) - ed
        if d < ext[0]:
            ext[0] = d
        if d > ext[1]:
            ext[1] = d
        if s > 0 and prev_rate * rate < 0.0:
            lo = prev_th
            hi = th
            for _ in range(50):
                mid = 0.5 * (lo + hi)
                harmonics(t + mid * h_used, Om, cs, sn)
                e, ed = error_and_rate(A, mon, Om, cs, sn)
                rm = _proj(mid, h_used, v0, qk, bw) - ed
                if rm * prev_rate > 0.0:
                    lo = mid
                else:
                    hi = mid
                if hi - lo < 1e-13:
                    break
            mid = 0.5 * (lo + hi)
            harmonics(t + mid * h_used, Om, cs, sn)
            e, ed = error_and_rate(A, mon, Om, cs, sn)
            d = _proj(mid, h_used, x0, pk, bw) - e
            if d < ext[0]:
                ext[0] = d
            if d > ext[1]:
                ext[1] = d
        prev_rate = rate
        prev_th = th


@njit(cache=True, _nrt=False, inline="always", fastmath=FAST)
def _axpy2(a, X, Y):
    """Y += a X for (n, ncol) C-contiguous arrays, row by row."""
    for i in range(X.shape[0]):
        xi = X[i]
        yi = Y[i]
        for c in range(X.shape[1]):
            yi[c] += a * xi[c]


@njit(cache=True, _nrt=False, inline="always")
def _variational_step(A, t, h_used, Om, dOm, dspin, mode, Phi, KP, Ph, Ys, kdS, cdS, cs, sn,
                      dfp, tmp, W):
    """Advance Phi = [d u / d u0, d u / d param] with the stages of the accepted step."""
    n = Phi.shape[0]
    ncol = Phi.shape[1]
    for s in range(7):
        for i in range(n):
            phr = Ph[i]
            pir = Phi[i]
            for c in range(ncol):
                phr[c] = pir[c]
        for k in range(s):
            a = h_used * _A[s, k]
            if a != 0.0:
                _axpy2(a, KP[k], Ph)
        jac_times(Ph, mode, A, kdS[s], cdS[s], KP[s], W)
        ts = t + _C[s] * h_used
        harmonics(ts, Om, cs, sn)
        accel_dparam(ts, Ys[s], mode, A, Om, dOm, dspin, cs, sn, kdS[s], cdS[s], dfp, tmp)
        for i in range(n):
            KP[s, i, n] += dfp[i]
    for k in range(6):
        a = h_used * _B[k]
        if a != 0.0:
            _axpy2(a, KP[k], Phi)


@njit(cache=True)
def dopri_loop(A, Om, dOm, dspin, y0, t0, t1, rtol, atol, h0, hmax, max_steps,
               max_events, variational, t_eval, rec_t0, mon, ev_cap):
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
    ncol = n + 1
    Phi = np.zeros((n, ncol))
    if variational:
        for i in range(n):
            Phi[i, i] = 1.0
    KP = np.empty((7, n, ncol)) if variational else np.empty((1, 1, 1))
    Ph = np.empty((n, ncol)) if variational else np.empty((1, 1))
    W = np.empty((3 * r + 1, ncol)) if variational else np.empty((1, 1))   # jac_times workspace
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
    while ie < ne and t_eval[ie] <= t0:
        u_eval[ie] = y
        ie += 1
    while t < t1:
        if steps >= max_steps:
            status = _MAX_STEPS
            break
        if h > hmax:
            h = hmax
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
        theta_ev, j_ev, m_ev = _event_search(A, t, h, Om, mode, CxS, CvS, cs, sn, bw, pk)
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
            ie = _dense_eval(t, h_used, t_new, y, K, t_eval, ie, u_eval, bw)
            if mon >= 0 and t_new > rec_t0:
                _extrema(A, t, h_used, rec_t0, mon, Om, K, CxS, CvS, cs, sn, bw, pk, qk, ext)
        if variational and h_used > 0.0:
            _variational_step(A, t, h_used, Om, dOm, dspin, mode, Phi, KP, Ph, Ys, kdS, cdS,
                              cs, sn, dfp, tmp, W)
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
            harmonics(t, Om, cs, sn)
            e, ed = error_and_rate(A, j, Om, cs, sn)
            rate = range_dot(A.G, j, A.glo[j], A.ghi[j], y[m:]) - ed
            if nev < ev_cap:
                ev_t[nev] = t
                ev_j[nev] = j
                ev_m[nev] = newm
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
                    harmonics(t, Om, cs, sn)
                    # d h / d param at fixed (t, x): h = c.x - e(t; Om) - gap
                    dh = 0.0
                    for hh in range(H):
                        nn = hh + 1
                        dh -= nn * t * (-A.ec[j, hh] * sn[hh] + A.es[j, hh] * cs[hh])
                    dh *= dOm
                    for c in range(ncol):
                        g = 0.0
                        for i in range(m):
                            g += A.C[j, i] * Phi[i, c]
                        if c == n:
                            g += dh
                        g /= rate
                        for i in range(n):
                            Phi[i, c] += (K[0, i] - K[6, i]) * g
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
    return (status, t, y, Phi, u_eval, counters, ev_t, ev_j, ev_m, ext[0], ext[1], mode, f_end,
            err_sum)
