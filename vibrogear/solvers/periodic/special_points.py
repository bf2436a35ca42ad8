"""Special points of a continuation branch: locating a test function's zero between two
points (regula falsi in arclength, :func:`locate`), and reading an orbit's contact pattern
(:func:`switch_counts`, :func:`grazing_note`: where it changes between two orbits a contact
interval appears or vanishes, a grazing bifurcation at which the flow is not
differentiable and smooth continuation ends)."""
from __future__ import annotations

import numpy as np

from .corrector import correct, tangent
from .floquet import test_functions

__all__ = ["COARSE_LOCATE_ITER", "locate", "switch_counts", "grazing_note"]

#: regula-falsi steps for a crossing that changes no stability (an NS or PD on an orbit
#: already unstable on both sides): one orbit near the linear interpolation of the test
#: function, its bracket reported (``BranchPoint.located_within``); full location cost
#: 5.5 orbits with the monodromy per special point on the two-stage branch (24 NS, 5 PD)
COARSE_LOCATE_ITER = 1


def locate(prob, za, ta, ds_total, fa, fb, which, options, p_b, k_ref=None, J0=None,
           max_iter=None):
    """Regula falsi (Illinois) in arclength between point a (test value ``fa``, s = 0)
    and the next point (``fb``, s = ds_total, parameter ``p_b``) for the zero of test
    function ``which``; ``J0``: point a's bordered Jacobian (the corrector's quasi-Newton
    start); ``max_iter``: instead of the method's ``locate_iter``.  Returns
    (z, flow, tangent, iterations, residual, within) of the last point computed, or None;
    ``within``: the parameter width of the final interval that holds the zero, or where the
    regula-falsi iterates settled first, their last change."""
    locate_tol = prob.method.locate_tol
    lo, hi = 0.0, ds_total
    f_lo, f_hi = fa, fb
    p_lo, p_hi = za[-1] * prob.scale, p_b
    best = None
    side = 0
    last = p_last = None
    for _ in range(max_iter or prob.method.locate_iter):
        if f_hi != f_lo:
            mid = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        else:
            mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            mid = 0.5 * (lo + hi)
        got = correct(prob, za + mid * ta, ta, options.max_corrector_iter, k_ref, J0)
        if got is None:
            break
        z, f, it, res = got
        t = tangent(prob.jac(f), ta)
        val = test_functions(f.monodromy, t, k_ref or 0, f.multipliers())[which]
        if np.sign(val) == np.sign(f_lo):
            lo, f_lo, p_lo = mid, val, z[-1] * prob.scale
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi, p_hi = mid, val, z[-1] * prob.scale
            if side == 1:
                f_lo *= 0.5
            side = 1
        p_mid = z[-1] * prob.scale
        within = abs(p_hi - p_lo)
        # the bracket, or the located point itself, settled (1e-6 / locate_tol of the step)
        if hi - lo < 1e-6 * ds_total or abs(val) < 1e-9:
            best = (z, f, t, it, res, within)
            break
        if last is not None and abs(mid - last) < locate_tol * ds_total:
            # the iterates settled: their last change measures the location
            best = (z, f, t, it, res, min(within, abs(p_mid - p_last)))
            break
        best = (z, f, t, it, res, within)
        last, p_last = mid, p_mid
    return best


def switch_counts(model, trajectory) -> np.ndarray:
    """Contact switches per contact over an orbit (two per contact interval)."""
    n = min(trajectory.events, trajectory.event_contacts.size)
    return np.bincount(trajectory.event_contacts[:n], minlength=model.contacts.count)


def grazing_note(model, before, after) -> str:
    """The contacts whose switches per orbit differ between ``before`` and ``after``
    (:func:`switch_counts`), in words; "" where none does."""
    names = model.contacts.names
    return "; ".join(f"{names[j] if names else f'contact {j}'}: {before[j]} -> {after[j]} "
                     f"contact switches per orbit" for j in np.flatnonzero(before != after))
