r"""Closed-form solutions of one linear region of a piecewise-linear oscillator.

In each region of the impact pair (see :mod:`vibrogear.verification.impact_exact`) the
motion obeys a linear ODE with constant coefficients::

    q'' + c q' + k q = F0 + Fp cos(Omega t)

This module gives its exact solution (:func:`linear_solution`, vectorised, and the
precomputed scalar form :class:`RegionSolution` used by the root finders), its exact
2x2 state-transition matrix (:func:`linear_stm`), the fixed-time sensitivity
d u / d Omega (:func:`linear_dOmega`) and the linear-limit (no contact) steady state
(:func:`linear_frf`, :func:`linear_periodic_state`).  Under-, critically and
over-damped, undamped, k = 0 and the undamped resonance Omega^2 = k are all covered.

Only numpy is used: nothing from the solvers, so it can verify them independently.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = [
    "linear_solution",
    "linear_stm",
    "linear_dOmega",
    "RegionSolution",
    "linear_frf",
    "linear_periodic_state",
]

# --------------------------------------------------------------------------
# one linear region: homogeneous part
# --------------------------------------------------------------------------
def _g_gp(c: float, k: float, s):
    """Impulse response g(s) (x''+c x'+k x = 0, x(0)=0, x'(0)=1) and g'(s).

    Handles under-, critically and over-damped, undamped and k = 0 cases with
    one formula family: with a = c/2, d = a^2 - k, z = d s^2::

        g  = e^{-a s} S(s),      S = sin(w s)/w | s | sinh(m s)/m
        g' = e^{-a s} (C - a S), C = cos(w s)   | 1 | cosh(m s)

    where w = sqrt(-d), m = sqrt(d).  For |z| small the (entire) Taylor
    series in z is used, which is uniformly accurate across critical damping.
    The over-damped branch is written with the two real exponents so that it
    cannot overflow for long times.
    """
    s = np.asarray(s, dtype=float)
    a = 0.5 * c
    d = a * a - k
    z = d * s * s
    g = np.empty_like(s)
    gp = np.empty_like(s)

    small = np.abs(z) < 1e-3
    if np.any(small):
        ss, zz = s[small], z[small]
        S = ss * (1.0 + zz / 6.0 * (1.0 + zz / 20.0 * (1.0 + zz / 42.0 * (1.0 + zz / 72.0))))
        C = 1.0 + zz / 2.0 * (1.0 + zz / 12.0 * (1.0 + zz / 30.0 * (1.0 + zz / 56.0)))
        E = np.exp(-a * ss)
        g[small] = E * S
        gp[small] = E * (C - a * S)
    big = ~small
    if np.any(big):
        sb = s[big]
        if d < 0.0:
            w = np.sqrt(-d)
            E = np.exp(-a * sb)
            S = np.sin(w * sb) / w
            g[big] = E * S
            gp[big] = E * (np.cos(w * sb) - a * S)
        else:  # d > 0 (d == 0 gives z == 0, always "small")
            m = np.sqrt(d)
            # r1 = -a + m (the slow root) computed without cancellation
            r1 = -k / (a + m) if a > 0.0 else -a + m
            r2 = -a - m
            with np.errstate(over="ignore", under="ignore", invalid="ignore"):
                e1 = np.exp(r1 * sb)
                e2 = np.exp(r2 * sb)
                # e1 - e2 = e2 * expm1(2 m s) is exact-ish for small m s
                diff = np.where(2.0 * m * np.abs(sb) < 1.0, e2 * np.expm1(2.0 * m * sb), e1 - e2)
            g[big] = diff / (2.0 * m)
            gp[big] = (r1 * e1 - r2 * e2) / (2.0 * m)
    return g, gp


def linear_stm(c: float, k: float, s) -> np.ndarray:
    """Exact state-transition matrix d u(t0+s)/d u(t0) of q'' + c q' + k q = F(t).

    ``Phi(s) = [[g' + c g, g], [-k g, g']]``.  For an array ``s`` the result
    has shape ``s.shape + (2, 2)``.
    """
    s_arr = np.asarray(s, dtype=float)
    g, gp = _g_gp(c, k, np.atleast_1d(s_arr))
    phi = np.empty(g.shape + (2, 2))
    phi[..., 0, 0] = gp + c * g
    phi[..., 0, 1] = g
    phi[..., 1, 0] = -k * g
    phi[..., 1, 1] = gp
    if s_arr.ndim == 0:
        return phi[0]
    return phi.reshape(s_arr.shape + (2, 2))


# --------------------------------------------------------------------------
# one linear region: particular solution
# --------------------------------------------------------------------------
def _harmonic_coefficients(c, k, Fp, Omega):
    """A, B with q_p = A cos(Omega t) + B sin(Omega t); None when resonant (c = 0, Omega^2 = k)."""
    det = k - Omega * Omega
    D = det * det + (c * Omega) ** 2
    if D == 0.0:
        return None
    return Fp * det / D, Fp * c * Omega / D


def _particular(c, k, F0, Fp, Omega, t, t0, harmonic=True):
    """A particular solution (q_p, q_p') of q'' + c q' + k q = F0 + Fp cos(Omega t).

    Secular pieces (k = 0 ramps, undamped resonance) are written in s = t - t0.
    With ``harmonic=False`` only the constant forcing F0 is accounted for.
    """
    t = np.asarray(t, dtype=float)
    s = t - t0
    if Omega == 0.0:  # cos(0) = 1: the "harmonic" forcing is a constant
        F0, Fp = F0 + Fp, 0.0
    # constant forcing
    if k != 0.0:
        qp = np.full_like(t, F0 / k)
        vp = np.zeros_like(t)
    elif c != 0.0:
        qp = F0 / c * s
        vp = np.full_like(t, F0 / c)
    else:
        qp = 0.5 * F0 * s * s
        vp = F0 * s
    # harmonic forcing
    if harmonic and Fp != 0.0:
        ab = _harmonic_coefficients(c, k, Fp, Omega)
        ct, st = np.cos(Omega * t), np.sin(Omega * t)
        if ab is not None:
            A, B = ab
            qp = qp + A * ct + B * st
            vp = vp + Omega * (-A * st + B * ct)
        else:  # undamped resonance: q_p = Fp/(2 Omega) s sin(Omega t)
            al = Fp / (2.0 * Omega)
            qp = qp + al * s * st
            vp = vp + al * (st + Omega * s * ct)
    return qp, vp


def _sinc(x):
    """sin(x)/x, accurate at and near 0."""
    x = np.asarray(x, dtype=float)
    out = np.empty_like(x)
    sm = np.abs(x) < 1e-4
    xs = x[sm] ** 2
    out[sm] = 1.0 - xs / 6.0 * (1.0 - xs / 20.0)
    out[~sm] = np.sin(x[~sm]) / x[~sm]
    return out


def _undamped_harmonic_zero_ic(k, Fp, Omega, t0, s):
    """Zero-initial-state response of q'' + k q = Fp cos(Omega t) (k > 0, Omega > 0).

    Duhamel integral written with a sinc of the detuning, so that it is uniformly
    accurate through and near the resonance Omega^2 = k (secular growth
    included, no 1/(k - Omega^2) cancellation)::

        z  = Fp/(2w) [ s sin((w+W)s/2 + th) sinc((w-W)s/2)
                       + (cos(W s + th) - cos(w s - th)) / (w + W) ]
        z' = Fp/2    [ s cos((w+W)s/2 + th) sinc((w-W)s/2)
                       + (sin(W s + th) + sin(w s - th)) / (w + W) ]

    with w = sqrt(k), W = Omega, th = Omega t0.
    """
    w, W, th = np.sqrt(k), Omega, Omega * t0
    sc = _sinc(0.5 * (w - W) * s)
    ph = 0.5 * (w + W) * s + th
    z = Fp / (2.0 * w) * (s * np.sin(ph) * sc + (np.cos(W * s + th) - np.cos(w * s - th)) / (w + W))
    zd = 0.5 * Fp * (s * np.cos(ph) * sc + (np.sin(W * s + th) + np.sin(w * s - th)) / (w + W))
    return z, zd


def _dparticular_dOmega(c, k, F0, Fp, Omega, t):
    """d(q_p, q_p')/d Omega at fixed t (non-resonant harmonic part only)."""
    t = np.asarray(t, dtype=float)
    if Fp == 0.0:
        return np.zeros_like(t), np.zeros_like(t)
    det = k - Omega * Omega
    D = det * det + (c * Omega) ** 2
    if D == 0.0:
        raise ValueError("d/dOmega not available at undamped resonance (c = 0, Omega^2 = k)")
    A, B = Fp * det / D, Fp * c * Omega / D
    dD = -4.0 * Omega * det + 2.0 * c * c * Omega
    dA = Fp * (-2.0 * Omega * D - det * dD) / (D * D)
    dB = Fp * (c * D - c * Omega * dD) / (D * D)
    ct, st = np.cos(Omega * t), np.sin(Omega * t)
    dq = dA * ct - A * t * st + dB * st + B * t * ct
    # q_p' = Omega (-A sin + B cos)
    dv = (-A * st + B * ct) + Omega * (-dA * st - A * t * ct + dB * ct - B * t * st)
    return dq, dv


def linear_solution(c, k, F0, Fp, Omega, t0, u0, t):
    """Closed-form solution of q'' + c q' + k q = F0 + Fp cos(Omega t), u(t0) = u0.

    Returns ``(q, v)`` at the time(s) ``t`` (scalar or array).  Covers
    under/critically/over-damped, undamped, k = 0 (with or without damping)
    and the undamped resonance Omega^2 = k (secular growth): for c = 0 the
    harmonic part is a sinc-form Duhamel integral, uniformly accurate through
    resonance.  For tiny but nonzero c near resonance the particular solution
    has amplitude ~ Fp/(c Omega) and accuracy degrades like eps / (c Omega).
    """
    t_arr = np.asarray(t, dtype=float)
    tt = np.atleast_1d(t_arr)
    q0, v0 = float(u0[0]), float(u0[1])
    # undamped oscillator with harmonic forcing: use the zero-state Duhamel
    # form (exact and well-conditioned through the resonance Omega^2 = k)
    duhamel = c == 0.0 and k > 0.0 and Omega != 0.0 and Fp != 0.0
    qp, vp = _particular(c, k, F0, Fp, Omega, tt, t0, harmonic=not duhamel)
    qp0, vp0 = _particular(c, k, F0, Fp, Omega, np.array([t0]), t0, harmonic=not duhamel)
    x0, y0 = q0 - qp0[0], v0 - vp0[0]
    g, gp = _g_gp(c, k, tt - t0)
    q = qp + (gp + c * g) * x0 + g * y0
    v = vp - k * g * x0 + gp * y0
    if duhamel:
        z, zd = _undamped_harmonic_zero_ic(k, Fp, Omega, t0, tt - t0)
        q, v = q + z, v + zd
    if t_arr.ndim == 0:
        return float(q[0]), float(v[0])
    return q.reshape(t_arr.shape), v.reshape(t_arr.shape)


def linear_dOmega(c, k, F0, Fp, Omega, t0, u0, t):
    """d u(t)/d Omega of one linear region with u(t0) = u0 held fixed (shape (2,))."""
    dq1, dv1 = _dparticular_dOmega(c, k, F0, Fp, Omega, np.array([t]))
    dq0, dv0 = _dparticular_dOmega(c, k, F0, Fp, Omega, np.array([t0]))
    phi = linear_stm(c, k, t - t0)
    return np.array([dq1[0], dv1[0]]) - phi @ np.array([dq0[0], dv0[0]])


class RegionSolution:
    """Closed-form solution of one region with everything precomputed.

    ``__call__(t)`` is vectorised (delegates to :func:`linear_solution`);
    ``scalar(t)`` is a fast pure-``math`` evaluation of the same formulas, used
    inside the root finders.  Both return ``(q, q')``.
    """

    def __init__(self, c, k, F0, Fp, Omega, t0, u0):
        self.c, self.k, self.F0, self.Fp, self.Omega = float(c), float(k), float(F0), float(Fp), float(Omega)
        self.t0 = float(t0)
        self.u0 = (float(u0[0]), float(u0[1]))
        F0e, Fpe = (F0 + Fp, 0.0) if Omega == 0.0 else (F0, Fp)
        self._F0e, self._Fpe = F0e, Fpe
        self.duhamel = c == 0.0 and k > 0.0 and Omega != 0.0 and Fpe != 0.0
        self.ab = None
        if Fpe != 0.0 and not self.duhamel:
            self.ab = _harmonic_coefficients(c, k, Fpe, Omega)
            if self.ab is None:  # pragma: no cover - unreachable (c = 0, k = Omega^2 > 0 is Duhamel)
                raise ValueError("resonant case")
        qp0, vp0 = self._particular(self.t0)
        self.x0, self.y0 = self.u0[0] - qp0, self.u0[1] - vp0
        a = 0.5 * c
        self._a, self._d = a, a * a - k
        if self._d > 0.0:
            m = math.sqrt(self._d)
            self._m = m
            self._r1 = -k / (a + m) if a > 0.0 else -a + m
            self._r2 = -a - m
        elif self._d < 0.0:
            self._w = math.sqrt(-self._d)

    def _particular(self, t):
        c, k, F0, Om = self.c, self.k, self._F0e, self.Omega
        s = t - self.t0
        if k != 0.0:
            qp, vp = F0 / k, 0.0
        elif c != 0.0:
            qp, vp = F0 / c * s, F0 / c
        else:
            qp, vp = 0.5 * F0 * s * s, F0 * s
        if self.ab is not None:
            A, B = self.ab
            ct, st = math.cos(Om * t), math.sin(Om * t)
            qp += A * ct + B * st
            vp += Om * (-A * st + B * ct)
        return qp, vp

    def _g_gp(self, s):
        a, d = self._a, self._d
        z = d * s * s
        if abs(z) < 1e-3:
            S = s * (1.0 + z / 6.0 * (1.0 + z / 20.0 * (1.0 + z / 42.0 * (1.0 + z / 72.0))))
            C = 1.0 + z / 2.0 * (1.0 + z / 12.0 * (1.0 + z / 30.0 * (1.0 + z / 56.0)))
            E = math.exp(-a * s)
            return E * S, E * (C - a * S)
        if d < 0.0:
            w = self._w
            E = math.exp(-a * s)
            S = math.sin(w * s) / w
            return E * S, E * (math.cos(w * s) - a * S)
        m, r1, r2 = self._m, self._r1, self._r2
        e1 = math.exp(r1 * s) if r1 * s < 700 else math.inf
        e2 = math.exp(r2 * s) if r2 * s > -745 else 0.0
        diff = e2 * math.expm1(2.0 * m * s) if 2.0 * m * abs(s) < 1.0 else e1 - e2
        return diff / (2.0 * m), (r1 * e1 - r2 * e2) / (2.0 * m)

    def scalar(self, t):
        t = float(t)
        s = t - self.t0
        g, gp = self._g_gp(s)
        qp, vp = self._particular(t)
        c, k = self.c, self.k
        q = qp + (gp + c * g) * self.x0 + g * self.y0
        v = vp - k * g * self.x0 + gp * self.y0
        if self.duhamel:
            w, W, th, Fp = math.sqrt(k), self.Omega, self.Omega * self.t0, self._Fpe
            x = 0.5 * (w - W) * s
            sc = 1.0 - x * x / 6.0 * (1.0 - x * x / 20.0) if abs(x) < 1e-4 else math.sin(x) / x
            ph = 0.5 * (w + W) * s + th
            q += Fp / (2.0 * w) * (s * math.sin(ph) * sc + (math.cos(W * s + th) - math.cos(w * s - th)) / (w + W))
            v += 0.5 * Fp * (s * math.cos(ph) * sc + (math.sin(W * s + th) + math.sin(w * s - th)) / (w + W))
        return q, v

    def __call__(self, t):
        return linear_solution(self.c, self.k, self.F0, self.Fp, self.Omega, self.t0, self.u0, t)



# --------------------------------------------------------------------------
# linear limit (no contact)
# --------------------------------------------------------------------------
def linear_frf(zeta: float, kappa: float, f_m: float, f_p: float, Omega):
    """Closed-form linear-limit response of q'' + 2 zeta q' + kappa q = f_m + f_p cos(Omega t).

    Returns ``(offset, amplitude)``: static offset f_m / kappa and harmonic
    amplitude f_p / sqrt((kappa - Omega^2)^2 + (2 zeta Omega)^2).  ``Omega``
    may be an array.  Requires kappa > 0.
    """
    if kappa <= 0.0:
        raise ValueError("linear_frf needs kappa > 0 (no static equilibrium otherwise)")
    Omega = np.asarray(Omega, dtype=float)
    amp = f_p / np.sqrt((kappa - Omega ** 2) ** 2 + (2.0 * zeta * Omega) ** 2)
    return f_m / kappa, amp


def linear_periodic_state(zeta, kappa, f_m, f_p, Omega, t0: float = 0.0) -> np.ndarray:
    """State [q, q'] at time t0 of the linear-limit steady state (no contact)."""
    if kappa == 0.0:
        return np.zeros(2)
    c = 2.0 * zeta
    if f_p == 0.0 or Omega == 0.0:
        return np.array([(f_m + (f_p if Omega == 0.0 else 0.0)) / kappa, 0.0])
    ab = _harmonic_coefficients(c, kappa, f_p, Omega)
    if ab is None:
        raise ValueError("undamped resonance: no periodic steady state")
    A, B = ab
    ct, st = np.cos(Omega * t0), np.sin(Omega * t0)
    return np.array([f_m / kappa + A * ct + B * st, Omega * (-A * st + B * ct)])
