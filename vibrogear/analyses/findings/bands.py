"""Speed bands of a sweep: contact loss, rattle, double-sided impacts, bearing unloading,
motion classes, hysteresis (:mod:`vibrogear.analyses.findings.findings` explains the band).

The test of a band is evaluated per grid point and per direction on the arrays of
``sweep.npz`` exactly as the band states it (:mod:`.band_rule`); failed points
(``ok = False``) never belong to a band.
"""
from __future__ import annotations

import numpy as np

from ...config.numbers import fmt, fmt_param
from ...solvers.sequential.motion import (APERIODIC, CHAOTIC, MULTI_FREQUENCY, NOT_SETTLED,
    QUASI_PERIODIC)
from .band_rule import Band, band_points, grid_masks, rule_bands, segments, stat_text

__all__ = ["sweep_bands", "map_bands", "mesh_and_bearing_names", "PARAM_UNITS"]

#: parameter -> unit text
PARAM_UNITS = {"rpm": "rpm", "Omega": ""}


def mesh_and_bearing_names(arrays: dict) -> tuple[list[str], list[str]]:
    meshes = sorted(k[len("contact_fraction_"):] for k in arrays
                    if k.startswith("contact_fraction_") and not k.endswith("err"))
    bearings = sorted(k[len("unloaded_"):] for k in arrays
                      if k.startswith("unloaded_") and not k.endswith("err"))
    return meshes, bearings


def sweep_bands(arrays: dict, rules, *, param_unit: str, length_scale: float,
                length_unit: str, monitored: str = "monitored contact", roles=None
                ) -> tuple[list[Band], list[dict], list[str]]:
    """Bands and jump events of a ``sweep.npz`` and what was checked; ``monitored``: the
    contact whose deformation ``qmin``/``qmax`` are (a gearbox: the first mesh);
    ``roles``: {mesh key: "loaded" | "idle"} (None: every mesh loaded)."""
    meshes, bearings = mesh_and_bearing_names(arrays)
    bands = _contact_bands(arrays, meshes, bearings, rules, param_unit, roles)
    bands += _motion_bands(arrays, rules, dict(param_unit=param_unit))
    hyst, events = _hysteresis(arrays, rules, param_unit, length_scale, length_unit,
                               monitored)
    bands += hyst
    checked = [f"sweep ({', '.join(sorted(set(np.asarray(arrays.get('direction', ['up']), str).tolist())))}"
               f", {np.unique(np.asarray(arrays['param'])).size} speeds): "
               + _roles_checked(meshes, roles)
               + (f", unloading of {', '.join(bearings)}" if bearings else "")
               + ", motion class, jumps and hysteresis"]
    return bands, events, checked


def _span_text(v) -> str:
    lo, hi = float(np.min(v)), float(np.max(v))
    return fmt(lo) if fmt(lo) == fmt(hi) else f"{fmt(lo)}–{fmt(hi)}"


def _roles_checked(meshes, roles) -> str:
    loaded = [m for m in meshes if (roles or {}).get(m, "loaded") == "loaded"]
    idle = [m for m in meshes if (roles or {}).get(m) == "idle"]
    parts = []
    if loaded:
        parts.append(f"contact loss, back-flank impacts and dynamic factor of the loaded "
                     f"{'mesh' if len(loaded) == 1 else 'meshes'} {', '.join(loaded)}")
    if idle:
        parts.append(f"rattle level of the idle {'mesh' if len(idle) == 1 else 'meshes'} "
                     f"{', '.join(idle)}")
    return "; ".join(parts) or "contact loss and rattle of the contacts"


def _kv_bands(arrays, m, rules, kw) -> list[Band]:
    """The dynamic-factor band of a loaded mesh: kv_<m> > kv_caution."""
    kv = f"kv_{m}"
    if kv not in arrays or not np.any(np.asarray(arrays[kv], float) > 0):
        return []

    def ev(idx):
        f0 = float(np.asarray(arrays.get(f"static_force_{m}", [np.nan]), float).ravel()[0])
        text = f"{m} dynamic factor kv {stat_text(arrays, kv, idx, 3)}"
        if f"max_force_{m}" in arrays and np.isfinite(f0):
            text += f" (largest mesh force {stat_text(arrays, f'max_force_{m}', idx, 3, 1e-3, 'kN')}" \
                    f" over the static {fmt(f0 * 1e-3, 3)} kN)"
        return text

    return rule_bands(arrays, dict(quantity="dynamic factor", where=m, metric=kv, op=">",
                               threshold=rules.kv_caution, severity=rules.dynamic_factor),
                  ev, **kw)


