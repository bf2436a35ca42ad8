"""Metrics of a sweep point's record window that converge as the record grows: the rattle /
contact metrics of every contact group (:func:`contact_groups`, :func:`metrics_with_errors`)
and the statistics of a deformation record (:func:`deformation_statistics`), each with its
batch-means error (:func:`batch_blocks`).  :mod:`.motion` classifies the motion itself.

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

__all__ = ["contact_key", "contact_groups", "window_metrics", "metrics_with_errors",
           "batch_blocks", "deformation_statistics"]


def contact_key(name: str) -> str:
    """A contact name as array keys spell it: runs of characters other than letters and
    digits become '_' ('contact' where none is left)."""
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
            key = contact_key(names[j])
            while key in out:
                key += "_"
            out[key] = ("mesh", np.array([j]))
        else:
            key = "bearing_" + contact_key(str(names[j]).split(":")[0])
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
