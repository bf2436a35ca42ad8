"""The ``states`` entry of ``summary.json``: what the census found, per grid value, in plain
records the findings engine reads.

``per_speed``: one record per grid value: ``param`` (the scene's parameter: rpm or Omega),
``n_starts`` (settled), ``failed``, ``coexisting`` (more than one attractor) and
``attractors``, largest basin first, each ``{"class", "period_n", "basin_fraction",
"basin_ci_95": [lo, hi], "starts", "qmin", "qmax" (display unit of the monitored mesh
deformation: um for a gearbox), "stable" (Floquet; None: not shot), "impacts_per_period":
{mesh: contact onsets per excitation period}, "rattle": {mesh: impact energy per period},
"seen_by_sweep"}``.  ``unseen_by_sweep`` lists the attractors the sweep path missed.
"""
from __future__ import annotations

import math

import numpy as np

from ...status import Status
from ..mesh_loads import mesh_judgement_arrays, static_mesh_forces
from ...solvers.sequential.record_metrics import contact_groups

__all__ = ["states_summary", "coexisting_points", "states_arrays"]


def _num(x):
    x = float(x)
    return x if math.isfinite(x) else None


def coexisting_points(result) -> list[int]:
    """Grid indices with more than one attractor."""
    counts = np.bincount([a.point for a in result.attractors], minlength=result.params.size)
    return [int(i) for i in np.flatnonzero(counts > 1)]


def states_summary(result, cfg, opts, info) -> dict:
    study = result.study
    scale = study.monitor.scale
    name = study.param_name
    per_speed = []
    for i, p in enumerate(result.params):
        atts = [a for a in result.attractors if a.point == i]
        per_speed.append({"param": float(p), "n_starts": int(result.n_starts[i]),
                          "failed": int(result.n_failed[i]), "coexisting": len(atts) > 1,
                          "attractors": [a.summary(scale) for a in atts]})
    unseen = [{"param": a.param, "class": a.class_name, "period_n": a.period_n,
               "basin_fraction": a.fraction, "basin_ci_95": list(a.ci),
               "qmin": a.qmin * scale, "qmax": a.qmax * scale}
              for a in result.attractors if a.seen_by_sweep is False]
    widths = [a.ci[1] - a.ci[0] for a in result.attractors]
    failed = int(result.n_failed.sum())
    coex = coexisting_points(result)
    n_att = len(result.attractors)
    msg = (f"{n_att} attractors at {result.params.size} {name} values; "
           f"{len(coex)} with coexisting states")
    if result.sweep is not None:
        msg += f"; {len(unseen)} attractors not on the sweep's path"
    classes = {}
    for a in result.attractors:
        key = a.class_name if a.period_n == 0 else f"period-{a.period_n}"
        classes[key] = classes.get(key, 0) + 1
    summary = {
        "status": Status.OK.text if failed == 0 else "partial",
        "message": msg + (f"; {failed} starts failed" if failed else ""),
        "param_name": name, "param_unit": study.param_unit,
        "q_unit": study.monitor.unit or "model units",
        "energy_unit": study.energy_unit,
        "points": int(result.params.size), "starts_per_point": int(cfg.starts),
        "seed": int(cfg.seed), "attractors": n_att, "attractor_classes": classes,
        "coexisting_at": [float(result.params[i]) for i in coex],
        "stopped_early_at": [float(result.params[i]) for i in info.get("stopped_early", [])],
        "per_speed": per_speed,
        "unseen_by_sweep": unseen if result.sweep is not None else None,
        "sweep_match_rule": "periodicity, and extrema within 5 % of the sweep's range "
                            "(periodic) or ranges overlapping over half their union "
                            "(non-periodic): a heuristic" if result.sweep is not None else None,
        "branches": list(result.branch_notes),
        "counters": result.counters,
        "wall_split_s": {k: round(float(v), 3) for k, v in result.timings.items()},
        "error_estimate": {"rtol": opts.rtol, "atol": opts.atol, "period_tol": cfg.period_tol,
                           "widest_basin_ci_95": _num(max(widths)) if widths else None,
                           "failed_starts": failed},
    }
    return summary


def _flag(v) -> int:
    return -1 if v is None else int(bool(v))


def _fin(a) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    return np.where(np.isfinite(a), a, 0.0)


