r"""Exact (closed-form, piecewise) reference for the piecewise-linear impact pair.

System (nondimensional time :math:`\tau`, written ``t`` here)::

    q'' + c(q) q' + kappa q + g(q) = f_m + f_p cos(Omega t)

    g(q) = (1-kappa)(q - b_r)   q >  b_r     (contact, "region +1")
           0                    |q| <= b_r   (clearance, "region 0")
           (1-kappa)(q + b_r)   q < -b_r     (contact, "region -1")

    c(q) = 2 zeta            in the clearance
           2 zeta + c_d      in contact (optional extra contact damping)

In every region the motion is linear with constant coefficients::

    q'' + c_r q' + k_r q = F_r + f_p cos(Omega t)

    region  0 : c = 2 zeta,       k = kappa, F = f_m
    region +1 : c = 2 zeta + c_d, k = 1,     F = f_m + (1-kappa) b_r
    region -1 : c = 2 zeta + c_d, k = 1,     F = f_m - (1-kappa) b_r

so the flow is known in closed form inside a region; the only numerical
operation is locating the switching times (roots of ``q(t) -+ b_r`` of the
closed-form solution, bracketed on a fine grid and polished by Brent's method
and a Newton step), which is accurate to a few ulps.

State ``u = [q, q']``.  Forcing phase is ``cos(Omega t)`` in *absolute* time
``t``.  This module deliberately uses only numpy/scipy and does **not** import
anything from :mod:`vibrogear`.

Main entry points
-----------------
``ImpactParams``              parameter set
``linear_solution``           closed-form solution of one linear region
``linear_stm``                its exact 2x2 state-transition matrix
``linear_dOmega``             d u(t)/d Omega of one region (u(t0) fixed)
``exact_flow``                flow over [t0, t1] with switches, STM, d/dOmega
``exact_dense``               the flow sampled at given times
``exact_monodromy``           monodromy over n forcing periods
``periodic_orbit``            Newton on u(T; u0) - u0 with the exact flow
``linear_frf``                closed-form linear-limit response (no contact)
``linear_periodic_state``     the linear-limit periodic state at t = 0
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

__all__ = [
    "ImpactParams",
    "region_coefficients",
    "linear_solution",
    "linear_stm",
    "linear_dOmega",
    "vector_field",
    "saltation_matrix",
    "initial_region",
    "FlowResult",
    "exact_flow",
    "exact_dense",
    "exact_monodromy",
    "PeriodicOrbit",
    "periodic_orbit",
    "linear_frf",
    "linear_periodic_state",
]


# --------------------------------------------------------------------------
# parameters
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class ImpactParams:
    zeta: float
    kappa: float
    f_m: float
    f_p: float
    b_r: float
    contact_damping: float = 0.0

    def __post_init__(self):
        if not self.b_r > 0.0:
            raise ValueError("b_r must be > 0 (use np.inf for the linear limit)")
        if self.zeta < 0.0 or self.contact_damping < 0.0:
            raise ValueError("damping must be non-negative")
        if self.kappa < 0.0:
            raise ValueError("kappa must be non-negative")


def region_coefficients(p: ImpactParams, region: int) -> tuple[float, float, float]:
    """(c, k, F) of the linear ODE q'' + c q' + k q = F + f_p cos(Omega t) in *region*."""
    if region == 0:
        return 2.0 * p.zeta, p.kappa, p.f_m
    if region == 1:
        return 2.0 * p.zeta + p.contact_damping, 1.0, p.f_m + (1.0 - p.kappa) * p.b_r
    if region == -1:
        return 2.0 * p.zeta + p.contact_damping, 1.0, p.f_m - (1.0 - p.kappa) * p.b_r
    raise ValueError(f"unknown region {region!r}")


