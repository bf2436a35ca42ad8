"""Motion classes with evidence (the rattle / contact metrics of a sweep point:
:mod:`.record_metrics`).

A class is a claim about the quantities an engineer reads, at a stated resolution: the
deformation and the force of every gear mesh (every two-sided contact) and of the monitored
contact (:func:`monitored_quantities`; a model without contacts: its first coordinate).
Each quantity's resolution is ``resolution_rel`` (default 1e-3) of its range over the
record window (dense samples, 16 per base period), but not below an absolute floor:
``resolution_length`` (1 nm) for a deformation, ``resolution_force`` (1 N) for a force
(models with physical units; the nondimensional impact pair has no floor)
(:func:`resolutions`, ``[sweep]``).  Bearings' rolling elements are not monitored: where
they switch contact at sub-nanometre amplitude without moving a mesh by its resolution,
the gearbox is periodic.  Bearing loads are not recorded by the sweep.

Motion classes (integer codes, :data:`MOTION_LEGEND`), relative to the excitation period
T (the common period of all forcing frequencies, ``ReducedModel.excitation_period``):

* ``PERIODIC`` (1): the stroboscopic samples (one per T) of every monitored quantity repeat
  within its resolution with a period n <= max_period (:func:`resolved_period`; n > 1
  only after a settled transient, not where the budget ran out), or the full state repeats
  within ``period_tol`` (:func:`classify_period`, the stricter test); ``period_n`` gives n;
* ``MULTI_FREQUENCY`` (6, "multi-frequency forced"): period 1 where the forcing has
  several frequencies (T spans ``period_multiple`` > 1 base periods), or, where the meshes'
  common period exceeds the limit and the samples are per mesh period
  (``multi_frequency``), no period and not chaotic: the response follows the forcing;
  seen one base period at a time it would look quasi-periodic;
* ``QUASI_PERIODIC`` (2): no period at the resolution, the transient stopped because its
  statistics settled, and the 95 % interval of the largest Lyapunov exponent reaches 0
  (on the record or on its rerun at rtol / 10);
* ``CHAOTIC`` (3): no period at the resolution, and the interval's lower bound exceeds 0,
  again when the same record is integrated at rtol / 10 and the estimate repeated on it
  (the caller passes ``floor`` 0 where it does, infinity where it does not);
* ``NOT_SETTLED`` (4): no period, not chaotic, and either the interval lies below 0 (the
  motion still converges: a transient longer than the budget, or a period > max_period)
  or the transient budget was used up;
* ``APERIODIC`` (5): no period, the transient stopped because its statistics settled,
  no exponent computed (``[sweep] lyapunov = false``);
* ``FAILED`` (0): the integration failed.

Per contact group (each gear mesh, i.e. each two-sided contact; each bearing, its
one-sided rolling-element contacts grouped by the name before ':') the period is
classified again on the group's own quantities (a mesh: its deformation and force at the
resolution; else, and for a bearing, its deformations and rates within period_tol): the loaded mesh can be period-1
while a free gear rattles; a group without a period of its own takes the point's class.
"""
from __future__ import annotations

import math

import numpy as np

from ...models.reduced import ReducedModel
from ...models.contact_law import evaluate, harmonic_series
from ..integrator.contact_eval import contact_kinematics
from .record_metrics import contact_key

__all__ = ["FAILED", "PERIODIC", "QUASI_PERIODIC", "CHAOTIC", "NOT_SETTLED", "APERIODIC",
           "MULTI_FREQUENCY", "MOTION_LEGEND", "monitored_quantities", "resolutions",
           "resolved_period", "period_defect", "monitored_name", "motion_class",
           "classify_period", "count_clusters", "monitored_deformation", "best_defect"]

FAILED, PERIODIC, QUASI_PERIODIC, CHAOTIC, NOT_SETTLED, APERIODIC, MULTI_FREQUENCY = range(7)
MOTION_LEGEND = ("failed", "periodic", "quasi-periodic", "chaotic", "not settled",
                 "not periodic (no exponent)", "multi-frequency forced")


def motion_class(period_n: int, ci=(math.nan, math.nan), *, budget_used: bool = False,
                 failed: bool = False, floor: float = 0.0, period_multiple: int = 1,
                 multi_frequency: bool = False) -> int:
    """The class code of a point (module docstring) from its period (in excitation
    periods), the exponent's interval ``ci`` (NaN: not computed), the exponent's noise
    floor ``floor`` (same unit; chaotic only where the interval's lower bound exceeds it),
    whether the transient budget ran out and the base periods per excitation period
    ``period_multiple`` (> 1: a forcing of several frequencies, whose period-1 response is
    multi-frequency forced; ``multi_frequency``: the samples are per mesh period of a
    forcing with no common period within the limit, so a response that follows it without
    chaos is multi-frequency forced)."""
    if failed:
        return FAILED
    if period_n > 0:
        return MULTI_FREQUENCY if period_n == 1 and period_multiple > 1 else PERIODIC
    lo, hi = (float(c) for c in ci)
    if math.isfinite(lo) and math.isfinite(hi):
        if lo > 0.0 and not lo <= float(floor):
            return CHAOTIC
        if multi_frequency:
            return MULTI_FREQUENCY
        if hi < 0.0 or budget_used:
            return NOT_SETTLED
        return QUASI_PERIODIC
    if multi_frequency:
        return MULTI_FREQUENCY
    return NOT_SETTLED if budget_used else APERIODIC