def _idle_bands(arrays, m, rules, kw, per) -> list[Band]:
    """The rattle of an idle mesh by its level rattle_db_<m> [dB re 1 pW]: caution within
    rattle_caution_db of the loudest, avoid above rattle_limit_db (only where set), the
    quietest speeds (within 3 dB of the quietest) as a fine band."""
    key = f"rattle_db_{m}"
    if key not in arrays:
        return []
    ok = np.asarray(arrays.get("ok", np.ones(np.asarray(arrays["param"]).size, bool)), bool)
    db = np.asarray(arrays[key], float)[ok]
    if db.size == 0 or not np.any(db > 0):
        return []
    loudest, quietest = float(db.max()), float(db.min())

    def ev(idx):
        text = f"{m} rattle {stat_text(arrays, key, idx, 3, unit='dB')} re 1 pW"
        if f"rattle_power_{m}" in arrays:
            text += f" ({stat_text(arrays, f'rattle_power_{m}', idx, 2, 1e3, 'mW')})"
        if f"impact_velocity_rms_{m}" in arrays:
            rms = stat_text(arrays, f"impact_velocity_rms_{m}", idx, 2, 1e3, "mm/s")
            text += f", rms impact velocity {rms}"
        if f"impacts_back_{m}" in arrays:
            text += f", {stat_text(arrays, f'impacts_back_{m}', idx)} back-flank impacts {per}"
        return text + f"; loudest over the run {fmt(loudest, 3)} dB"

    out = []
    if rules.rattle_limit_db is not None:
        out += rule_bands(arrays, dict(quantity="rattle above the limit", where=m, metric=key,
                                   op=">", threshold=float(rules.rattle_limit_db),
                                   severity="avoid", margin="dB"), ev, **kw)
    out += rule_bands(arrays, dict(quantity="rattle", where=m, metric=key, op=">",
                               threshold=loudest - rules.rattle_caution_db,
                               severity=rules.idle_rattle, margin="dB"), ev, **kw)
    out += rule_bands(arrays, dict(quantity="quietest rattle", where=m, metric=key, op="<=",
                               threshold=quietest + QUIET_DB, severity="fine", margin="dB"),
                  ev, **kw)
    return out


#: the quietest rattle band: within this many dB of the run's quietest level
QUIET_DB = 3.0


