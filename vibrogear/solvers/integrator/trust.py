"""Whether a finished integration can be trusted: the checks every run passes before it is
called ok.

The compiled loop stops only on hard failures (non-finite state, step underflow,
chattering).  A run at a tolerance the model cannot use may still finish with finite
numbers that mean nothing: the error controller lets the stiff modes carry noise of the
size of the tolerance, the contacts see it as spurious impacts, and the state can grow
without bound.  :func:`assess` judges the finished run on three pieces of evidence the
loop returns, cheapest first:

1. **Physical bounds** (:data:`Status.DIVERGED`).  No contact deformation may exceed
   ``max_deformation`` times its physical scale: the dead zone's width (a mesh's backlash),
   plus the static deflection under the mean load (:func:`~.static.static_equilibrium`),
   plus the kinematic error's amplitude, plus the resonant response of every master mode
   to the harmonic forcing (its amplitude over modal damping times frequency; a forced
   undamped or rigid mode leaves the contacts it moves without a bound).  In an undriven system with non-negative damping
   (no harmonic forcing, no kinematic error, no stiffness modulation, a symmetric
   spin-free coupling) the mechanical energy may not grow.
2. **Event storms** (:data:`Status.INACCURATE`).  More than ``max_events_per_period``
   contact events per contact and excitation period: contacts switching on integration
   noise, not on the motion.
3. **The error estimate** (:data:`Status.INACCURATE`).  The sum of the local error
   estimates (a bound of the global error while errors do not grow along the flow) per
   excitation period above ``max_error`` times the solution's size (the RMS norm of the
   larger of the start and end states).  Per period, not in total: in a damped, stable
   motion the error made in one period decays over the next few, so the total of a long
   run overstates the error by the run's length (a 400-period run at a tolerance that is
   accurate over 20 periods would otherwise fail).

Each failure message names the tolerance in use and says to tighten it, to a value strictly
tighter and never the built-in default (:func:`advised_rtol`: a scene that writes the default
reads as one that writes none, and its sweep would run at the accuracy rule's looser rtol
again); a divergence of a free model (:func:`free_body`) says so and advises no tolerance.  The loosest rtol
the model can use is found by :func:`vibrogear.solvers.integrator.rtol_limit.loosest_rtol`.
"""
from __future__ import annotations

import math
import weakref
from dataclasses import replace

import numpy as np

from ...config.options import IntegrationOptions
from ...models.reduced import Forcing, ReducedModel
from ...status import Status

__all__ = ["assess", "deformation_scale", "mechanical_energy", "is_undriven", "advised_rtol",
           "free_body", "DEFAULT_RTOL"]

_SCALE: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
_UNDRIVEN: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _gap_width(ct) -> np.ndarray:
    """Per contact: the dead zone's width where both gaps are finite, else the finite gap."""
    hi, lo = np.asarray(ct.gap_hi, dtype=float), np.asarray(ct.gap_lo, dtype=float)
    two = np.isfinite(hi) & np.isfinite(lo)
    width = np.where(two, np.abs(hi - np.where(two, lo, 0.0)), 0.0)
    one = np.where(np.isfinite(hi), np.abs(hi), 0.0)
    return np.where(two, width, one)


def deformation_scale(model: ReducedModel) -> np.ndarray:
    """(nc,) the physical size of each contact's deformation: gap width + |static
    deflection| + kinematic-error amplitude + resonant forced response (cached per model)."""
    got = _SCALE.get(model)
    if got is not None:
        return got
    from ..static import static_equilibrium     # local: static imports this layer's status

    ct = model.contacts
    te = np.sum(np.hypot(ct.error_cos, ct.error_sin), axis=1) if ct.count else np.zeros(0)
    st = static_equilibrium(model, 0.0)
    static = np.abs(ct.directions @ st.x) if st.converged else np.zeros(ct.count)
    scale = _gap_width(ct) + static + te + _resonant(model, st.x if st.converged else None)
    _SCALE[model] = scale
    return scale