def _region_of_position(p: ImpactParams, q: float) -> int:
    if q > p.b_r:
        return 1
    if q < -p.b_r:
        return -1
    return 0


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
# full vector field, regions, saltation
# --------------------------------------------------------------------------
def _restoring(p: ImpactParams, q: float, region: int) -> float:
    """kappa q + g(q) evaluated with the formula of *region* (continuous at +-b_r)."""
    if region == 0:
        return p.kappa * q
    if region == 1:
        return p.kappa * q + (1.0 - p.kappa) * (q - p.b_r)
    return p.kappa * q + (1.0 - p.kappa) * (q + p.b_r)


def vector_field(p: ImpactParams, Omega: float, t: float, u, region: int | None = None) -> np.ndarray:
    """f(t, u) = [q', q''] using the formulas of *region* (default: region of q)."""
    q, v = float(u[0]), float(u[1])
    if region is None:
        region = _region_of_position(p, q)
    c = 2.0 * p.zeta + (p.contact_damping if region != 0 else 0.0)
    acc = p.f_m + p.f_p * np.cos(Omega * t) - c * v - _restoring(p, q, region)
    return np.array([v, acc])


def saltation_matrix(f_minus, f_plus, n) -> np.ndarray:
    """S = I + (f+ - f-) n^T / (n^T f-) for a crossing of the surface with normal n."""
    f_minus, f_plus, n = (np.asarray(x, dtype=float) for x in (f_minus, f_plus, n))
    den = float(n @ f_minus)
    if den == 0.0:
        raise ZeroDivisionError("grazing crossing: saltation matrix undefined")
    return np.eye(len(n)) + np.outer(f_plus - f_minus, n) / den


def initial_region(p: ImpactParams, Omega: float, t: float, u) -> int:
    """Region a state starts in; on a boundary decided by velocity, then acceleration."""
    q, v = float(u[0]), float(u[1])
    b = p.b_r
    if q > b:
        return 1
    if q < -b:
        return -1
    if q == b:
        if v != 0.0:
            return 1 if v > 0.0 else 0
        acc = p.f_m + p.f_p * np.cos(Omega * t) - p.kappa * b  # same on both sides
        return 1 if acc > 0.0 else 0
    if q == -b:
        if v != 0.0:
            return -1 if v < 0.0 else 0
        acc = p.f_m + p.f_p * np.cos(Omega * t) + p.kappa * b
        return -1 if acc < 0.0 else 0
    return 0


# --------------------------------------------------------------------------
# switch detection in one region
# --------------------------------------------------------------------------
def _region_timescale(c, k, Omega):
    a = 0.5 * c
    w = max(np.sqrt(abs(k)), abs(Omega), abs(a), 1e-12)
    return 2.0 * np.pi / w


def _next_switch(p, Omega, region, t_start, u_start, t_end, pts_per_period=64, chunk=512):
    """First time in (t_start, t_end] at which the closed-form solution leaves *region*.

    Returns ``(t_switch, boundary_sign)`` or ``(None, 0)``.  boundary_sign is
    +1 for q = +b_r, -1 for q = -b_r.
    """
    if not np.isfinite(p.b_r):
        return None, 0
    c, k, F0 = region_coefficients(p, region)
    Fp, b = p.f_p, p.b_r

    sol = RegionSolution(c, k, F0, Fp, Omega, t_start, u_start)
    qv = sol

    # "inside" functions h >= 0 in the region, with their derivatives
    if region == 0:
        bounds = [(+1, lambda q: b - q, -1.0), (-1, lambda q: q + b, +1.0)]
    elif region == 1:
        bounds = [(+1, lambda q: q - b, +1.0)]
    else:
        bounds = [(-1, lambda q: -b - q, -1.0)]

    dt = min(_region_timescale(c, k, Omega) / pts_per_period, 0.25)
    scale = max(b, 1.0)
    graze_tol = 1e-13 * scale
    t_lo = t_start
    npts = 32
    while t_lo < t_end:
        t_hi = min(t_lo + npts * dt, t_end)
        npts = min(2 * npts, chunk)
        n = max(int(np.ceil((t_hi - t_lo) / dt)), 1)
        ts = np.linspace(t_lo, t_hi, n + 1)
        q, v = qv(ts)
        best = None
        for sign, hfun, dsign in bounds:
            h = hfun(q)
            hd = dsign * v
            if t_lo == t_start:
                h[0] = max(h[0], 0.0)  # start state is inside (or on) the region
            root = _first_exit(ts, h, hd, lambda t, hf=hfun, ds=dsign: _hh(sol.scalar, hf, ds, t), graze_tol)
            if root is not None and (best is None or root < best[0]):
                best = (root, sign)
        if best is not None:
            return best
        t_lo = t_hi
    return None, 0


