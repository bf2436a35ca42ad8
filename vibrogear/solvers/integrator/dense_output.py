"""Dense output of an accepted Dormand-Prince step (Hairer's 4th-order interpolant) and
what the integrator reads from it: the earliest contact switch in the step (sampled,
then bisected on the interpolant), the states at requested output times, and the extrema
of the monitored contact deformation (samples plus the located zeros of its rate)."""
from __future__ import annotations

from numba import njit

from .kernels import error_and_rate, harmonics, range_dot
from .tableau import DP_P

__all__ = ["N_SAMPLES", "dense_weights", "dense_projection", "event_search", "dense_eval",
           "monitor_extrema"]

N_SAMPLES = 4  # dense-output samples per step for switch and extremum detection


@njit(cache=True, inline="always", _nrt=False)
def dense_weights(theta, b):
    """Dense-output weights b_i(theta) (sum_i b_i K_i h gives y(theta) - y0)."""
    t1 = theta
    t2 = t1 * theta
    t3 = t2 * theta
    t4 = t3 * theta
    for i in range(7):
        b[i] = DP_P[i, 0] * t1 + DP_P[i, 1] * t2 + DP_P[i, 2] * t3 + DP_P[i, 3] * t4


@njit(cache=True, inline="always", _nrt=False)
def dense_projection(theta, h, p0, pk, b):
    """Dense value of a projection: p0 + h sum_i b_i(theta) pk[i]."""
    dense_weights(theta, b)
    s = 0.0
    for i in range(7):
        s += b[i] * pk[i]
    return p0 + h * s


@njit(cache=True, inline="always", _nrt=False)
def contact_delta(A, j, t, Om, cx, cs, sn):
    if A.eharm[j] == 0.0:       # no kinematic error: no harmonics to evaluate
        return cx
    harmonics(A.hmul, t, Om, cs, sn)
    e, ed = error_and_rate(A, j, Om, cs, sn)
    return cx - e


@njit(cache=True, inline="always", _nrt=False)
def mode_violation(A, j, md, delta):
    """Largest violation of the current mode's region (> 0: the contact left it)."""
    if md > 0:
        return A.g_hi[j] - delta
    if md < 0:
        return delta - A.g_lo[j]
    v1 = delta - A.g_hi[j]
    v2 = A.g_lo[j] - delta
    return v1 if v1 > v2 else v2




@njit(cache=True, _nrt=False)
def event_search(A, t, h, Om, mode, CxS, CvS, cs, sn, bw, pk):
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
            d = contact_delta(A, j, t + th * h, Om, dense_projection(th, h, x0, pk, bw), cs, sn)
            v = mode_violation(A, j, md, d)
            if v > 0.0:
                lo = th_prev
                hi = th
                for _ in range(60):
                    mid = 0.5 * (lo + hi)
                    dm = contact_delta(A, j, t + mid * h, Om,
                                       dense_projection(mid, h, x0, pk, bw), cs, sn)
                    if mode_violation(A, j, md, dm) > 0.0:
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


@njit(cache=True, _nrt=False)
def dense_eval(t, h_used, t_new, y, K, t_eval, ie, u_eval, bw):
    """Dense output at the requested times inside the step; returns the next index."""
    n = y.shape[0]
    ne = t_eval.shape[0]
    while ie < ne and t_eval[ie] <= t_new:
        th = (t_eval[ie] - t) / h_used
        dense_weights(th, bw)
        for i in range(n):
            s_ = 0.0
            for k in range(7):
                s_ += bw[k] * K[k, i]
            u_eval[ie, i] = y[i] + h_used * s_
        ie += 1
    return ie


@njit(cache=True, _nrt=False, inline="always")
def _rate_zero(A, mon, t, h, Om, v0, qk, cs, sn, bw, lo, hi, f_lo, f_hi):
    """The zero of the monitored deformation's rate in (lo, hi) (signs f_lo, f_hi differ):
    Illinois regula falsi to 1e-13 in theta (the rate is a smooth quartic in theta inside
    the step) where bisection of the quarter step took 41 evaluations: the two-stage
    gearbox's step 15.6 -> 15.0 us at rtol 3.9e-4 (benchmarks/bench_rhs_floor.py)."""
    side = 0
    for _ in range(60):
        mid = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        if not lo < mid < hi:
            mid = 0.5 * (lo + hi)
        harmonics(A.hmul, t + mid * h, Om, cs, sn)
        _, ed = error_and_rate(A, mon, Om, cs, sn)
        rm = dense_projection(mid, h, v0, qk, bw) - ed
        if rm == 0.0:
            return mid
        if rm * f_lo > 0.0:
            lo, f_lo = mid, rm
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = mid, rm
            if side == 1:
                f_lo *= 0.5
            side = 1
        if hi - lo < 1e-13:
            break
    return 0.5 * (lo + hi)


@njit(cache=True, _nrt=False)
def monitor_extrema(A, t, h_used, rec_t0, mon, Om, K, CxS, CvS, cs, sn, bw, pk, qk, ext):
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
        harmonics(A.hmul, t + th * h_used, Om, cs, sn)
        e, ed = error_and_rate(A, mon, Om, cs, sn)
        d = dense_projection(th, h_used, x0, pk, bw) - e
        rate = dense_projection(th, h_used, v0, qk, bw) - ed
        if d < ext[0]:
            ext[0] = d
        if d > ext[1]:
            ext[1] = d
        if s > 0 and prev_rate * rate < 0.0:
            mid = _rate_zero(A, mon, t, h_used, Om, v0, qk, cs, sn, bw, prev_th, th,
                             prev_rate, rate)
            harmonics(A.hmul, t + mid * h_used, Om, cs, sn)
            e, ed = error_and_rate(A, mon, Om, cs, sn)
            d = dense_projection(mid, h_used, x0, pk, bw) - e
            if d < ext[0]:
                ext[0] = d
            if d > ext[1]:
                ext[1] = d
        prev_rate = rate
        prev_th = th
