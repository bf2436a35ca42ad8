"""Findings from the continuation (special points), the modes (resonance speeds), the ERP
(peak and the bands above a level) and the census of coexisting states."""
from __future__ import annotations

import numpy as np

from ...config.numbers import fmt
from .band_rule import Band, segments

__all__ = ["branch_events", "resonance_events", "erp_findings", "states_findings",
           "runup_findings", "RUNUP_MERGE_PERIODS"]

#: a run-up's contact-loss periods closer than this many mesh periods form one band
RUNUP_MERGE_PERIODS = 50

#: what a special point of a branch means, in plain words
LABELS = {"LP": "fold (LP): the branch turns back",
          "PD": "period doubling (PD): a period-2 response branches off",
          "NS": "Neimark-Sacker (NS): a torus (quasi-periodic motion) branches off",
          "BP": "branch point (BP)", "GR": "grazing: a contact just touches"}


def _stability(stable, i: int, branch) -> str:
    same = np.flatnonzero(branch == branch[i])
    before = [j for j in same if j < i]
    after = [j for j in same if j > i]
    a = "stable" if before and stable[before[-1]] else "unstable" if before else "?"
    b = "stable" if after and stable[after[0]] else "unstable" if after else "?"
    return f"{a} → {b}"


def branch_events(arrays: dict, *, param_unit: str, length_scale: float,
                  length_unit: str) -> list[dict]:
    """One event per labelled point of ``branch.npz``, with the stability on each side."""
    label = np.asarray(arrays.get("label", []), str)
    param = np.asarray(arrays["param"], float)
    stable = np.asarray(arrays.get("stable", np.zeros(param.size, bool)), bool)
    branch = np.asarray(arrays.get("branch", np.zeros(param.size, int)))
    nper = np.asarray(arrays.get("n_periods", np.ones(param.size, int)))
    qmax = np.asarray(arrays.get("qmax", np.zeros(param.size)), float)
    out = []
    for i in np.flatnonzero(label != ""):
        kind = str(label[i])
        stability = _stability(stable, i, branch)
        what = LABELS.get(kind, kind)
        if kind == "LP" and "stable" in stability.replace("unstable", ""):
            what += "; the stable response ends here: it jumps to another"
        out.append({"kind": kind, "at": float(param[i]),
                    "where": f"branch {int(branch[i])} (period-{int(nper[i])})",
                    "stability": stability,
                    "evidence": f"{what}; stability {stability}; qmax "
                    f"{fmt(qmax[i] * length_scale, 3)} {length_unit}".rstrip()})
    return out


def resonance_events(resonances: list[dict], rules) -> list[dict]:
    """The modes' resonance speeds (mesh order x mode frequency) whose mesh strain-energy
    share is above ``rules.resonance_share_above``."""
    out = []
    for r in resonances:
        share = float(r.get("mesh_energy_share", 0.0))
        if share <= rules.resonance_share_above:
            continue
        mesh = f"{r['mesh']} " if r.get("mesh") else ""
        out.append({"kind": "resonance", "at": float(r["rpm"]),
                    "where": f"mode {int(r['mode']) + 1} ({fmt(r['frequency_hz'], 4)} Hz)",
                    "mesh_order": int(r.get("mesh_order", 1)),
                    "evidence": f"{mesh}mesh order {int(r.get('mesh_order', 1))} meets mode "
                    f"{int(r['mode']) + 1} at {fmt(r['frequency_hz'], 4)} Hz; "
                    f"{fmt(100 * share, 2)} % of its strain energy is in the meshes"})
    return out


def erp_findings(arrays: dict, rules, *, direction: str) -> tuple[list[Band], list[dict]]:
    """The ERP peak (event) and the bands where ``erp_db`` is above the level."""
    rpm = np.asarray(arrays["rpm"], float)
    db = np.asarray(arrays["erp_db"], float)
    order = np.argsort(rpm)
    rpm, db = rpm[order], db[order]
    k = int(np.nanargmax(db))
    events = [{"kind": "erp_peak", "at": float(rpm[k]), "where": "housing",
               "evidence": f"radiated power (ERP) peaks at {fmt(db[k], 4)} dB re 1 pW"}]
    level = float(db[k] - 6.0) if rules.erp_above_db is None else float(rules.erp_above_db)
    step = float(np.min(np.diff(rpm))) if rpm.size > 1 else 0.0
    bands = []
    for i0, i1 in segments(db > level):
        bands.append(Band("radiated power", "housing", direction, float(rpm[i0]),
                          float(rpm[i1]), rules.erp, "erp_db", ">", level,
                          f"ERP {fmt(db[i0:i1 + 1].min(), 4)}–{fmt(db[i0:i1 + 1].max(), 4)} dB "
                          f"re 1 pW, above {fmt(level, 4)} dB", source="erp.csv",
                          edge_err=step, points=int(i1 - i0 + 1)))
    return bands, events