def _hh(qv, hfun, dsign, t):
    q, v = qv(t)
    return hfun(q), dsign * v


def _first_exit(ts, h, hd, hh, graze_tol):
    """First t where h goes negative, using samples h, hd on grid ts."""
    n = len(ts) - 1
    # candidate intervals: sign change of h, or an interior minimum of h
    sc = (h[:-1] >= 0.0) & (h[1:] < 0.0)
    mn = (hd[:-1] < 0.0) & (hd[1:] > 0.0) & ~sc
    # starting on the boundary and leaving again within the first interval
    cand = np.flatnonzero(sc | mn)
    for i in cand:
        a, bnd = ts[i], ts[i + 1]
        if sc[i]:
            lo = a
            if h[i] == 0.0:
                # h starts at zero (boundary): root is after the maximum of h
                if hd[i] > 0.0 and hd[i + 1] < 0.0:
                    lo = brentq(lambda t: hh(t)[1], a, bnd, xtol=1e-16, rtol=8.9e-16, maxiter=200)
                    if hh(lo)[0] < 0.0:  # pragma: no cover - defensive
                        lo = a
                elif hd[i] <= 0.0:
                    if i == 0:
                        raise RuntimeError("state leaves its region immediately (inconsistent region)")
                    return a
            return _polish(hh, lo, bnd)
        # interior minimum of h without sign change at the samples
        if n == 0:
            continue
        tm = brentq(lambda t: hh(t)[1], a, bnd, xtol=1e-16, rtol=8.9e-16, maxiter=200)
        hm = hh(tm)[0]
        if hm < -graze_tol:
            return _polish(hh, a, tm)
    return None


def _polish(hh, a, b):
    """Root of h on [a, b] with h(a) >= 0 > h(b)."""
    t = brentq(lambda t: hh(t)[0], a, b, xtol=1e-16, rtol=8.9e-16, maxiter=200)
    # one Newton step with the analytic derivative (kept only if it stays in [a, b])
    h, hd = hh(t)
    if hd != 0.0:
        tn = t - h / hd
        if a <= tn <= b and abs(hh(tn)[0]) <= abs(h):
            t = tn
    return t


# --------------------------------------------------------------------------
# exact flow
# --------------------------------------------------------------------------
@dataclass
class FlowResult:
    u_end: np.ndarray
    t0: float
    t1: float
    switch_times: np.ndarray
    switch_states: np.ndarray          # state at each switch (q snapped to +-b_r)
    switch_from: np.ndarray             # region left at each switch
    switch_to: np.ndarray               # region entered at each switch
    segments: list = field(default_factory=list)  # (region, t_start, t_end, u_start)
    stm: np.ndarray | None = None       # d u(t1)/d u(t0), saltations included
    dOmega: np.ndarray | None = None    # d u(t1)/d Omega at fixed t0, t1, u(t0)
    time_in_contact: float = 0.0

    @property
    def n_switches(self) -> int:
        return len(self.switch_times)

    @property
    def regions_visited(self) -> set:
        return {seg[0] for seg in self.segments if seg[2] > seg[1]}


