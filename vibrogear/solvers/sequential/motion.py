"""Motion classes with evidence and the rattle / contact metrics of a sweep point.

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

Contact metrics over a record window of P excitation periods, from the integrator's
located contact events (exact switch times) and the contact law's modes:

* ``impacts_drive_<g>`` / ``impacts_back_<g>``: contact onsets on the upper (drive,
  delta > gap_hi) / lower (back, delta < gap_lo) flank per base excitation period
  2 pi / W (a gearbox's: the mesh period of its first mesh, also where a torque order
  makes the excitation period a multiple of it; other meshes are counted per that
  period too);
* ``impact_velocity_rms_<g>`` / ``impact_velocity_max_<g>``: RMS and largest normal
  approach speed |delta'| at those onsets, in the model's length unit per second (m/s for
  a gearbox; ``ReducedModel.time_unit_s``);
* ``contact_fraction_<g>``: fraction of the time in contact (mode != 0);
* ``rattle_<g>``: impact energy per period, sum over onsets of m_eff v^2 / 2 divided by
  P, with m_eff = 1 / (c . c) the effective mass of the contact direction c in the
  model's mass-normalised modal coordinates, converted with the model's force unit
  (energy = force x length: J for a gearbox; model units for a nondimensional model);
* ``unloaded_<bearing>``: mean number of its rolling elements out of contact.

Each metric has an ``_err`` companion: the standard error of its mean over up to 8
consecutive blocks of the record window (batch means, s / sqrt(B); blocks of whole
multiples of the period for a periodic point, where it is ~0), so that chaotic points
report statistics with an error that shrinks as the record grows.
"""
from __future__ import annotations

import math
import re

import numpy as np

from ...models.reduced import ReducedModel
from ...models.contact_law import evaluate, harmonic_series
from ..integrator.contact_eval import contact_kinematics

__all__ = ["FAILED", "PERIODIC", "QUASI_PERIODIC", "CHAOTIC", "NOT_SETTLED", "APERIODIC",
           "MULTI_FREQUENCY", "MOTION_LEGEND", "monitored_quantities", "resolutions",
           "resolved_period", "period_defect", "monitored_name", "motion_class",
           "contact_groups", "window_metrics", "metrics_with_errors", "classify_period", "count_clusters",
           "monitored_deformation", "best_defect", "deformation_statistics", "batch_blocks"]

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


def _key(name: str) -> str:
    return re.sub(r"[^0-9A-Za-z]+", "_", str(name)).strip("_") or "contact"


def contact_groups(model: ReducedModel) -> dict:
    """{key: ("mesh" | "bearing", contact indices)}: every two-sided contact alone (a
    gear mesh, the impact pair's clearance), one-sided contacts grouped by the part of
    their name before ':' (a bearing's rolling elements)."""
    ct = model.contacts
    out: dict = {}
    names = ct.names or tuple(f"c{j}" for j in range(ct.count))
    for j in range(ct.count):
        if np.isfinite(ct.gap_lo[j]):
            key = _key(names[j])
            while key in out:
                key += "_"
            out[key] = ("mesh", np.array([j]))
        else:
            key = "bearing_" + _key(str(names[j]).split(":")[0])
            kind, idx = out.get(key, ("bearing", np.zeros(0, int)))
            out[key] = (kind, np.append(idx, j).astype(int))
    return out


def _fractions(mode0, times, contacts_of, modes, t0: float, t1: float, rows) -> np.ndarray:
    """The fraction of [t0, t1] each contact in ``rows`` spends in contact (mode != 0),
    from the modes ``mode0`` at t0 and the events (``times``, ``contacts_of``, ``modes``)
    of all contacts in time order: every contact's mode segments, sorted by contact then
    time, their lengths summed per contact (contact by contact, a bearing's rolling
    elements cost 7 ms a sweep point on the two-stage gearbox)."""
    rows = np.asarray(rows, dtype=int)
    keep = np.isin(contacts_of, rows)
    c = np.concatenate([rows, np.asarray(contacts_of)[keep]])
    start = np.concatenate([np.full(rows.size, float(t0)), np.asarray(times)[keep]])
    mode = np.concatenate([np.asarray(mode0)[rows], np.asarray(modes)[keep]])
    order = np.lexsort((start, c))          # stable: a contact's segments in time order
    c, start, mode = c[order], start[order], mode[order]
    end = np.append(start[1:], t1)
    end[np.append(c[1:] != c[:-1], True)] = t1
    on = np.bincount(c, weights=(end - start) * (mode != 0),
                     minlength=int(rows.max(initial=-1)) + 1)
    return on[rows] / (t1 - t0)