def states_arrays(res) -> dict:
    """The arrays of ``states.npz`` from a :class:`~vibrogear.analyses.states.states.StatesResult`
    (the names and units: :mod:`vibrogear.report.writers.states`)."""
    atts = res.attractors
    meshes = sorted({g for a in atts for g in a.metrics})
    ci = np.array([a.ci for a in atts], dtype=float).reshape(-1, 2)
    out = {
        "param": np.asarray(res.params, float), "n_starts": np.asarray(res.n_starts, int),
        "n_failed": np.asarray(res.n_failed, int),
        "attractor_param": np.array([a.param for a in atts], float),
        "attractor_class": np.array([a.motion_class for a in atts], int),
        "attractor_class_legend": np.asarray(res.legend),
        "attractor_period_n": np.array([a.period_n for a in atts], int),
        "attractor_qmin": _fin([a.qmin for a in atts]),
        "attractor_qmax": _fin([a.qmax for a in atts]),
        "basin_fraction": _fin([a.fraction for a in atts]),
        "basin_ci_lo": ci[:, 0], "basin_ci_hi": ci[:, 1],
        "attractor_starts": np.array([a.count for a in atts], int),
        "attractor_stable": np.array([_flag(a.stable) for a in atts], int),
        "attractor_max_multiplier": _fin([a.max_multiplier for a in atts]),
        "attractor_refined": np.array([a.refined for a in atts], bool),
        "attractor_seen_by_sweep": np.array([_flag(a.seen_by_sweep) for a in atts], int),
        "q_display_scale": np.float64(res.study.monitor.scale),
        "q_display_unit": np.asarray(res.study.monitor.unit),
        "param_name": np.asarray(res.study.param_name),
    }
    for g in meshes:
        out[f"attractor_impacts_{g}"] = _fin([a.metrics.get(g, {}).get("impacts", math.nan)
                                              for a in atts])
        out[f"attractor_rattle_{g}"] = _fin([a.metrics.get(g, {}).get("rattle", math.nan)
                                             for a in atts])
    out.update(_dynamic_factors(res, atts, meshes))
    brs = res.branches
    pts = [p for b in brs for p in b.points]
    out["branch_start"] = np.concatenate([[0], np.cumsum([len(b.points) for b in brs])]).astype(int)
    out["branch_n_periods"] = np.array([b.n_periods for b in brs], int)
    out["branch_param"] = np.array([p.param for p in pts], float)
    out["branch_qmin"] = np.array([p.qmin for p in pts], float)
    out["branch_qmax"] = np.array([p.qmax for p in pts], float)
    out["branch_stable"] = np.array([p.stable for p in pts], bool)
    out["branch_label"] = np.array([p.label for p in pts], dtype="<U2")
    for k, v in (res.starts or {}).items():
        out[f"start_{k}"] = np.asarray(v)
    sw = res.sweep or {}
    for k in ("param", "qmin", "qmax"):
        v = np.asarray(sw.get(k, np.zeros(0)), float)
        out[f"sweep_{k}"] = v
    if sw:
        ok = np.isfinite(out["sweep_qmin"]) & np.isfinite(out["sweep_qmax"])
        for k in ("param", "qmin", "qmax"):
            out[f"sweep_{k}"] = out[f"sweep_{k}"][ok]
    return out


def _dynamic_factors(res, atts, meshes) -> dict:
    """``attractor_max_force_<mesh>`` [N] (largest over the state's records),
    ``static_force_<mesh>`` [N] and ``attractor_kv_<mesh>`` = their ratio
    (:mod:`vibrogear.analyses.mesh_loads`; 0 where not formed)."""
    peaks = {g: [a.metrics.get(g, {}).get("max_force", math.nan) for a in atts] for g in meshes}
    if not atts or not any(np.any(np.isfinite(v)) for v in peaks.values()):
        return {}
    model = res.study.model
    static = static_mesh_forces(model, res.study.start(float(atts[0].param)),
                                contact_groups(model))
    arrays = mesh_judgement_arrays({f"max_force_{g}": np.asarray(v, float)
                                    for g, v in peaks.items()}, static)
    out = {}
    for g in meshes:
        out[f"attractor_max_force_{g}"] = _fin(peaks[g])
        if f"kv_{g}" in arrays:
            out[f"attractor_kv_{g}"] = _fin(arrays[f"kv_{g}"])
            out[f"static_force_{g}"] = np.float64(static[g])
    return out