# ---------------------------------------------------------------- periodicity

def monitored_deformation(model: ReducedModel, param: float, t, states) -> np.ndarray:
    """delta_mon = c_mon . x - e_mon(t) at times ``t`` for states (len(t), 2m)."""
    states = np.atleast_2d(states)
    if model.contacts.count == 0:
        return states[:, 0].copy()
    ct, j = model.contacts, model.monitor      # delta alone (not its rate, not mu)
    e = harmonic_series(ct.error_cos[j], ct.error_sin[j], model.excitation_frequency(param),
                        t, orders=model.harmonic_orders)[0]
    return states[:, :model.n_modes] @ ct.directions[j] - e


def block_scaled(samples: np.ndarray, split: int | None, ref=None) -> np.ndarray:
    """Samples divided by block scales (largest |value| in each block of ``ref``, default
    the samples themselves; tiny floor)."""
    s = np.asarray(samples, dtype=float)
    if s.ndim == 1:
        s = s[:, None]
    r = s if ref is None else np.asarray(ref, dtype=float).reshape(-1, s.shape[1])
    blocks = [slice(0, s.shape[1])] if not split else [slice(0, split), slice(split, None)]
    out = np.empty_like(s)
    for b in blocks:
        sc = float(np.max(np.abs(r[:, b]), initial=0.0))
        out[:, b] = s[:, b] / (sc if sc > 1e-300 else 1.0)
    return out


def classify_period(samples, max_period: int, period_tol: float, *,
                    split: int | None = None) -> tuple[int, float]:
    """(n, defect): smallest n <= max_period with max_k |P_{k+n} - P_k| <= period_tol.

    ``samples`` (R,) or (R, n) stroboscopic samples; ``split``: index where the velocity
    block starts (the two blocks are scaled separately).  Differences are measured in
    units of each block's largest |value|.  Returns (0, nan) when no n qualifies or the
    samples are not finite.
    """
    s = np.asarray(samples, dtype=float)
    if s.ndim == 1:
        s = s[:, None]
    if s.shape[0] < 2 or not np.all(np.isfinite(s)):
        return 0, math.nan
    z = block_scaled(s, split)
    defects = {}
    for n in range(1, min(int(max_period), s.shape[0] - 1) + 1):
        defects[n] = float(np.max(np.abs(z[n:] - z[:-n])))
        if defects[n] > period_tol:
            continue
        # a genuine period-n cycle is resolved from every shorter divisor cycle; a slowly
        # decaying transient can pass at n > 1 by aliasing while n = 1 nearly passes
        if all(defects[d] > 10.0 * period_tol for d in range(1, n) if n % d == 0):
            return n, defects[n]
    return 0, math.nan


def count_clusters(samples, rel_tol: float = 1e-3, *, split: int | None = None) -> int:
    """Number of distinct Poincare clusters (greedy, inf-norm radius ``rel_tol`` in scaled
    units).  Period-n motion gives n; quasi-periodic or chaotic motion gives many."""
    s = np.asarray(samples, dtype=float)
    if s.ndim == 1:
        s = s[:, None]
    if s.shape[0] == 0 or not np.all(np.isfinite(s)):
        return 0
    z = block_scaled(s, split)
    centres = np.empty_like(z)      # greedy, in sample order; one array op per sample
    k = 0
    for p in z:
        if k == 0 or not np.any(np.max(np.abs(centres[:k] - p), axis=1) <= rel_tol):
            centres[k] = p
            k += 1
    return k


def best_defect(samples, max_period: int) -> float:
    """min over n <= max_period of max_k |P_{k+n} - P_k| (raw units, inf-norm): the
    distance of the stroboscopic samples from the nearest period.  It shrinks while a
    transient decays and stays put on a quasi-periodic or chaotic attractor; compare it
    between windows of one run (it carries the samples' units)."""
    s = np.asarray(samples, dtype=float)
    if s.ndim == 1:
        s = s[:, None]
    d = [float(np.max(np.abs(s[n:] - s[:-n]))) for n in range(1, min(int(max_period),
                                                                   s.shape[0] - 1) + 1)]
    return min(d) if d else math.nan


# ---------------------------------------------------------------- engineering resolution