def window_metrics(model: ReducedModel, groups: dict, mode0, events, onset_speed,
                   t0: float, t1: float, period: float, *, empty: float = 0.0) -> dict:
    """The metrics (module docstring) over [t0, t1]: ``mode0`` (nc,) the modes at t0,
    ``events`` (t, contact, new mode) of the window in time order, ``onset_speed`` (len
    events,) |delta'| at each event (NaN where not needed); ``empty``: the approach
    speeds of a mesh without impacts.  Counts and energies are per base period 2 pi / W
    (``period`` / model.period_multiple: the mesh period of a gearbox even where a
    torque order makes the excitation period longer)."""
    t, j, md = events
    speed = np.asarray(onset_speed, dtype=float)
    P = (t1 - t0) / period * model.period_multiple
    out = {}
    c2 = np.sum(model.contacts.directions ** 2, axis=1)
    per_s = 1.0 / model.time_unit_s          # approach speeds per second, not per model time
    joule = model.force_unit_n               # model energy (force x length) -> J
    # every group's contacts in one call (each contact's own segments summed)
    rows = [np.asarray(idx, dtype=int) for _, idx in groups.values()]
    rows = np.unique(np.concatenate(rows)) if rows else np.zeros(0, int)
    on = dict(zip(rows.tolist(), _fractions(mode0, t, j, md, t0, t1, rows))) if rows.size \
        else {}
    for key, (kind, idx) in groups.items():
        if kind == "mesh":
            c = int(idx[0])
            mine = j == c
            drive = mine & (md == 1)
            back = mine & (md == -1)
            onset = drive | back
            v = speed[onset] * per_s
            out[f"impacts_drive_{key}"] = float(np.sum(drive) / P)
            out[f"impacts_back_{key}"] = float(np.sum(back) / P)
            out[f"impact_velocity_rms_{key}"] = float(np.sqrt(np.mean(v ** 2))) if v.size \
                else empty
            out[f"impact_velocity_max_{key}"] = float(np.max(v)) if v.size else empty
            out[f"contact_fraction_{key}"] = float(on[c])
            energy = float(np.sum(0.5 * speed[onset] ** 2 / c2[c]) * joule)
            out[f"rattle_{key}"] = energy / P
            out[f"rattle_power_{key}"] = energy / ((t1 - t0) * model.time_unit_s)
        else:
            out[f"unloaded_{key}"] = float(np.sum(1.0 - np.array([on[int(c)] for c in idx])))
    return out


def metrics_with_errors(model: ReducedModel, groups: dict, mode0, events, onset_speed,
                        t0: float, t1: float, period: float, *, period_n: int = 0,
                        blocks: int = 8) -> dict:
    """:func:`window_metrics` over [t0, t1] and the ``_err`` companions: the standard
    error of the mean of the metric over at most ``blocks`` consecutive blocks of whole
    periods (multiples of ``period_n`` for a periodic point), s / sqrt(B) (batch means;
    two blocks: half their difference).  Speeds use the blocks that have impacts."""
    t, j, md = (np.asarray(a) for a in events)
    speed = np.asarray(onset_speed, dtype=float)
    full = window_metrics(model, groups, mode0, (t, j, md), speed, t0, t1, period)
    P = int(round((t1 - t0) / period))
    L, B = batch_blocks(P, period_n, blocks)
    if B < 2:
        return {**full, **{f"{k}_err": math.nan for k in full}}
    mode = np.array(mode0, dtype=int).copy()
    vals = {k: [] for k in full}
    for b in range(B):
        a, e = t0 + b * L * period, t0 + (b + 1) * L * period
        sel = (t >= a) & (t < e)
        w = window_metrics(model, groups, mode, (t[sel], j[sel], md[sel]), speed[sel], a, e,
                           period, empty=math.nan)
        for k, v in w.items():
            vals[k].append(v)
        for i in np.nonzero(sel)[0]:            # modes at the next block's start
            mode[j[i]] = md[i]
    err = {}
    for k, v in vals.items():
        v = np.asarray(v, dtype=float)
        v = v[np.isfinite(v)]
        if v.size >= 2:
            err[f"{k}_err"] = float(np.std(v, ddof=1) / math.sqrt(v.size))
        else:                                   # no impacts in any block: exactly 0
            err[f"{k}_err"] = 0.0 if v.size == 0 and full[k] == 0.0 else math.nan
    return {**full, **err}


def batch_blocks(periods: int, period_n: int = 0, blocks: int = 8) -> tuple[int, int]:
    """(L, B): blocks of L whole periods (a multiple of ``period_n`` for a periodic point),
    B of them, at most about ``blocks``, over a record of ``periods`` periods."""
    n = max(1, int(period_n))
    L = n * max(1, (int(periods) // n) // int(blocks))
    return L, int(periods) // L


def deformation_statistics(delta, samples_per_period: int, *, harmonics=(1, 2, 3),
                           period_n: int = 0, blocks: int = 8) -> dict:
    """Statistics of a deformation record that converge on chaotic motion: ``rms`` (about
    its mean: the dynamic deformation) and ``line_<k>x``, the amplitude of the spectral line
    at k times the excitation frequency (the Fourier coefficient over whole periods,
    |2/N sum delta exp(-i k W t)|), each with an ``_err`` companion by batch means over
    blocks of whole periods (:func:`batch_blocks`; NaN with fewer than 2 blocks).
    ``delta``: S = ``samples_per_period`` equidistant samples per period over whole
    periods, starting at a period's start (the sample at the record's end left out)."""
    d = np.asarray(delta, dtype=float).ravel()
    S = int(samples_per_period)
    P = d.size // S
    d = d[:P * S]

    def stats(x):
        k = np.arange(x.size)
        out = {"rms": float(np.std(x))}
        for h in harmonics:
            c = 2.0 / x.size * np.sum(x * np.exp(-2j * np.pi * h * k / S))
            out[f"line_{h}x"] = float(abs(c))
        return out

    full = stats(d)
    L, B = batch_blocks(P, period_n, blocks)
    if B < 2:
        return {**full, **{f"{k}_err": math.nan for k in full}}
    per = [stats(d[b * L * S:(b + 1) * L * S]) for b in range(B)]
    err = {f"{k}_err": float(np.std([q[k] for q in per], ddof=1) / math.sqrt(B))
           for k in full}
    return {**full, **err}


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
            key = _key(names[j])
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
