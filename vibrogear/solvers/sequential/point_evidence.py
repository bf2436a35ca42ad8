"""The evidence of a sweep point's motion class from its record window (:mod:`.sweep_point`
runs the point and calls these): the period at the engineering resolution
(:func:`resolution_test`), each contact group's own period (:func:`group_periods`), the
largest Lyapunov exponent by Benettin's method on the record's chunks
(:func:`lyapunov_exponent`), the contact metrics with their batch-means errors
(:func:`record_contact_metrics`) and the class's evidence in physical units
(:func:`resolution_metrics`).
"""
from __future__ import annotations

import math

import numpy as np

from ...models.contact_law import flank
from ...status import Status
from ..integrator.contact_eval import contact_kinematics
from .lyapunov import D0, block_estimate, state_scale, tangent_chunk
from .motion import classify_period, monitored_name, monitored_quantities, resolutions, \
    resolved_period
from .record_metrics import batch_blocks, metrics_with_errors
from .record_window import RecordWindow

__all__ = ["record_contact_metrics", "group_periods", "resolution_test", "lyapunov_exponent",
           "perturbation",
           "resolution_metrics"]


def record_contact_metrics(model, param, u_rec, rec: RecordWindow, groups, R, T, n) -> dict:
    """The contact metrics of a record with their batch-means errors."""
    mode0 = flank(contact_kinematics(model, param, [0.0], u_rec[None, :])[0][:, 0],
                  model.contacts.gap_hi, model.contacts.gap_lo)
    out = metrics_with_errors(model, groups, mode0, rec.events, rec.speeds, 0.0, R * T, T,
                              period_n=n)
    for key, (kind, idx) in groups.items():     # the largest mesh force [N] (record_window)
        if kind == "mesh" and rec.peak_force and int(idx[0]) in rec.peak_force:
            out[f"max_force_{key}"] = rec.peak_force[int(idx[0])] * model.force_unit_n
    return out


def group_periods(model, param, T, strob, groups, max_period, period_tol,
                   resolved=None, t=None) -> dict:
    """period_n of each contact group: a mesh's from its deformation and force at the
    engineering resolution (``resolved``: (samples, resolutions) of
    :func:`resolution_test`), or, where those do not repeat, from its deformations and
    rates within period_tol, as a bearing's.  ``t``: the samples' model times (default 0:
    period ends at phase 0; a multi-frequency model's record gives its own)."""
    out = {}
    t = np.zeros(strob.shape[0]) if t is None else t
    d, dd, _ = contact_kinematics(model, param, t, strob)
    for key, (_kind, idx) in groups.items():
        n = 0
        if resolved is not None and f"delta_{key}" in resolved[0]:
            mine = {k: resolved[0][k] for k in (f"delta_{key}", f"force_{key}")}
            n = resolved_period(mine, resolved[1], max_period)[0]
        if n == 0:
            s = np.hstack([d[idx].T, dd[idx].T])
            n = classify_period(s, max_period, period_tol, split=len(idx))[0]
        out[f"period_n_{key}"] = n
    return out


def resolution_test(model, param, states, rec: RecordWindow, settings):
    """(n, defect in resolutions, samples, resolutions) of the engineering-resolution
    test: the stroboscopic samples of every monitored quantity
    (:func:`~.motion.monitored_quantities`) against its resolution
    (:func:`~.motion.resolutions`, from the quantity's range over the record's dense
    samples)."""
    q = monitored_quantities(model, param, rec.phase_times(), states)
    samples = {k: v for k, (v, _kind) in q.items()}
    kinds = {k: kind for k, (_v, kind) in q.items()}
    ranges = {}
    for k, v in samples.items():
        lo, hi = (rec.ranges or {}).get(k, (math.inf, -math.inf))
        ranges[k] = max(hi, float(np.max(v))) - min(lo, float(np.min(v)))
    res = resolutions(model, ranges, kinds, rel=settings.resolution_rel,
                      length_m=settings.resolution_length, force_n=settings.resolution_force)
    n, defect = resolved_period(samples, res, settings.max_period)
    return n, defect, samples, res