def _resonant(model: ReducedModel, x_static=None) -> np.ndarray:
    """(nc,) the largest deformation the harmonic forcing can drive through each contact
    if every master mode resonated at once: sum_i |c_ji| |F_i| / (d_i w_i) over the damped
    elastic modes (inf where an undamped elastic mode is forced: no bound); where the
    forcing also drives a mode without modal stiffness (a shaft's rigid rotation, held by
    a coupling spring in the low-rank part: a torque order), the static response to each
    forcing vector through the whole model, amplified by 1 / (2 zeta_min) of the damped
    modes.  The mesh stiffness variation counts as a forcing too: at the static state
    ``x_static`` a contact carrying the force f_j with relative stiffness harmonics a_jh
    is driven by up to f_j sum_h |a_jh| along its direction (without it, a rolling element
    at the edge of its load zone, deflected by nanometres statically, was bounded by
    nanometres while every stage's mesh excited it)."""
    ct, f = model.contacts, model.forcing
    if not ct.count:
        return np.zeros(0)
    amp = np.sum(np.abs(f.Fc), axis=0) + np.sum(np.abs(f.Fs), axis=0)
    mod = np.sum(np.hypot(ct.stiffness_cos, ct.stiffness_sin), axis=1)
    if x_static is not None and np.any(mod > 0.0):
        d = ct.directions @ x_static
        over = np.maximum(d - ct.gap_hi, 0.0)
        under = np.where(np.isfinite(ct.gap_lo), np.maximum(ct.gap_lo - d, 0.0), 0.0)
        f_static = ct.k_hi * over ** ct.exponent + ct.k_lo * under ** ct.exponent
        amp = amp + np.abs(ct.directions).T @ (f_static * mod)
    w = np.sqrt(np.maximum(model.omega2, 0.0))
    damped = (w > 0.0) & (model.damping > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        per_mode = np.where((amp > 0.0) & damped, amp / (model.damping * w), 0.0)
    out = np.abs(ct.directions) @ per_mode
    forced = amp > 0.0
    if np.any(forced & (w > 0.0) & ~damped) or (np.any(forced & (w == 0.0)) and not damped.any()):
        return np.full(ct.count, np.inf)        # an undamped forced mode: no bound
    if np.any(forced & (w == 0.0)):
        zeta = np.min(model.damping[damped] / (2.0 * w[damped]))
        out = out + _static_response(model) / (2.0 * min(zeta, 0.5))
    return out


def _static_response(model: ReducedModel) -> np.ndarray:
    """(nc,) sum over the forcing vectors (each Fc_h, Fs_h) of |c_j . (x(F0 + F) - x(F0))|,
    the static equilibria at rest (inf where one does not converge)."""
    from ..static import static_equilibrium     # local: static imports this layer's status

    f, ct = model.forcing, model.contacts
    base = static_equilibrium(model, 0.0)
    if not base.converged:
        return np.full(ct.count, np.inf)
    out = np.zeros(ct.count)
    for vec in (*f.Fc, *f.Fs):
        if not np.any(vec):
            continue
        loaded = replace(model, forcing=Forcing(f.F0 + vec, 0.0 * f.Fc, 0.0 * f.Fs))
        st = static_equilibrium(loaded, 0.0, x0=base.x)
        if not st.converged:
            return np.full(ct.count, np.inf)
        out += np.abs(ct.directions @ (st.x - base.x))
    return out


def is_undriven(model: ReducedModel, param: float) -> bool:
    """No harmonic forcing, kinematic error or stiffness modulation, damping >= 0 and a
    symmetric coupling without spin terms: its mechanical energy can only decrease."""
    got = _UNDRIVEN.get(model)
    if got is None:
        f, ct, cp = model.forcing, model.contacts, model.coupling
        passive = (not np.any(f.Fc) and not np.any(f.Fs) and not np.any(ct.error_cos)
                   and not np.any(ct.error_sin) and not np.any(ct.stiffness_cos)
                   and not np.any(ct.stiffness_sin) and bool(np.all(model.damping >= 0.0))
                   and bool(np.all(ct.damping >= 0.0)) and np.allclose(cp.Kc0, cp.Kc0.T)
                   and (cp.Bc0.size == 0 or bool(np.all(
                       np.linalg.eigvalsh(cp.Bc0 + cp.Bc0.T)
                       >= -1e-12 * max(1.0, float(np.abs(cp.Bc0).max()))))))
        spin_free = not np.any(cp.Kc1) and not np.any(cp.Bc1)
        got = _UNDRIVEN[model] = (passive, spin_free)
    passive, spin_free = got
    return passive and (spin_free or model.spin_per_param * param == 0.0)


def mechanical_energy(model: ReducedModel, u: np.ndarray) -> float:
    """Kinetic + modal and coupling strain + contact potential - work of the mean load
    (for :func:`is_undriven` models: the contact law's potential k s^(p+1) / (p+1))."""
    m = model.n_modes
    x, v = u[:m], u[m:]
    ct, cp = model.contacts, model.coupling
    e = 0.5 * v @ v + 0.5 * x @ (model.omega2 * x) - model.forcing.F0 @ x
    if cp.P.shape[0]:
        y = cp.P @ x
        e += 0.5 * y @ (cp.Kc0 @ y)
    if ct.count:
        d = ct.directions @ x
        p = ct.exponent
        over = np.maximum(d - ct.gap_hi, 0.0)
        under = np.where(np.isfinite(ct.gap_lo), np.maximum(ct.gap_lo - d, 0.0), 0.0)
        e += float(np.sum(ct.k_hi * over ** (p + 1) / (p + 1)
                          + ct.k_lo * under ** (p + 1) / (p + 1)))
    return float(e)


#: the built-in [integration] rtol: a scene that writes exactly this value cannot be told
#: from one that writes none (the accuracy rule of a sweep or time response then applies),
#: so advice never names it
DEFAULT_RTOL = IntegrationOptions.__dataclass_fields__["rtol"].default


def advised_rtol(rtol: float) -> float:
    """The rtol to advise after a failure at ``rtol``: two decades tighter, never the
    built-in default (it would read as "not given" and bring back the rule's looser rtol:
    the advice would loop), so always strictly tighter than the one in use."""
    advice = float(f"{rtol / 100:.1g}")
    if math.isclose(advice, DEFAULT_RTOL, rel_tol=1e-9):
        advice = DEFAULT_RTOL / 10
    return advice


def _tighten(options: IntegrationOptions) -> str:
    return (f"rtol {options.rtol:.3g}: tighten [integration] rtol (the section's own rtol "
            f"where it has one), e.g. to {advised_rtol(options.rtol):.1g} (an [integration] "
            f"rtol equal to the default {DEFAULT_RTOL:g} counts as not given)")


def free_body(model: ReducedModel) -> str:
    """Why the model's motion has no bound whatever the tolerance ("" when none is found):
    no static equilibrium under the mean load (a free body the load moves).  A gearbox whose
    load bypasses its meshes (a shaft that slides or turns off its load) is refused before
    any dynamics (:mod:`vibrogear.analyses.static_load`), so it never reaches this check."""
    from ..static import static_equilibrium     # local: static imports this layer's status

    if not np.any(model.forcing.F0):
        return ""
    if not static_equilibrium(model, 0.0).converged:
        return ("the model has no static equilibrium under its mean load: the load moves a "
                "body that nothing holds (a shaft free along the load's direction)")
    return ""


def _free_message(reason: str) -> str:
    return (f"{Status.DIVERGED.message}: {reason}; no integration tolerance changes this: "
            "run `vibrogear check` on the scene, which names the shaft, the direction and "
            "the bearing to fix")


def assess(model: ReducedModel, param: float, u0: np.ndarray, u_end: np.ndarray,
           u_eval: np.ndarray, t0: float, t1: float, error_estimate: float, events: int,
           monitor_range: tuple[float, float], options: IntegrationOptions
           ) -> tuple[Status, str, float]:
    """(status, message, relative error estimate) of a run the loop finished: OK, or
    DIVERGED / INACCURATE with the evidence and the tolerance to tighten."""
    ct = model.contacts
    n = u0.shape[0]
    size = np.sqrt(max(float(u0 @ u0), float(u_end @ u_end)) / n)
    rel = error_estimate / (size + options.atol)
    if ct.count:
        m = model.n_modes
        bound = options.max_deformation * deformation_scale(model)
        worst = np.abs(ct.directions @ u_end[:m])
        if u_eval.size:
            worst = np.maximum(worst, np.max(np.abs(u_eval[:, :m] @ ct.directions.T), axis=0))
        lo, hi = monitor_range
        if math.isfinite(lo) and math.isfinite(hi):  # the monitored extrema see between samples
            te = float(np.sum(np.hypot(ct.error_cos[model.monitor], ct.error_sin[model.monitor])))
            worst[model.monitor] = max(worst[model.monitor], max(abs(lo), abs(hi)) - te)
        over = np.flatnonzero((worst > bound) & (bound > 0.0))      # inf bound: none
        if over.size:
            reason = free_body(model)
            if reason:
                return Status.DIVERGED, _free_message(reason), rel
            j = int(over[np.argmax(worst[over] / bound[over])])
            name = ct.names[j] if j < len(ct.names) else f"contact {j}"
            return (Status.DIVERGED,
                    f"{Status.DIVERGED.message}: the deformation of {name} reached "
                    f"{worst[j]:.3g}, {worst[j] / bound[j] * options.max_deformation:.3g} "
                    f"times its physical scale {bound[j] / options.max_deformation:.3g} "
                    f"(gap + static deflection + kinematic error; the limit is "
                    f"{options.max_deformation:g} times); {_tighten(options)}", rel)
    if is_undriven(model, param):
        e0, e1 = mechanical_energy(model, u0), mechanical_energy(model, u_end)
        slack = 1e-6 * max(abs(e0), abs(e1)) + 10.0 * error_estimate * (size + 1e-300)
        if e1 > e0 + slack and abs(e1 - e0) > 1e-3 * abs(e0):
            reason = free_body(model)
            if reason:
                return Status.DIVERGED, _free_message(reason), rel
            return (Status.DIVERGED,
                    f"{Status.DIVERGED.message}: the energy of an undriven, damped system "
                    f"grew from {e0:.6g} to {e1:.6g}; {_tighten(options)}", rel)
    W = model.excitation_frequency(param)
    periods = (t1 - t0) * W / (2.0 * np.pi) if W > 0.0 else 1.0
    if ct.count and W > 0.0:
        limit = options.max_events_per_period * ct.count * max(periods, 1.0)
        if events > limit:
            return (Status.INACCURATE,
                    f"{Status.INACCURATE.message}: {events} contact events in "
                    f"{periods:.4g} excitation periods, more than "
                    f"{options.max_events_per_period:g} per contact and period (the contacts "
                    f"switch on integration noise); {_tighten(options)}", rel)
    rate = rel / max(periods, 1.0)
    if rate > options.max_error:
        return (Status.INACCURATE,
                f"{Status.INACCURATE.message}: the accumulated error estimate "
                f"{error_estimate:.3g} is {rate:.3g} of the solution's size {size:.3g} per "
                f"excitation period (limit {options.max_error:g}); {_tighten(options)}", rel)
    return Status.OK, Status.OK.message, rel