def _monitored_rows(model: ReducedModel) -> dict:
    """{name: contact index} of the quantities an engineer reads: every two-sided contact
    (a gear mesh, the impact pair's clearance) and the monitored contact."""
    ct = model.contacts
    names = ct.names or tuple(f"c{j}" for j in range(ct.count))
    rows = {}
    for j in range(ct.count):
        if np.isfinite(ct.gap_lo[j]) or j == model.monitor:
            key = contact_key(names[j])
            while key in rows:
                key += "_"
            rows[key] = j
    return rows


def monitored_name(model: ReducedModel) -> str:
    """The monitored deformation's name among :func:`monitored_quantities`
    (``delta_<contact>``; ``x0`` without contacts)."""
    if model.contacts.count == 0:
        return "x0"
    return "delta_" + next(k for k, j in _monitored_rows(model).items() if j == model.monitor)


def monitored_quantities(model: ReducedModel, param: float, t, states) -> dict:
    """{name: (values (len(t),), kind)} at times ``t`` for states (len(t), 2m): the
    deformation (``delta_<mesh>``, kind "length") and the contact-law force
    (``force_<mesh>``, kind "force", in the model's force unit) of every gear mesh and of
    the monitored contact; a model without contacts: its first coordinate ``x0``."""
    states = np.atleast_2d(np.asarray(states, dtype=float))
    if model.contacts.count == 0:
        return {"x0": (states[:, 0].copy(), "length")}
    rows = _monitored_rows(model)
    idx = np.array(list(rows.values()), dtype=int)
    d, dd, mu = contact_kinematics(model, param, t, states, rows=idx)
    ct = model.contacts
    col = (slice(None), None)
    f = evaluate(d, dd, k_hi=ct.k_hi[idx][col], k_lo=ct.k_lo[idx][col],
                 gap_hi=ct.gap_hi[idx][col], gap_lo=ct.gap_lo[idx][col],
                 exponent=ct.exponent[idx][col], damping=ct.damping[idx][col],
                 modulation=mu).force
    out = {}
    for i, key in enumerate(rows):
        out[f"delta_{key}"] = (d[i], "length")
        out[f"force_{key}"] = (f[i], "force")
    return out


def resolutions(model: ReducedModel, ranges: dict, kinds: dict, *, rel: float = 1e-3,
                length_m: float = 1e-9, force_n: float = 1.0) -> dict:
    """{name: resolution}: ``rel`` times the quantity's range over the record plus nothing
    below an absolute floor, ``length_m`` [m] for a deformation and ``force_n`` [N] for a
    force, converted to the model's units (a model without physical units, the impact
    pair's, has no absolute floor: there the resolution is ``rel`` of the range alone)."""
    physical = model.length_unit == "m"
    floors = {"length": length_m if physical else 0.0,
              "force": force_n / model.force_unit_n if physical else 0.0}
    return {k: max(rel * float(r), floors[kinds[k]]) for k, r in ranges.items()}


def resolved_period(samples: dict, res: dict, max_period: int) -> tuple[int, float]:
    """(n, defect): the smallest n <= max_period at which the stroboscopic samples of
    every quantity agree with those n periods later within its resolution:
    max_k |q_{k+n} - q_k| <= res_q for every q of ``samples`` {name: (R,)} (and, for n > 1,
    differ at each divisor of n by more than 10 resolutions); ``defect``
    the largest of those differences in units of the resolution (<= 1).  Where no n
    qualifies: (0, the least over n of that largest difference, > 1: how many resolutions
    the samples spread); (0, nan) when a sample is not finite.""" 
    qs = [np.asarray(v, dtype=float).ravel() for v in samples.values()]
    if not qs or qs[0].size < 2 or not all(np.all(np.isfinite(q)) for q in qs):
        return 0, math.nan
    R = qs[0].size
    scale = [float(res[k]) for k in samples]
    best, worst_at = math.inf, {}
    for n in range(1, min(int(max_period), R - 1) + 1):
        worst = 0.0
        for q, r in zip(qs, scale):
            d = float(np.max(np.abs(q[n:] - q[:-n])))
            worst = max(worst, d / r if r > 0 else (0.0 if d == 0 else math.inf))
        worst_at[n] = worst
        best = min(best, worst)
        # as classify_period: a period-n cycle is resolved from each shorter divisor cycle
        # by 10 resolutions; a slowly decaying free vibration whose frequency is a rational
        # multiple of the excitation's passes at n > 1 while n = 1 nearly passes
        if worst <= 1.0 and all(worst_at[d] > 10.0 for d in range(1, n) if n % d == 0):
            return n, worst
    return 0, best


def period_defect(samples, n: int, *, split: int | None = None) -> float:
    """max_k |P_{k+n} - P_k| of the full-state samples in units of each block's largest
    |value| (:func:`classify_period`'s measure) at a given period n."""
    s = np.asarray(samples, dtype=float)
    if s.ndim == 1:
        s = s[:, None]
    if n < 1 or s.shape[0] <= n:
        return math.nan
    z = block_scaled(s, split)
    return float(np.max(np.abs(z[n:] - z[:-n])))