def exact_flow(p: ImpactParams, Omega: float, u0, t0: float, t1: float, *,
               stm: bool = False, dOmega: bool = False, max_switches: int = 100000,
               pts_per_period: int = 64) -> FlowResult:
    """Exact flow of the impact pair from u(t0) = u0 to t1 (t1 >= t0).

    The state-transition matrix is the ordered product of the exact segment
    STMs and the saltation matrices at each switch (identity for c_d = 0).
    ``dOmega`` propagates the fixed-time sensitivity d u / d Omega the same way
    (the switching surface does not depend on Omega).
    """
    u = np.array(u0, dtype=float).reshape(2)
    if t1 < t0:
        raise ValueError("t1 must be >= t0")
    region = initial_region(p, Omega, t0, u)
    t = float(t0)
    M = np.eye(2) if stm else None
    y = np.zeros(2) if dOmega else None
    sw_t, sw_u, sw_from, sw_to, segs = [], [], [], [], []
    t_contact = 0.0
    while True:
        c, k, F0 = region_coefficients(p, region)
        ts, sign = _next_switch(p, Omega, region, t, u, t1, pts_per_period=pts_per_period)
        t_seg_end = t1 if ts is None else ts
        q_e, v_e = linear_solution(c, k, F0, p.f_p, Omega, t, u, t_seg_end)
        segs.append((region, t, t_seg_end, u.copy()))
        if region != 0:
            t_contact += t_seg_end - t
        if stm:
            M = linear_stm(c, k, t_seg_end - t) @ M
        if dOmega:
            y = linear_stm(c, k, t_seg_end - t) @ y + linear_dOmega(c, k, F0, p.f_p, Omega, t, u, t_seg_end)
        if ts is None:
            u = np.array([q_e, v_e])
            break
        # switch: snap onto the surface, pick the new region
        u_s = np.array([sign * p.b_r, v_e])
        # side of the surface the motion continues on: decided by the sign of
        # q' (then of q'' when grazing), so a tangential touch may keep the region
        new_region = initial_region(p, Omega, ts, u_s)
        if new_region != region:
            if len(sw_t) >= max_switches:
                raise RuntimeError(f"more than {max_switches} switches in exact_flow")
            sw_t.append(ts)
            sw_u.append(u_s.copy())
            sw_from.append(region)
            sw_to.append(new_region)
            if (stm or dOmega) and p.contact_damping != 0.0:
                S = saltation_matrix(vector_field(p, Omega, ts, u_s, region),
                                     vector_field(p, Omega, ts, u_s, new_region), [1.0, 0.0])
                if stm:
                    M = S @ M
                if dOmega:
                    y = S @ y
        region, t, u = new_region, ts, u_s
        if t >= t1:
            break
    return FlowResult(u_end=u, t0=float(t0), t1=float(t1),
                      switch_times=np.array(sw_t), switch_states=np.array(sw_u).reshape(-1, 2),
                      switch_from=np.array(sw_from, dtype=int), switch_to=np.array(sw_to, dtype=int),
                      segments=segs, stm=M, dOmega=y, time_in_contact=t_contact)


def exact_dense(p: ImpactParams, Omega: float, u0, t0: float, t_eval, flow: FlowResult | None = None) -> np.ndarray:
    """Exact states at the (sorted, >= t0) times ``t_eval``; shape (len(t_eval), 2)."""
    t_eval = np.asarray(t_eval, dtype=float)
    if flow is None:
        flow = exact_flow(p, Omega, u0, t0, float(t_eval.max()) if t_eval.size else t0)
    out = np.empty((t_eval.size, 2))
    starts = np.array([s[1] for s in flow.segments])
    idx = np.clip(np.searchsorted(starts, t_eval, side="right") - 1, 0, len(starts) - 1)
    for j in np.unique(idx):
        region, ta, tb, ua = flow.segments[j]
        c, k, F0 = region_coefficients(p, region)
        m = idx == j
        q, v = linear_solution(c, k, F0, p.f_p, Omega, ta, ua, t_eval[m])
        out[m, 0], out[m, 1] = q, v
    return out


