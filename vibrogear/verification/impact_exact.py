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
the solvers (:mod:`vibrogear.solvers`): it is an independent check of them.  The
closed-form solutions of one linear region live in :mod:`.pwl_region`.

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

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from .pwl_region import (RegionSolution, linear_dOmega, linear_frf, linear_periodic_state,
                         linear_solution, linear_stm)

__all__ = [
    "ImpactParams",
    "region_coefficients",
    "linear_solution",
    "linear_stm",
    "linear_dOmega",
    "RegionSolution",
    "vector_field",
    "saltation_matrix",
    "initial_region",
    "FlowResult",
    "exact_flow",
    "exact_dense",
    "exact_monodromy",
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