def _contact_bands(arrays, meshes, bearings, rules, param_unit, roles=None) -> list[Band]:
    """Per loaded mesh: contact loss, dynamic factor, back-flank and double-sided impacts;
    per idle mesh: its rattle level; per bearing: unloading."""
    bands: list[Band] = []
    per = "per mesh period" if param_unit == "rpm" else "per excitation period"
    kw = dict(param_unit=param_unit)
    for m in meshes:
        cf, back, drive = f"contact_fraction_{m}", f"impacts_back_{m}", f"impacts_drive_{m}"
        if (roles or {}).get(m) == "idle":
            bands += _idle_bands(arrays, m, rules, kw, per)
            continue
        bands += _kv_bands(arrays, m, rules, kw)

        def loss(idx, m=m, cf=cf, drive=drive):
            out = {"out": 1.0 - np.asarray(arrays[cf], float)}
            if f"{cf}_err" in arrays:
                out["out_err"] = arrays[f"{cf}_err"]
            return (f"{m} out of contact {stat_text(out, 'out', idx, 2, 100, '%')} of the time, "
                    f"{stat_text(arrays, drive, idx)} drive-flank re-impacts {per}")

        def rattle(idx, m=m, back=back):
            text = f"{m}: {stat_text(arrays, back, idx)} back-flank impacts {per}"
            if f"rattle_{m}" in arrays:
                text += f", impact energy {stat_text(arrays, f'rattle_{m}', idx, 2, 1e3, 'mJ')} " \
                        f"{per}"
            return text

        bands += rule_bands(arrays, dict(quantity="contact loss", where=m, metric=cf, op="<",
                                     threshold=1.0 - rules.loss_share_avoid,
                                     severity=rules.contact_loss), loss, **kw)
        bands += rule_bands(arrays, dict(quantity="rattle", where=m, metric=back, op=">",
                                     threshold=rules.back_impacts_above,
                                     severity=rules.rattle), rattle, **kw)
        if back in arrays and drive in arrays:
            both = dict(arrays)
            both[f"double_sided_{m}"] = np.minimum(np.asarray(arrays[back], float),
                                                   np.asarray(arrays[drive], float))
            # a double-sided band that is exactly a rattle band says nothing new: kept
            # only where the two differ
            rattling = {(b.direction, b.start, b.stop) for b in bands
                        if b.quantity == "rattle" and b.where == m}
            bands += [_with(b, compare=f"min({back}, {drive})")
                      for b in rule_bands(both, dict(quantity="double-sided impacts", where=m,
                                                 metric=f"double_sided_{m}", op=">",
                                                 threshold=0.0,
                                                 severity=rules.double_sided),
                                      lambda idx, m=m, back=back, drive=drive:
                                      f"{m} hits both flanks: {stat_text(arrays, drive, idx)} "
                                      f"drive and {stat_text(arrays, back, idx)} back impacts "
                                      f"{per}", **kw)
                      if (b.direction, b.start, b.stop) not in rattling]
    ok = np.asarray(arrays.get("ok", np.ones(np.asarray(arrays["param"]).size, bool)), bool)
    for b in bearings:
        key = f"unloaded_{b}"
        if key not in arrays or not np.any(ok):
            continue
        # a loaded rolling bearing has elements outside its load zone at any speed: the
        # band is where more unload than at the run's quietest point
        least = float(np.min(np.asarray(arrays[key], float)[ok]))
        bands += rule_bands(arrays, dict(quantity="bearing unloading", where=b, metric=key,
                                     op=">", threshold=least + rules.unloaded_above,
                                     severity=rules.bearing_unloading),
                        lambda idx, b=b, key=key, least=least:
                        f"{b}: {stat_text(arrays, key, idx)} rolling elements out of contact on "
                        f"average ({fmt(least)} at the quietest point)", **kw)
    return bands


def _points(n: int) -> str:
    """'1 point' / 'n points' (of the file: both directions counted)."""
    return f"{n} point" + ("" if n == 1 else "s")


def map_bands(arrays: dict, rules, *, param_unit: str, roles=None
              ) -> tuple[list[Band], list[str]]:
    """Contact-loss, rattle, double-sided and bearing bands of a ``map.npz`` at each load:
    the map's (directions, loads, speeds) grids are read one load at a time as a sweep;
    each band names its load (``load_index`` into ``torque``, the array's middle axis)."""
    rpm = np.asarray(arrays["rpm"], float)
    dirs = [str(d) for d in np.asarray(arrays["direction"])]
    torque = np.asarray(arrays["torque"], float)
    meshes, bearings = mesh_and_bearing_names(arrays)
    keys = [k for k in arrays if k.startswith(("contact_fraction_", "impacts_back_",
                                               "impacts_drive_", "unloaded_", "rattle_"))]
    bands = []
    for j, t in enumerate(torque):
        as_sweep = {"param": np.tile(rpm, len(dirs)), "direction": np.repeat(dirs, rpm.size),
                    "ok": np.asarray(arrays["ok"], bool)[:, j, :].ravel()}
        for k in keys:
            as_sweep[k] = np.asarray(arrays[k], float)[:, j, :].ravel()
        for k in [k for k in arrays if k.startswith(("kv_", "rattle_db_", "max_force_",
                                                      "rattle_power_", "static_force_"))]:
            as_sweep[k] = np.asarray(arrays[k], float)[:, j, :].ravel()
        for b in _contact_bands(as_sweep, meshes, bearings, rules, param_unit, roles):
            bands.append(Band(**{**b.__dict__, "where": f"{b.where} at {t:.3g} N m",
                                 "source": "map.npz",
                                 "extra": {**b.extra, "load_index": j, "torque": float(t)}}))
    checked = [f"map ({torque.size} loads x {rpm.size} speeds): contact loss and rattle of "
               f"{', '.join(meshes)}" + (f", unloading of {', '.join(bearings)}" if bearings
                                         else "")]
    return bands, checked