def _state_impact_bands(arrays, grid, step, rules, roles, per) -> list[Band]:
    """Per mesh, the speeds whose states hit the teeth (``attractor_impacts_<mesh>`` > 0):
    a loaded mesh "avoid" where every state found at the speed impacts (min over them),
    "caution" where some do (max); an idle mesh's rattle "caution" where any state
    impacts, with its impact energy."""
    ap = np.asarray(arrays["attractor_param"], float)
    out = []
    for key in sorted(k for k in arrays if k.startswith("attractor_impacts_")):
        m = key[len("attractor_impacts_"):]
        imp = np.asarray(arrays[key], float)
        rat = np.asarray(arrays.get(f"attractor_rattle_{m}", np.zeros(ap.size)), float)
        lo = np.array([imp[ap == p].min() for p in grid])
        hi = np.array([imp[ap == p].max() for p in grid])
        idle = (roles or {}).get(m) == "idle"
        if not idle and f"attractor_kv_{m}" in arrays:      # the states' dynamic factor
            kv = np.asarray(arrays[f"attractor_kv_{m}"], float)
            top = np.array([kv[ap == p].max() for p in grid])
            for i0, i1 in segments(top > rules.kv_caution):
                sel = (ap >= grid[i0]) & (ap <= grid[i1])
                out.append(Band("dynamic factor in a state", m, "both", float(grid[i0]),
                                float(grid[i1]), rules.dynamic_factor, f"attractor_kv_{m}",
                                ">", float(rules.kv_caution),
                                f"{m}: dynamic factor kv up to {fmt(float(kv[sel].max()), 3)} "
                                "in the states found", source="states.npz", edge_err=step,
                                points=int(i1 - i0 + 1),
                                extra={"compare": "max over the states at each speed",
                                       "margin": float(top[i0:i1 + 1].max())
                                       / rules.kv_caution - 1, "margin_unit": "relative"}))
        tests = [("max", hi > 0, rules.idle_rattle, "rattle in a state")] if idle else \
            [("min", lo > 0, rules.contact_loss, "impacts in a state"),
             ("max", (hi > 0) & ~(lo > 0), "caution", "impacts in a state")]
        for how, mask, severity, quantity in tests:
            for i0, i1 in segments(mask):
                sel = (ap >= grid[i0]) & (ap <= grid[i1]) & (imp > 0)
                text = (f"{m}: {'every' if how == 'min' else 'a'} state found hits the teeth, "
                        f"{fmt(float(imp[sel].min()), 2)}–{fmt(float(imp[sel].max()), 2)} "
                        f"contact onsets {per}, impact energy up to "
                        f"{fmt(float(rat[sel].max()) * 1e3, 2)} mJ {per}")
                out.append(Band(quantity, m, "both", float(grid[i0]), float(grid[i1]),
                                severity, key, ">", 0.0, text, source="states.npz",
                                edge_err=step, points=int(i1 - i0 + 1),
                                extra={"compare": f"{how} over the states at each speed",
                                       "margin": float(imp[sel].max()),
                                       "margin_unit": "relative"}))
    return out


