"""The contact law: the one definition of every gear-mesh and rolling-element force.

A contact acts on its deformation delta = c . x - e(t) (coupling vector c, kinematic
transmission error e), positive = compression of the upper (working) flank.  It is a
dead zone between a lower gap g_lo and an upper gap g_hi (g_lo = -inf: one-sided, a
rolling element; g_hi = 0, g_lo = -backlash: a gear mesh), with the force

    f =  k_hi mu(t) (delta - g_hi)^p + c delta'     delta > g_hi            (mode +1)
    f =  0                                          g_lo <= delta <= g_hi   (mode  0)
    f = -k_lo mu(t) (g_lo - delta)^p + c delta'     delta < g_lo            (mode -1)

f > 0 pushes the two bodies apart along c (the generalised force on the DOF is -c f).
p = 1 (piecewise linear mesh), 3/2 (Hertz, balls) or 10/9 (rollers);
mu(t) = 1 + sum_h a_h cos(h W t) + b_h sin(h W t) is the stiffness modulation factor
(periodic mesh stiffness); the viscous damping c acts only in contact (mode != 0).
The law returns (f, df/ddelta, df/ddelta'): df/ddelta = p k mu s^(p-1) with s the
penetration beyond the gap, df/ddelta' = c, all three 0 in mode 0.

Which flank is in contact (the mode) is part of the law's input:

* contacts switched at located events (p = 1, or any damped contact: the force jumps at
  the gap) get the mode the integrator holds; between a crossing and its located event
  the law is the smooth continuation of that mode's branch (p = 1: the linear branch
  extended beyond the gap; p > 1: no stiffness force beyond it, damping still on);
* smooth contacts (p > 1 and no damping: f is C1 at the gap, :func:`smooth_contacts`)
  take the mode from the sign of delta - gap (:func:`contact_mode`), as does
  post-processing, which has no integrator mode.

:func:`contact_force` is the compiled scalar law the kernels inline; :func:`evaluate`
and :func:`evaluate_set` are the numpy wrappers (vectorised over contacts and samples)
every non-compiled caller uses; they run the same compiled law.  The kernels that inline
the law are recompiled when this module changes (:mod:`vibrogear.models.numba_cache`).
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import njit

from . import numba_cache  # noqa: F401  (joint cache stamps, before any compiled call)

__all__ = ["power", "contact_mode", "resolve_mode", "contact_force", "smooth_contacts",
           "ContactForces", "evaluate", "evaluate_set", "flank", "harmonic_series"]


@njit(cache=True, inline="always", _nrt=False)
def power(s, p):
    """s**p for s > 0, with the common contact exponents done without pow()."""
    if p == 1.5:
        return s * np.sqrt(s)
    if p == 2.0:
        return s * s
    return np.exp(p * np.log(s))


@njit(cache=True, inline="always", _nrt=False)
def contact_mode(delta, g_hi, g_lo):
    """Mode from the sign: +1 beyond the upper gap, -1 beyond the lower gap, else 0."""
    if delta > g_hi:
        return 1
    if delta < g_lo:
        return -1
    return 0


@njit(cache=True, inline="always", _nrt=False)
def resolve_mode(mode, smooth, delta, g_hi, g_lo):
    """The mode the law runs in: the held ``mode``, or the sign's for a smooth contact."""
    if smooth:
        return contact_mode(delta, g_hi, g_lo)
    return mode


@njit(cache=True, inline="always", _nrt=False)
def contact_force(mode, delta, delta_dot, k_hi, k_lo, g_hi, g_lo, p, c, mu):
    """(f, df/ddelta, df/ddelta') of the law in ``mode`` (module docstring)."""
    if mode == 0:
        return 0.0, 0.0, 0.0
    if mode > 0:
        sgn = 1.0
        s = delta - g_hi
        k = k_hi * mu
    else:
        sgn = -1.0
        s = g_lo - delta
        k = k_lo * mu
    if p == 1.0:
        f = sgn * k * s
        kd = k
    elif s > 0.0:
        fs = k * power(s, p)
        f = sgn * fs
        kd = p * fs / s
    else:
        f = 0.0
        kd = 0.0
    return f + c * delta_dot, kd, c


def smooth_contacts(exponent, damping) -> np.ndarray:
    """Contacts whose force is C1 at the gap (p > 1, undamped): mode from the sign."""
    return (np.asarray(exponent) > 1.0) & (np.asarray(damping) == 0.0)