def _with(band: Band, **extra) -> Band:
    return Band(**{**band.__dict__, "extra": {**band.extra, **extra}})


def _motion_bands(arrays, rules, kw) -> list[Band]:
    if "motion_class" not in arrays:
        return []
    out = []
    lyap = "lyapunov_ci" in arrays

    def exponent(idx) -> str:
        """The exponent's 95 % lower bound in 1/s and per excitation period, with its noise
        floor (files written before these arrays: per excitation period not known)."""
        parts = []
        if "lyapunov_lo_per_s" in arrays and kw["param_unit"] == "rpm":
            parts.append(f"{_span_text(np.asarray(arrays['lyapunov_lo_per_s'], float)[idx])}"
                         " 1/s")
        if "lyapunov_lo_per_period" in arrays:
            txt = f"{_span_text(np.asarray(arrays['lyapunov_lo_per_period'], float)[idx])} " \
                  "per excitation period"
            if "lyapunov_floor_per_period" in arrays:
                fl = np.asarray(arrays["lyapunov_floor_per_period"], float)[idx]
                txt += f", above its noise floor {_span_text(fl)} (the change at rtol / 10)"
            parts.append(txt)
        return "; ".join(parts)

    def chaos(idx):
        text = f"chaotic at {_points(idx.size)}"
        if lyap:
            ev = exponent(idx)
            text += "; the stroboscopic samples do not repeat within the resolution and the " \
                    "largest Lyapunov exponent is > 0 with 95 % confidence" + \
                    (f" (lower bound {ev})" if ev else "")
        return text

    def torus(idx):
        text = f"quasi-periodic at {_points(idx.size)} (no period within the resolution; " \
               "Lyapunov interval reaches 0 or its noise floor)"
        if "base_f2_order" in arrays:
            nu = np.asarray(arrays["base_f2_order"], float)[idx]
            nu = nu[nu > 0]
            if nu.size:
                text += f"; second frequency f2 = {_span_text(nu)} x the excitation " \
                        "frequency (folded)"
        return text

    for quantity, code, severity, ev in (("chaotic motion", CHAOTIC, rules.chaotic, chaos),
                                         ("quasi-periodic motion", QUASI_PERIODIC,
                                          rules.quasi_periodic, torus),
                                         ("motion not settled", NOT_SETTLED, rules.not_settled,
                                          lambda idx: f"not settled within the transient "
                                          f"budget at {_points(idx.size)}"),
                                         ("aperiodic motion", APERIODIC, rules.not_settled,
                                          lambda idx: f"no period found at {_points(idx.size)} "
                                          "(no Lyapunov exponent computed)"),
                                         ("multi-frequency forced motion", MULTI_FREQUENCY,
                                          "fine", lambda idx: f"follows the forcing's "
                                          f"frequencies at {_points(idx.size)} (meshes "
                                          "exciting at their own frequencies): periodic over "
                                          "their common period, or, where that exceeds the "
                                          "period limit, not chaotic")):
        out += rule_bands(arrays, dict(quantity=quantity, where="gearbox" if kw["param_unit"]
                                   == "rpm" else "system", metric="motion_class", op="==",
                                   threshold=code, severity=severity), ev, **kw)
    if "period_n" in arrays:
        pn = np.asarray(arrays["period_n"])
        out += rule_bands(arrays, dict(quantity="subharmonic motion", where="gearbox" if
                                   kw["param_unit"] == "rpm" else "system", metric="period_n",
                                   op=">=", threshold=2, severity=rules.subharmonic),
                      lambda idx: f"period {', '.join(str(int(n)) for n in np.unique(pn[idx]))}"
                      " x the excitation period", **kw)
        out += rule_bands(arrays, dict(quantity="periodic motion", where="gearbox" if
                                   kw["param_unit"] == "rpm" else "system", metric="period_n",
                                   op="==", threshold=1, severity="fine"),
                      lambda idx: f"period 1 at {_points(idx.size)}", **kw)
    return out