def states_findings(arrays: dict, rules, *, param_unit: str, length_scale: float,
                    length_unit: str, roles=None) -> tuple[list[Band], list[dict]]:
    """Speeds where more than one attractor was found (band on ``n_attractors`` of
    ``states.npz``, per speed), one event per attractor that coexists with another, and
    per mesh the speeds whose states hit the teeth (:func:`_state_impact_bands`)."""
    ap = np.asarray(arrays["attractor_param"], float)
    grid = np.unique(ap)
    count = np.array([np.sum(ap == p) for p in grid])
    basin = np.asarray(arrays.get("basin_fraction", np.ones(ap.size)), float)
    lo = np.asarray(arrays.get("basin_ci_lo", basin), float)
    hi = np.asarray(arrays.get("basin_ci_hi", basin), float)
    legend = [str(s) for s in np.asarray(arrays.get("attractor_class_legend", []))]
    cls = np.asarray(arrays.get("attractor_class", np.zeros(ap.size, int)))
    step = float(np.min(np.diff(grid))) if grid.size > 1 else 0.0
    bands, events = [], []
    for i0, i1 in segments(count > 1):
        bands.append(Band("coexisting states", "gearbox" if param_unit == "rpm" else "system",
                          "both", float(grid[i0]), float(grid[i1]), rules.coexisting,
                          "n_attractors", ">", 1.0,
                          f"up to {int(count[i0:i1 + 1].max())} distinct states from random "
                          "starts", source="states.npz", edge_err=step,
                          points=int(i1 - i0 + 1),
                          extra={"compare": "count of attractor_param equal to the speed"}))
    bands += _state_impact_bands(arrays, grid, step, rules, roles,
                                 "per mesh period" if param_unit == "rpm" else
                                 "per excitation period")
    period = np.asarray(arrays.get("attractor_period_n", np.zeros(ap.size, int)))
    seen = np.asarray(arrays.get("attractor_seen_by_sweep", np.full(ap.size, -1)))
    meshes = sorted(k[len("attractor_impacts_"):] for k in arrays
                    if k.startswith("attractor_impacts_"))
    for j in np.flatnonzero(np.isin(ap, grid[count > 1])):
        name = legend[int(cls[j])] if legend and 0 <= int(cls[j]) < len(legend) else str(cls[j])
        if name == "periodic":
            name = f"period-{int(period[j])}"
        hits = [f"{m} {fmt(float(arrays[f'attractor_impacts_{m}'][j]), 2)} impacts per period"
                for m in meshes if float(arrays[f"attractor_impacts_{m}"][j]) > 0]
        text = f"a {name} state" + (f" ({', '.join(hits)})" if hits else " without impacts")
        text += f"; {fmt(100 * basin[j], 2)} % of the disturbances end there (95 %: " \
                f"{fmt(100 * lo[j], 2)}–{fmt(100 * hi[j], 2)} %)"
        if int(seen[j]) == 0:
            text += "; not on the sweep's path"
        events.append({"kind": "coexisting", "at": float(ap[j]), "where": name,
                       "basin_fraction": float(basin[j]), "evidence": text})
    return bands, events


def runup_findings(arrays: dict, rules, *, param_unit: str, roles=None) -> list[Band]:
    """Contact loss during a run-up / run-down: per run ``<d>`` and mesh, the speeds
    (``<d>_rpm``, the mean speed of each mesh period) of the periods with contact losses
    (``<d>_losses_<mesh>`` > 0), periods closer than :data:`RUNUP_MERGE_PERIODS` joined into
    one band; ``edge_err``: the largest speed change over one mesh period in the band.
    Idle meshes (``roles``) are left out: a free gear leaves its drive flank at any speed."""
    runs = [str(r) for r in np.asarray(arrays.get("runs", arrays.get("directions", [])))]
    meshes = [str(m) for m in np.asarray(arrays.get("meshes", []))]
    bands = []
    for run in runs:
        rpm = np.asarray(arrays.get(f"{run}_rpm", []), float)
        direction = "down" if run.startswith("down") else "up"
        for m in meshes:
            if (roles or {}).get(m) == "idle":     # an idle gear leaves its flank: not judged
                continue
            key = f"{run}_losses_{m}"
            if key not in arrays or rpm.size == 0:
                continue
            losses = np.asarray(arrays[key], float)
            hit = np.flatnonzero(losses > 0)
            if hit.size == 0:
                continue
            cuts = np.flatnonzero(np.diff(hit) > RUNUP_MERGE_PERIODS)
            for group in np.split(hit, cuts + 1):
                i0, i1 = int(group[0]), int(group[-1])
                seg = rpm[i0:i1 + 1]
                step = float(np.max(np.abs(np.diff(rpm[max(i0 - 1, 0):i1 + 2]))))
                label = run.replace("_no_inertia", " (no inertia torque)")
                bands.append(Band("contact loss in the run-up" if direction == "up" else
                                  "contact loss in the run-down", m, direction,
                                  float(seg.min()), float(seg.max()), rules.contact_loss,
                                  key, ">", 0.0,
                                  f"{m} loses contact in {group.size} of {i1 - i0 + 1} mesh "
                                  f"periods of the {label} run ({int(losses[group].sum())} "
                                  "losses)", source="runup.npz", edge_err=step,
                                  points=int(group.size),
                                  extra={"param": f"{run}_rpm", "run": run}))
    return bands