def exact_monodromy(p: ImpactParams, Omega: float, u0, n_periods: int = 1, t0: float = 0.0) -> np.ndarray:
    """Exact monodromy d u(t0+T)/d u(t0), T = 2 pi n / Omega."""
    T = 2.0 * np.pi * n_periods / Omega
    return exact_flow(p, Omega, u0, t0, t0 + T, stm=True).stm


# --------------------------------------------------------------------------
# periodic orbits
# --------------------------------------------------------------------------
@dataclass
class PeriodicOrbit:
    u0: np.ndarray
    period: float
    n_periods: int
    monodromy: np.ndarray
    floquet: np.ndarray
    residual: float
    iterations: int
    converged: bool
    flow: FlowResult
    q_min: float
    q_max: float

    @property
    def contact_sides(self) -> set:
        """Subset of {+1, -1}: the contact regions the orbit enters."""
        return {r for r in self.flow.regions_visited if r != 0}

    @property
    def stable(self) -> bool:
        return bool(np.max(np.abs(self.floquet)) < 1.0)


def _orbit_extrema(p, Omega, flow, n=4000):
    ts = np.linspace(flow.t0, flow.t1, n)
    ts = np.union1d(ts, flow.switch_times)
    u = exact_dense(p, Omega, None, flow.t0, ts, flow=flow)
    return float(u[:, 0].min()), float(u[:, 0].max())


def periodic_orbit(p: ImpactParams, Omega: float, u0_guess=None, *, n_periods: int = 1,
                   t0: float = 0.0, tol: float = 1e-13, max_iter: int = 60) -> PeriodicOrbit:
    """Periodic orbit of period T = 2 pi n / Omega by damped Newton on u(T; u0) - u0.

    The Jacobian is the exact monodromy minus identity.  Default initial guess:
    the linear-limit (no contact) periodic state.  ``tol`` applies to
    max|u(T) - u0| relative to max(1, |u0|).
    """
    T = 2.0 * np.pi * n_periods / Omega
    u = (linear_periodic_state(p.zeta, p.kappa, p.f_m, p.f_p, Omega, t0) if u0_guess is None
         else np.array(u0_guess, dtype=float))

    def resid(u):
        fl = exact_flow(p, Omega, u, t0, t0 + T, stm=True)
        return fl.u_end - u, fl

    F, fl = resid(u)
    nF = np.max(np.abs(F))
    it = 0
    converged = nF <= tol * max(1.0, np.max(np.abs(u)))
    while not converged and it < max_iter:
        it += 1
        J = fl.stm - np.eye(2)
        try:
            du = np.linalg.solve(J, -F)
        except np.linalg.LinAlgError:
            break
        lam = 1.0
        while True:
            un = u + lam * du
            Fn, fln = resid(un)
            nFn = np.max(np.abs(Fn))
            if nFn < nF or lam < 1e-6:
                break
            lam *= 0.5
        u, F, fl, nF = un, Fn, fln, nFn
        converged = nF <= tol * max(1.0, np.max(np.abs(u)))
    if converged:  # one extra polishing step (cheap, quadratic convergence)
        J = fl.stm - np.eye(2)
        un = u + np.linalg.solve(J, -F)
        Fn, fln = resid(un)
        if np.max(np.abs(Fn)) <= nF:
            u, F, fl, nF = un, Fn, fln, np.max(np.abs(Fn))
    qmin, qmax = _orbit_extrema(p, Omega, fl)
    return PeriodicOrbit(u0=u, period=T, n_periods=n_periods, monodromy=fl.stm,
                         floquet=np.linalg.eigvals(fl.stm), residual=float(nF), iterations=it,
                         converged=bool(converged), flow=fl, q_min=qmin, q_max=qmax)


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