def _hysteresis(arrays, rules, param_unit, scale, unit,
                monitored) -> tuple[list[Band], list[dict]]:
    """Jumps per direction (events) and the band where up and down differ.

    A jump: neighbouring points of one direction whose qmax differs by more than
    ``jump_rel`` of its range over the run, than ``jump_level_rel`` of the larger qmax, than
    the resolution of either point (``qmax_res``) and than the sum of their batch-means
    errors (``qmax_err``).  The band:
    ``hysteresis_<mesh>`` (|qmax up - qmax down| per speed, sweep.npz) above
    ``hysteresis_rel`` of the qmax range or the largest resolution, whichever is larger."""
    param = np.asarray(arrays["param"], float)
    d = np.asarray(arrays.get("direction", np.full(param.size, "up")), str)
    ok = np.asarray(arrays.get("ok", np.ones(param.size, bool)), bool)
    qmax = np.asarray(arrays["qmax"], float)
    span = float(np.ptp(qmax[ok])) if np.any(ok) else 0.0
    res = np.asarray(arrays.get("qmax_res", np.zeros(param.size)), float)
    err = np.asarray(arrays.get("qmax_err", np.zeros(param.size)), float)
    events = []
    for direction in ("up", "down"):
        sel = np.flatnonzero((d == direction) & ok)
        sel = sel[np.argsort(param[sel])]
        if direction == "down":
            sel = sel[::-1]
        for a, b in zip(sel[:-1], sel[1:]):
            step = abs(qmax[b] - qmax[a])
            level = rules.jump_level_rel * max(abs(qmax[a]), abs(qmax[b]))
            if span > 0 and step > rules.jump_rel * span and step > max(res[a], res[b]) \
                    and step > err[a] + err[b] and step > level:
                events.append({"kind": "jump", "at": float(0.5 * (param[a] + param[b])),
                               "where": monitored, "direction": direction,
                               "evidence": f"going {direction}, qmax changes from "
                               f"{fmt(qmax[a] * scale, 3)} to {fmt(qmax[b] * scale, 3)} {unit} "
                               f"between {fmt_param(param[a])} and {fmt_param(param[b])} "
                               f"{param_unit}".replace("  ", " ")})
    if not (np.any(d == "up") and np.any(d == "down")) or span == 0:
        return [], events
    key = next((k for k in arrays if k.startswith("hysteresis_")), None)
    h = np.asarray(arrays[key], float) if key else _up_down_difference(param, d, ok, qmax)
    # a file written before the array: the rule on qmax, compared up against down
    metric, extra = (key, {}) if key else ("qmax", {"compare": "abs(up - down)"})
    thr = max(rules.hysteresis_rel * span, float(np.max(res[ok], initial=0.0)))
    grid, masks = grid_masks({**arrays, "_h": h}, "_h", ">", thr)
    mask = masks["up"] & masks["down"]
    step = float(np.min(np.diff(grid))) if grid.size > 1 else 0.0
    bands = []
    for i0, i1 in segments(mask):
        idx = band_points(arrays, grid, "both", i0, i1)
        bands.append(Band("hysteresis (up and down differ)", monitored, "both", float(grid[i0]),
                          float(grid[i1]), rules.hysteresis, metric, ">", thr,
                          f"up and down end in different states: qmax differs by up to "
                          f"{fmt(h[idx].max() * scale, 2)} {unit}".rstrip(),
                          edge_err=step, points=int(i1 - i0 + 1), extra=extra))
    return bands, events


def _up_down_difference(param, d, ok, qmax) -> np.ndarray:
    """|qmax up - qmax down| per point at its speed (0 where either failed)."""
    h = np.zeros(param.size)
    for k in range(param.size):
        other = np.flatnonzero((param == param[k]) & (d != d[k]) & ok)
        if ok[k] and other.size:
            h[k] = abs(qmax[k] - qmax[other[0]])
    return h
