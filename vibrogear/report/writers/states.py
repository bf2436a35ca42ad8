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

from ...analyses.states.summary import states_arrays
from ...pipeline.files import atomic_write_bytes, atomic_write_npz
from ..figure import save_figure
from ..plots.states import plot_danger_map

__all__ = ["write", "states_arrays", "html_caption", "figure"]


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
    paths = save_figure(figure(res, arrays), out / "states.png")
    for p in paths:
        files[f"danger_map_{Path(p).suffix.lstrip('.')}"] = str(p)
    return files


def figure(res, arrays: dict | None = None):
    """The danger map of a census (:class:`~vibrogear.analyses.states.states.StatesResult`) as a
    Figure, the report's ``states.png``; ``arrays``: its :func:`states_arrays` when at hand."""
    st = res.study
    return plot_danger_map(states_arrays(res) if arrays is None else arrays,
                           param_label=st.param_label, q_label=st.monitor.axis_label(),
                           scale=st.monitor.scale, title=st.title)