@njit(cache=True)
def _evaluate(mode, smooth, delta, ddot, k_hi, k_lo, g_hi, g_lo, p, c, mu, f, kd, cd, md):
    for i in range(delta.shape[0]):
        m = resolve_mode(mode[i], smooth[i], delta[i], g_hi[i], g_lo[i])
        f[i], kd[i], cd[i] = contact_force(m, delta[i], ddot[i], k_hi[i], k_lo[i], g_hi[i],
                                           g_lo[i], p[i], c[i], mu[i])
        md[i] = m


ContactForces = namedtuple("ContactForces", ["force", "stiffness", "damping", "mode"])
ContactForces.__doc__ = ("f, df/ddelta, df/ddelta' and the mode (-1, 0, +1) the law ran in, "
                         "each shaped like the broadcast inputs")


def evaluate(delta, delta_dot=0.0, *, k_hi, k_lo, gap_hi, gap_lo, exponent, damping=0.0,
             modulation=1.0, mode=None) -> ContactForces:
    """The law on numpy arrays (all arguments broadcast together).

    ``mode``: the held modes of contacts switched at events; None takes every mode from
    the sign.  Smooth contacts (:func:`smooth_contacts`) always take it from the sign."""
    held = np.zeros((), np.int64) if mode is None else np.asarray(mode, dtype=np.int64)
    smooth = smooth_contacts(exponent, damping) | (mode is None)
    args = np.broadcast_arrays(held, smooth, delta, delta_dot, k_hi, k_lo, gap_hi, gap_lo,
                               exponent, damping, modulation)
    shape = args[0].shape
    flat = [np.array(a, dtype=t).ravel() for a, t in   # copies: broadcast views are read-only
            zip(args, (np.int64, np.bool_) + (np.float64,) * 9)]
    n = flat[0].size
    f, kd, cd = np.empty(n), np.empty(n), np.empty(n)
    md = np.empty(n, np.int64)
    _evaluate(*flat, f, kd, cd, md)
    return ContactForces(*(a.reshape(shape) for a in (f, kd, cd, md)))


def evaluate_set(contacts, delta, delta_dot=0.0, modulation=1.0, mode=None) -> ContactForces:
    """The law of every contact of a :class:`~vibrogear.models.reduced.ContactSet`:
    ``delta`` (nc,) or (nc, n samples); ``delta_dot``, ``modulation``, ``mode`` broadcast."""
    delta = np.asarray(delta, dtype=float)
    col = (slice(None),) + (None,) * (delta.ndim - 1)
    ct = contacts
    return evaluate(delta, delta_dot, k_hi=ct.k_hi[col], k_lo=ct.k_lo[col],
                    gap_hi=ct.gap_hi[col], gap_lo=ct.gap_lo[col], exponent=ct.exponent[col],
                    damping=ct.damping[col], modulation=modulation, mode=mode)


def flank(delta, gap_hi, gap_lo) -> np.ndarray:
    """:func:`contact_mode` on numpy arrays (broadcast): +1, 0 or -1."""
    return evaluate(delta, k_hi=0.0, k_lo=0.0, gap_hi=gap_hi, gap_lo=gap_lo,
                    exponent=1.0).mode


def harmonic_series(amp_cos, amp_sin, frequency, t, *, orders=None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """s(t) = sum_h a_h cos(n_h W t) + b_h sin(n_h W t) and s'(t), n_h = h = 1..H, or the
    first H of ``orders`` (a model's harmonic_orders).

    ``amp_cos``, ``amp_sin``: (..., H) (the shorter is zero-padded); ``t``: (n,) or a
    scalar.  Returns two arrays (..., n) (the transmission error e(t) and its rate, or
    mu(t) - 1 of the stiffness modulation)."""
    a = np.atleast_1d(np.asarray(amp_cos, dtype=float))
    b = np.atleast_1d(np.asarray(amp_sin, dtype=float))
    H = max(a.shape[-1], b.shape[-1])
    a = np.pad(a, [(0, 0)] * (a.ndim - 1) + [(0, H - a.shape[-1])])
    b = np.pad(b, [(0, 0)] * (b.ndim - 1) + [(0, H - b.shape[-1])])
    n = np.arange(1.0, H + 1.0) if orders is None else np.asarray(orders, float)[:H]
    hW = n * float(frequency)
    phase = np.multiply.outer(hW, np.atleast_1d(np.asarray(t, dtype=float)))   # (H, n)
    cos, sin = np.cos(phase), np.sin(phase)
    return a @ cos + b @ sin, (b * hW) @ cos - (a * hW) @ sin
