"""``nvh``: spectra of the steady response over speed and the housing's radiated power.

Steady points: the settled end states u_end (excitation phase 0) of a [sweep] that ran before
in the same run (``previous["sweep"]``, the direction ``[nvh] sweep_direction``), else the
[nvh] speed grid settled here by :func:`~vibrogear.solvers.sweep.sweep` (upward, from the
static equilibrium).  From each state ``record_periods`` whole mesh periods are integrated
(:func:`~vibrogear.solvers.integrate.integrate`) with ``samples_per_period`` dense samples
each, and the one-sided amplitude spectra (:mod:`vibrogear.solvers.spectrum`: mesh
harmonics exactly on bins, no window) of

* the dynamic transmission error: each mesh's deformation delta = c . x - e(t) [m],
* the mesh forces by the contact law (:func:`~vibrogear.solvers.contact_eval.contact_history`) [N],
* each rolling-element bearing's resultant force on the housing, sum_j f_j e_j over its
  elements (radial unit e_j, rotor frame X = -x, Y = z of the housing) [N],

and, with a housing, the ERP of its outer surface (:mod:`.housing_surface`).  Frequencies
are k / (record_periods T_mesh): order k / record_periods of the first mesh.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..config.base import ConfigError
from ..pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ..solvers.contact_eval import contact_history
from ..solvers.integrate import integrate
from ..solvers.spectrum import amplitude_spectrum
from .housing_surface import erp_db, erp_spectrum, erp_watts, rms_velocity_field, surface_map
from .study import Study, integration_options

__all__ = ["NvhResult", "run", "steady_points", "order_lines"]


@dataclass(frozen=True, eq=False)
class NvhResult:
    rpm: np.ndarray                      # (P,) steady points that were recorded
    order: np.ndarray                    # (K,) bin frequency in orders of the first mesh
    freq_hz: np.ndarray                  # (P, K)
    amplitudes: dict                     # quantity -> (P, channels, K) one-sided amplitudes
    channels: dict                       # quantity -> channel names
    units: dict                          # quantity -> unit
    parseval: dict                       # quantity -> largest relative Parseval error
    mesh_hz: np.ndarray                  # (P, n meshes) tooth-pass frequencies
    shaft_hz: np.ndarray                 # (P, n shafts) shaft rotation frequencies
    shaft_names: tuple
    source: str                          # "sweep:<direction>" | "nvh grid"
    erp_w: np.ndarray | None = None      # (P,)
    erp_per_bin: np.ndarray | None = None    # (P, K) ERP of each frequency bin [W]
    erp_note: str = ""
    surface: object = None               # SurfaceMap (for the velocity fields)
    velocity_fields: dict = field(default_factory=dict)    # rpm -> (nf,) RMS v_n [m/s]
    study: Study | None = None

    @property
    def erp_db(self) -> np.ndarray | None:
        """(P,) ERP level [dB re 1e-12 W] (None without surface data)."""
        return None if self.erp_w is None else erp_db(self.erp_w)


def steady_points(study: Study, scene, previous, ctx: RunContext | None = None
                  ) -> tuple[np.ndarray, np.ndarray, str]:
    """(rpm (P,), settled states (P, n), source) of the steady points (module docstring)."""
    cfg = scene.nvh
    prev = (previous or {}).get("sweep") if cfg.use_sweep else None
    if prev is not None:
        res = prev.result.sweep
        keep = (res.direction == cfg.sweep_direction) & (res.status == 0)
        if not np.any(keep):
            raise NumericalFailure(f"nvh: the sweep has no settled {cfg.sweep_direction!r} "
                                   "points")
        order = np.argsort(res.param[keep], kind="stable")
        return res.param[keep][order], res.u_end[keep][order], f"sweep:{cfg.sweep_direction}"
    if not cfg.own_grid():
        raise ConfigError("nvh.rpm_min", "no steady points: list 'sweep' before 'nvh' in "
                          "scene.analyses (with nvh.use_sweep = true), or give the [nvh] "
                          "speed grid rpm_min / rpm_max")
    from ..solvers.sweep import sweep

    rpm = np.linspace(cfg.rpm_min, cfg.rpm_max, cfg.n_speeds)
    kw = dict(directions=("up",), transient_periods=cfg.transient_periods, record_periods=1,
              max_period=1, options=integration_options(scene, record=True),
              u0=study.start(rpm[0]), workers=1, lyapunov=False)
    if ctx is None:
        res = sweep(study.model, rpm, **kw)
    else:
        with ctx.progress(rpm.size, "nvh settle") as bar:
            res = sweep(study.model, rpm, **kw,
                        callback=lambda rec: bar.update(1, f"{rec.param:.4g} rpm"))
    ok = res.status == 0
    if not np.any(ok):
        raise NumericalFailure(f"nvh: no speed of the [nvh] grid settled: {res.message[0]}")
    return res.param[ok], res.u_end[ok], "nvh grid"


def order_lines(gearbox_cfg, rpm) -> tuple[np.ndarray, np.ndarray, tuple]:
    """(tooth-pass frequency of each mesh (P, n meshes), rotation frequency of each shaft
    (P, n shafts), shaft names) [Hz] at the driving speeds ``rpm``."""
    rpm = np.atleast_1d(np.asarray(rpm, dtype=float))
    shaft_p, gear_p = gearbox_cfg.speed_ratios()
    teeth = [gearbox_cfg.gears[gearbox_cfg.gear_index(m.gear_a, "")].teeth
             * abs(gear_p[gearbox_cfg.gear_index(m.gear_a, "")]) for m in gearbox_cfg.meshes]
    return (np.outer(rpm / 60.0, teeth), np.outer(rpm / 60.0, np.abs(shaft_p)),
            tuple(sh.name for sh in gearbox_cfg.shafts))


def _bearings(study: Study):
    """[(name, element indices, radial units (n, 2))] of the rolling-element bearings."""
    gm = study.gearbox
    out = []
    for key, idx in study.contact_groups.items():
        if not key.startswith("bearing:"):
            continue
        units = np.array([gm.contacts[j].vector.parts[0][2][:2] for j in idx], dtype=float)
        out.append((key.split(":", 1)[1], np.asarray(idx), units))
    return out


def _record(study: Study, p: float, u0, R: int, S: int, opts):
    """The trajectory over R whole mesh periods from ``u0`` with S samples per period."""
    T = study.model.excitation_period(p)
    t = np.arange(R * S) * (T / S)
    return t, R * T, integrate(study.model, p, u0, 0.0, R * T, t_eval=t, options=opts)


def run(study: Study, scene, ctx: RunContext, previous=None) -> AnalysisOutcome:
    cfg = scene.nvh
    gm, model = study.gearbox, study.model
    t_start = time.perf_counter()
    rpm, states0, source = steady_points(study, scene, previous, ctx)
    t_settle = time.perf_counter() - t_start
    R, S = cfg.record_periods, cfg.samples_per_period
    opts = integration_options(scene, record=True)
    mesh = study.contact_groups.get("mesh", np.zeros(0, int))
    bearings = _bearings(study)
    smap, note = surface_map(gm)
    want = {float(rpm[int(np.argmin(np.abs(rpm - r)))]) for r in cfg.velocity_rpms}
    records = {"dte": [], "mesh_force": [], "bearing_force": []}
    parseval = {k: 0.0 for k in records}
    erp, erp_bins, kept, rates_at, best, warnings = [], [], [], {}, (-1.0, None), []
    with ctx.progress(len(rpm), "nvh") as bar:
        for p, u0 in zip(rpm, states0):
            p = float(p)
            t, span, tr = _record(study, p, u0, R, S, opts)
            bar.update(1, f"{p:.4g} rpm")
            if not tr.ok:
                warnings.append(f"nvh: {p:g} rpm left out: {tr.message}")
                continue
            delta, _, force = contact_history(model, p, t, tr.u)
            force = force * study.force_unit_n
            bforce = [np.einsum("jt,jc->ct", force[idx], units) for _, idx, units in bearings]
            sig = {"dte": delta[mesh], "mesh_force": force[mesh],
                   "bearing_force": np.concatenate(bforce) if bforce else np.zeros((0, t.size))}
            for k, x in sig.items():
                spec = amplitude_spectrum(x, span)
                records[k].append(spec.amplitude)
                if x.size:
                    parseval[k] = max(parseval[k], spec.parseval_error)
            if smap is not None:
                rates = smap.modal_rates(tr.u, model.n_modes)
                erp.append(erp_watts(smap.gram, rates, cfg.rho_air, cfg.c_air))
                erp_bins.append(erp_spectrum(smap.gram, rates, cfg.rho_air, cfg.c_air))
                if p in want:
                    rates_at[p] = rates
                elif not want and erp[-1] > best[0]:
                    best = (erp[-1], (p, rates))     # no speeds asked: the largest ERP
            kept.append(p)
    if not kept:
        raise NumericalFailure(f"nvh: every steady point failed; first: {warnings[0]}")
    if best[1] is not None:
        rates_at[best[1][0]] = best[1][1]
    rpm = np.array(kept)
    erp_w = np.array(erp) if smap is not None else None
    fields = {p: rms_velocity_field(smap, r) for p, r in sorted(rates_at.items())}
    order = np.arange(R * S // 2 + 1) / R
    mesh_hz, shaft_hz, shaft_names = order_lines(scene.gearbox, rpm)
    names = {"dte": tuple(gm.contacts[j].name for j in mesh),
             "mesh_force": tuple(gm.contacts[j].name for j in mesh),
             "bearing_force": tuple(f"{b}:{c}" for b, _, _ in bearings for c in ("X", "Y"))}
    res = NvhResult(rpm=rpm, order=order, freq_hz=np.outer(model.excitation_frequency(rpm)
                                                           / (2 * np.pi * study.time_unit_s),
                                                           order),
                    amplitudes={k: np.array(v) for k, v in records.items()}, channels=names,
                    units={"dte": "m", "mesh_force": "N", "bearing_force": "N"},
                    parseval=parseval, mesh_hz=mesh_hz, shaft_hz=shaft_hz,
                    shaft_names=shaft_names, source=source, erp_w=erp_w, erp_note=note,
                    erp_per_bin=np.array(erp_bins) if smap is not None else None,
                    surface=smap, velocity_fields=fields, study=study)
    summary = {"status": "ok" if not warnings else "partial", "points": int(rpm.size),
               "source": source, "record_periods": R, "samples_per_period": S,
               "resolution_orders": 1.0 / R, "window": "none (whole mesh periods)",
               "parseval_max_rel_error": parseval, "settle_wall_s": t_settle,
               "wall_s": time.perf_counter() - t_start}
    if erp_w is not None:
        k = int(np.argmax(erp_w))
        parseval["erp"] = float(np.max(np.abs(res.erp_per_bin.sum(axis=1) - erp_w)
                                       / np.maximum(erp_w, np.finfo(float).tiny)))
        summary.update({"erp_max_w": float(erp_w[k]), "erp_max_db": float(erp_db(erp_w[k])),
                        "erp_max_at_rpm": float(rpm[k]), "surface_area_m2": smap.area,
                        "surface_facets": int(smap.areas.size), "rho_air": cfg.rho_air,
                        "c_air": cfg.c_air, "velocity_fields_rpm": sorted(fields)})
    else:
        summary["erp"] = note
    return AnalysisOutcome(summary=summary, result=res, warnings=tuple(warnings))
