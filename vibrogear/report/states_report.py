"""Files of ``vibrogear states``: ``states.npz``, ``states.csv`` and the danger map
``states.png`` (+ ``.svg``).

``states.npz`` (no NaN: missing values are 0 with a flag):

* per attractor: ``attractor_param`` (the scene's parameter: rpm or Omega),
  ``attractor_class`` (codes of ``attractor_class_legend``, the sweep's motion classes),
  ``attractor_period_n`` (0: not periodic), ``attractor_qmin`` / ``attractor_qmax`` (the
  monitored deformation in the model's unit: m for a gearbox; ``q_display_scale`` converts
  to ``q_display_unit``), ``basin_fraction``, ``basin_ci_lo``, ``basin_ci_hi`` (Wilson 95 %),
  ``attractor_starts``, ``attractor_stable`` (1 / 0 from the Floquet multipliers of the shot
  orbit, -1 not shot), ``attractor_max_multiplier``, ``attractor_refined`` (extrema of the
  shot orbit), ``attractor_seen_by_sweep`` (1 / 0, -1: no sweep), per mesh
  ``attractor_impacts_<mesh>`` (contact onsets per excitation period) and
  ``attractor_rattle_<mesh>`` (impact energy per period), ``attractor_max_force_<mesh>``
  [N] (largest mesh force), ``attractor_kv_<mesh>`` (its dynamic factor: over the static
  mesh force ``static_force_<mesh>`` [N]);
* per grid value: ``param``, ``n_starts`` (settled), ``n_failed``;
* branches continued from attractors: ``branch_param``, ``branch_qmin``, ``branch_qmax``,
  ``branch_stable``, ``branch_label`` (points of all branches, concatenated),
  ``branch_start`` (offsets, branches + 1), ``branch_n_periods``;
* per settled start: ``start_point`` (grid index), ``start_index``, ``start_wall_s`` and
  ``start_attractor`` (index into the attractor arrays; -1: the integration failed);
* the sweep compared with: ``sweep_param``, ``sweep_qmin``, ``sweep_qmax`` (empty without).

``states.csv``: one row per attractor (display units in the header).

:func:`write` returns {name: path} of the files, as every writer does: ``report.html`` shows
the figures among them with the summary's records (``summary.json``, ``results.states``).
"""
from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from ..pipeline.files import atomic_write_bytes, atomic_write_npz
from .states_plots import plot_danger_map

__all__ = ["write", "states_arrays", "html_caption"]


def _flag(v) -> int:
    return -1 if v is None else int(bool(v))


def _fin(a) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    return np.where(np.isfinite(a), a, 0.0)


def states_arrays(res) -> dict:
    """The arrays of ``states.npz`` from a :class:`~vibrogear.analyses.states.StatesResult`."""
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
    from ..analyses.mesh_loads import mesh_judgement_arrays, static_mesh_forces
    from ..solvers.sequential.motion import contact_groups
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


def _csv(res, arrays) -> bytes:
    st = res.study
    unit = st.monitor.unit or "model units"
    s = st.monitor.scale
    meshes = sorted({g for a in res.attractors for g in a.metrics})
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow([f"{st.param_name}" + (f"_{st.param_unit}" if st.param_unit else ""), "class",
                "period_n", f"qmin_{unit}", f"qmax_{unit}", "basin_fraction", "basin_ci_lo",
                "basin_ci_hi", "starts", "n_starts_settled", "stable", "max_multiplier",
                "seen_by_sweep"] + [f"impacts_per_period_{g}" for g in meshes] +
               [f"rattle_{g}_{st.energy_unit.replace(' ', '_')}" for g in meshes])
    for a in res.attractors:
        lo, hi = a.ci
        row = [repr(a.param), a.class_name, a.period_n, _cell(a.qmin * s), _cell(a.qmax * s),
               _cell(a.fraction), _cell(lo), _cell(hi), a.count, a.n_ok,
               "" if a.stable is None else int(a.stable), _cell(a.max_multiplier),
               "" if a.seen_by_sweep is None else int(a.seen_by_sweep)]
        row += [_cell(a.metrics.get(g, {}).get("impacts", math.nan)) for g in meshes]
        row += [_cell(a.metrics.get(g, {}).get("rattle", math.nan)) for g in meshes]
        w.writerow(row)
    return text.getvalue().encode()


def _cell(x) -> str:
    x = float(x)
    return repr(x) if math.isfinite(x) else ""


def html_caption(summary: dict) -> str:
    """One paragraph for ``report.html`` under the danger map: what to look at."""
    name = summary.get("param_name", "")
    unit = summary.get("param_unit", "")
    where = summary.get("coexisting_at") or []
    text = (f"Every attractor found from {summary.get('starts_per_point')} random starts per "
            f"{name} value; marker area = basin fraction (95 % Wilson intervals in states.csv). ")
    if where:
        text += (f"States coexist at {len(where)} {name} values ({min(where):g}-{max(where):g} "
                 f"{unit}): there a disturbance can switch the gearbox between them. ")
    else:
        text += "No coexisting states were found. "
    unseen = summary.get("unseen_by_sweep")
    if unseen:
        text += (f"{len(unseen)} attractors (red rings) lie off the sweep's path: "
                 "the sweep alone would not show them.")
    return text


def write(scene, outcome, out, previous=None) -> dict:
    res = outcome.result
    out = Path(out)
    arrays = states_arrays(res)
    files = {"npz": str(atomic_write_npz(out / "states.npz", arrays)),
             "csv": str(atomic_write_bytes(out / "states.csv", _csv(res, arrays)))}
    st = res.study
    paths = plot_danger_map(arrays, out / "states.png", param_label=st.param_label,
                            q_label=st.monitor.axis_label(), scale=st.monitor.scale,
                            title=st.title)
    for p in paths:
        files[f"danger_map_{Path(p).suffix.lstrip('.')}"] = str(p)
    return files