def _qmax_error(rec: RecordWindow) -> float:
    """Batch-means error of the monitored deformation's largest value: the standard error
    of the mean of the block maxima over at most 8 blocks of the record's chunks."""
    c = np.asarray(rec.chunk_max if rec.chunk_max is not None else [], dtype=float)
    if c.size < 2 or not np.all(np.isfinite(c)):
        return math.nan
    L, B = batch_blocks(c.size, 0, 8)
    if B < 2:
        return math.nan
    blocks = c[:L * B].reshape(B, L).max(axis=1)
    return float(np.std(blocks, ddof=1) / math.sqrt(B))


def perturbation(options) -> float:
    """Benettin's perturbation for a record integrated with ``options``: 10 x rtol of the
    state's scale, at least D0."""
    return max(D0, 10.0 * float(options.rtol))


def lyapunov_exponent(model, param, chunks, v0, options, T, chunk, counts, d0=None):
    """(exponent, interval, message) of Benettin's method on a record's chunks from the
    tangent ``v0`` (:mod:`~.lyapunov`), in units of the model's time.  The perturbation
    ``d0`` (of the state's scale) is by default ten times the integrator's rtol (at least
    D0): a smaller one drowns in the integration error, whose growth then reads as an
    exponent (the FVA gearbox at 543 rpm, kv 1.001: +1.24 per period with D0 = 1e-6 at rtol
    1e-5, +0.20 with 1e-4 and -0.05 at rtol 1e-6; the two-stage gearbox's chaos at 2000 rpm
    reads 0.61 and 0.57)."""
    scale = state_scale(np.vstack([chunks[0][0]] + [c[1] for c in chunks]), model.n_modes)
    d0 = perturbation(options) if d0 is None else float(d0)
    v, logs = v0, []
    for start, ends, _, t_s in chunks:
        g, v, calls, st = tangent_chunk(model, param, start, ends, v, scale, options=options,
                                        d0=d0, t_start=t_s)
        counts[2] += calls
        if st != Status.OK:
            return math.nan, (math.nan, math.nan), \
                f"Lyapunov exponent not determined: {st.message}"
        logs.append(g)
    lam, ci, _ = block_estimate(np.concatenate(logs), T, chunk, burn=1)
    return lam, ci, "ok"


def resolution_metrics(model, T, n_res, res_defect, res, rec, lam, ci, floor) -> dict:
    """The class's evidence at engineering resolution and the exponent in physical units:
    ``resolution_period_n`` (0: the samples do not repeat within the resolution),
    ``resolution_defect`` (the samples' largest difference at that period, in
    resolutions; where none: the least over n, how many resolutions they spread),
    ``qmax_res`` (the monitored deformation's resolution), ``qmax_err`` (batch means of
    its largest value), ``lyapunov_per_s`` / ``lyapunov_lo_per_s`` (the exponent and its
    95 % lower bound in 1/s) and ``lyapunov_per_period`` / ``lyapunov_lo_per_period`` /
    ``lyapunov_floor_per_period`` (per excitation period: the log growth over one period;
    the floor, the change at rtol / 10; NaN where not computed)."""
    per_s = 1.0 / model.time_unit_s
    return {"resolution_period_n": int(n_res),
            "resolution_defect": float(res_defect),
            "qmax_res": float(res.get(monitored_name(model), math.nan)),
            "qmax_err": _qmax_error(rec),
            "lyapunov_per_s": float(lam) * per_s, "lyapunov_lo_per_s": float(ci[0]) * per_s,
            "lyapunov_per_period": float(lam) * T, "lyapunov_lo_per_period": float(ci[0]) * T,
            "lyapunov_floor_per_period": float(floor) * T}
