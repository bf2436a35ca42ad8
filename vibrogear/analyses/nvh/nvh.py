"""``nvh``: spectra of the steady response over speed and the housing's radiated power.

Steady points: the settled end states u_end (excitation phase 0) of a [sweep] that ran before
in the same run (``previous["sweep"]``, the direction ``[nvh] sweep_direction``), else the
[nvh] speed grid settled here by :func:`~vibrogear.solvers.sequential.sweep.sweep` (upward, from the
static equilibrium).  From each state ``record_periods`` whole mesh periods are integrated
(:func:`~vibrogear.solvers.integrator.integrate.integrate`) with ``samples_per_period`` dense samples
each, and the one-sided amplitude spectra (:mod:`vibrogear.solvers.sequential.spectrum`: mesh
harmonics exactly on bins, no window) of

* the dynamic transmission error: each mesh's deformation delta = c . x - e(t) [m],
* the mesh forces by the contact law (:func:`~vibrogear.solvers.integrator.contact_eval.contact_history`) [N],
* each rolling-element bearing's resultant force on the housing, sum_j f_j e_j over its
  elements (radial unit e_j, rotor frame X = -x, Y = z of the housing) [N],

and, with a housing, the ERP of its outer surface (:mod:`.housing_surface`).  Frequencies
are k / (record_periods T_mesh): order k / record_periods of the first mesh.

Branch spectra (``[nvh] branch_spectra``, :func:`branch_spectra`): the same quantities for
each point of the branches of a ``continuation`` that ran before in the same run, from its
state u0 at phase 0 over exactly ONE orbit period (n_periods excitation periods).  The
point is a converged shooting solution, u(n T) = u0, so the one-period record is the
periodic signal itself and its DFT the exact line spectrum (no leakage, no window), for
unstable orbits as much as stable ones: the orbit is computed, not settled onto.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ...config.base import ConfigError
from ...pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ...solvers.integrator.contact_eval import contact_history
from ...solvers.integrator.integrate import integrate
from ...solvers.sequential.spectrum import amplitude_spectrum
from ...status import Outcome
from .housing_surface import erp_db, erp_spectrum, erp_watts, rms_velocity_field, surface_map
from .line_sources import label_points, natural_frequencies, point_summary, sweep_classes
from ..study import Study, integration_options

__all__ = ["NvhResult", "BranchSpectra", "run", "steady_points", "order_lines",
           "branch_spectra", "operating_shape"]


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
    branch: BranchSpectra | None = None    # spectra of the continuation's branch points
    #: quantity -> [Lines per point]: the named spectral lines (analyses/nvh/line_sources.py)
    lines: dict = field(default_factory=dict)
    #: evidence name -> (P,): the DTE spectrum's torus base pair and broadband measures
    evidence: dict = field(default_factory=dict)
    motion_class: np.ndarray | None = None   # (P,) the sweep's class per point (-1: none)
    #: the operating deflection shape at the ERP peak (:func:`operating_shape`; {} without)
    ods: dict = field(default_factory=dict)

    @property
    def erp_db(self) -> np.ndarray | None:
        """(P,) ERP level [dB re 1e-12 W] (None without surface data)."""
        return None if self.erp_w is None else erp_db(self.erp_w)


def operating_shape(rpm: float, rates: np.ndarray, per_bin: np.ndarray) -> dict:
    """The harmonic of the largest ERP among the bins above 0 of one steady point: ``rpm``,
    ``bin`` (k), ``erp_share`` (its part of the point's ERP) and ``modal_velocity`` (m,),
    complex: the modal rates' part at bin k is Re(X exp(2 pi i k t / span))."""
    k = 1 + int(np.argmax(per_bin[1:]))
    n = rates.shape[-1]
    X = np.fft.rfft(rates, axis=-1)[:, k] * ((1.0 if 2 * k == n else 2.0) / n)
    return {"rpm": float(rpm), "bin": k, "erp_share": float(per_bin[k] / max(per_bin.sum(), 1e-300)),
            "modal_velocity": X}


def steady_points(study: Study, scene, previous, ctx: RunContext | None = None
                  ) -> tuple[np.ndarray, np.ndarray, str, np.ndarray]:
    """(rpm (P,), settled states (P, n), source, each state's model time (P,): the
    forcing's phase, zeros unless the model is multi-frequency) of the steady points (module
    docstring)."""
    cfg = scene.nvh
    prev = (previous or {}).get("sweep") if cfg.use_sweep else None
    if prev is not None:
        res = prev.result.sweep
        keep = (res.direction == cfg.sweep_direction) & (res.status == 0)
        if not np.any(keep):
            raise NumericalFailure(f"nvh: the sweep has no settled {cfg.sweep_direction!r} "
                                   "points")
        order = np.argsort(res.param[keep], kind="stable")
        phase = np.zeros(res.param.size) if res.u_end_t is None else res.u_end_t
        return (res.param[keep][order], res.u_end[keep][order], f"sweep:{cfg.sweep_direction}",
                phase[keep][order])
    if not cfg.own_grid():
        raise ConfigError("nvh.rpm_min", "no steady points: list 'sweep' before 'nvh' in "
                          "scene.analyses (with nvh.use_sweep = true), or give the [nvh] "
                          "speed grid rpm_min / rpm_max")
    from ...config.options import SweepOptions
    from ...solvers.sequential.sweep import sweep

    rpm = np.linspace(cfg.rpm_min, cfg.rpm_max, cfg.n_speeds)
    kw = dict(settings=SweepOptions(directions=("up",), transient_periods=cfg.transient_periods,
                                    extra_transient_periods=0, record_periods=1, max_period=1,
                                    workers=1, lyapunov=False, shoot=False),
              options=integration_options(scene, record=True, study=study),
              u0=study.start(rpm[0]))
    if ctx is None:
        res = sweep(study.model, rpm, **kw)
    else:
        with ctx.progress(rpm.size, "nvh settle") as bar:
            res = sweep(study.model, rpm, **kw,
                        callback=lambda rec: bar.update(1, f"{rec.param:.4g} rpm"))
    ok = res.status == 0
    if not np.any(ok):
        raise NumericalFailure(f"nvh: no speed of the [nvh] grid settled: {res.message[0]}")
    phase = np.zeros(res.param.size) if res.u_end_t is None else res.u_end_t
    return res.param[ok], res.u_end[ok], "nvh grid", phase[ok]


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


def _record(study: Study, p: float, u0, R: int, S: int, opts, t0: float = 0.0):
    """The trajectory over R whole excitation periods from ``u0`` (R P mesh periods, P the
    model's period_multiple: 1 unless torque orders or meshes at their own frequencies make
    the excitation's period longer) with S samples per mesh period; ``t0``: the model time
    of ``u0`` (the forcing's phase: 0 unless the model is multi-frequency).  The times
    returned count from the record's start."""
    P, T = study.model.period_multiple, study.model.base_period(p)
    t = np.arange(R * P * S) * (T / S)
    tr = integrate(study.model, p, u0, t0, t0 + R * P * T, t_eval=t0 + t, options=opts)
    return t, R * P * T, tr


def _signals(study: Study, p: float, t, u, mesh, bearings) -> dict:
    """quantity -> (channels, samples): the DTE, mesh forces and bearing forces of a record."""
    delta, _, force = contact_history(study.model, p, t, u)
    force = force * study.force_unit_n
    bforce = [np.einsum("jt,jc->ct", force[idx], units) for _, idx, units in bearings]
    return {"dte": delta[mesh], "mesh_force": force[mesh],
            "bearing_force": np.concatenate(bforce) if bforce else np.zeros((0, t.size))}


@dataclass(frozen=True, eq=False)
class BranchSpectra:
    """Line spectra of the continuation's branch points (module docstring), all on the
    common order grid k / N (N = lcm of the points' n_periods): a period-n orbit's bin k
    lies at k N / n, the bins between are exactly zero (the spectrum of N periods)."""
    rpm: np.ndarray                      # (P,)
    branch: np.ndarray                   # (P,) index of the branch in the continuation
    index: np.ndarray                    # (P,) index along it (order of continuation)
    stable: np.ndarray                   # (P,) bool
    n_periods: np.ndarray                # (P,) orbit period in excitation periods
    order: np.ndarray                    # (K,) bin frequency in orders of the first mesh
    freq_hz: np.ndarray                  # (P, K)
    amplitudes: dict                     # quantity -> (P, channels, K)
    parseval: dict                       # quantity -> largest relative Parseval error
    closure: np.ndarray                  # (P,) |u(n T) - u0| / |u0| of the one-period record
    first_pass: np.ndarray               # (P,) bool: branch 0 up to its first fold
    erp_w: np.ndarray | None = None      # (P,)
    erp_per_bin: np.ndarray | None = None    # (P, K)


def _first_pass(rpm: np.ndarray, branch: np.ndarray) -> np.ndarray:
    """Branch 0's points up to its first fold (the speed monotone along the branch): the
    waterfall draws these only, as after a fold the branch revisits speeds."""
    keep = branch == 0
    idx = np.flatnonzero(keep)
    step = np.sign(np.diff(rpm[idx]))
    turn = np.flatnonzero(step != step[0]) if step.size else np.zeros(0, int)
    if turn.size:
        keep[idx[turn[0] + 1:]] = False
    return keep


def branch_spectra(study: Study, scene, continuation, mesh, bearings, smap
                   ) -> tuple[BranchSpectra | None, list]:
    """(the spectra of every point of ``continuation``'s branches, warnings): one orbit
    period from each point's u0 with ``samples_per_period`` samples per excitation period
    (module docstring).  None when every point failed."""
    cfg = scene.nvh
    S, opts = cfg.samples_per_period, integration_options(scene, record=True, study=study)
    pts = [(b, i, br.n_periods, pt) for b, br in enumerate(continuation.branches)
           for i, pt in enumerate(br.points)]
    N = int(np.lcm.reduce([n for _, _, n, _ in pts])) if pts else 1
    P = study.model.period_multiple          # mesh periods per excitation period
    K = N * P * S // 2 + 1
    rows, recs, warnings = [], {"dte": [], "mesh_force": [], "bearing_force": []}, []
    parseval, erp, erp_bins = {k: 0.0 for k in recs}, [], []
    for b, i, n, pt in pts:
        p, u0 = float(pt.param), np.asarray(pt.u0, dtype=float)
        t, span, tr = _record(study, p, u0, n, S, opts)
        if not tr.ok:
            warnings.append(f"nvh: branch {b} point {i} ({p:g} rpm) left out: {tr.message}")
            continue
        closure = float(np.linalg.norm(tr.u_end - u0) / max(np.linalg.norm(u0), 1e-300))
        for k, x in _signals(study, p, t, tr.u, mesh, bearings).items():
            spec = amplitude_spectrum(x, span)
            amp = np.zeros(x.shape[:-1] + (K,))
            amp[..., ::N // n] = spec.amplitude
            recs[k].append(amp)
            if x.size:
                parseval[k] = max(parseval[k], spec.parseval_error)
        if smap is not None:
            rates = smap.modal_rates(tr.u, study.model.n_modes)
            erp.append(erp_watts(smap.gram, rates, cfg.rho_air, cfg.c_air))
            per_bin = np.zeros(K)
            per_bin[::N // n] = erp_spectrum(smap.gram, rates, cfg.rho_air, cfg.c_air)
            erp_bins.append(per_bin)
        rows.append((p, b, i, pt.stable, n, closure))
    if not rows:
        return None, warnings
    rpm, branch, index, stable, n_per, closure = (np.array(c) for c in zip(*rows))
    model = study.model
    return BranchSpectra(
        rpm=rpm, branch=branch, index=index, stable=stable.astype(bool), n_periods=n_per,
        order=np.arange(K) / (N * P),
        freq_hz=np.outer(model.excitation_frequency(rpm) / (2 * np.pi * study.time_unit_s),
                         np.arange(K) / (N * P)),
        amplitudes={k: np.array(v) for k, v in recs.items()}, parseval=parseval,
        closure=closure, first_pass=_first_pass(rpm, branch),
        erp_w=np.array(erp) if smap is not None else None,
        erp_per_bin=np.array(erp_bins) if smap is not None else None), warnings


def run(study: Study, scene, ctx: RunContext, previous=None) -> AnalysisOutcome:
    cfg = scene.nvh
    gm, model = study.gearbox, study.model
    t_start = time.perf_counter()
    rpm, states0, source, phase0 = steady_points(study, scene, previous, ctx)
    t_settle = time.perf_counter() - t_start
    R, S = cfg.record_periods, cfg.samples_per_period
    opts = integration_options(scene, record=True, study=study)
    mesh = study.contact_groups.get("mesh", np.zeros(0, int))
    bearings = _bearings(study)
    smap, note = surface_map(gm)
    want = {float(rpm[int(np.argmin(np.abs(rpm - r)))]) for r in cfg.velocity_rpms}
    records = {"dte": [], "mesh_force": [], "bearing_force": []}
    parseval = {k: 0.0 for k in records}
    erp, erp_bins, kept, rates_at, best, warnings = [], [], [], {}, (-1.0, None), []
    solves = []             # each steady point's record: one outcome for the runner
    with ctx.progress(len(rpm), "nvh") as bar:
        for p, u0, t0 in zip(rpm, states0, phase0):
            p = float(p)
            t, span, tr = _record(study, p, u0, R, S, opts, t0=float(t0))
            solves.append(tr.outcome)
            bar.update(1, f"{p:.4g} rpm")
            if not tr.ok:
                warnings.append(f"nvh: {p:g} rpm left out: {tr.message}")
                continue
            for k, x in _signals(study, p, tr.t, tr.u, mesh, bearings).items():
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
                if erp[-1] > best[0]:
                    best = (erp[-1], (p, rates))     # the largest ERP: its field and ODS
            kept.append(p)
    if not kept:
        raise NumericalFailure(f"nvh: every steady point failed; first: {warnings[0]}")
    if best[1] is not None:
        rates_at[best[1][0]] = best[1][1]
    rpm = np.array(kept)
    erp_w = np.array(erp) if smap is not None else None
    fields = {p: rms_velocity_field(smap, r) for p, r in sorted(rates_at.items())}
    ods = {} if best[1] is None else operating_shape(*best[1], erp_bins[kept.index(best[1][0])])
    branch = None
    if cfg.branch_spectra:
        cont = (previous or {}).get("continuation")
        if cont is None:
            warnings.append("nvh.branch_spectra: no continuation ran before nvh in this run "
                            "(list 'continuation' before 'nvh' in scene.analyses): the branch "
                            "spectra are left out")
        else:
            branch, more = branch_spectra(study, scene, cont.result.result, mesh, bearings,
                                          smap)
            warnings.extend(more)
    P = model.period_multiple                # R whole excitation periods of P mesh periods
    order = np.arange(R * P * S // 2 + 1) / (R * P)
    mesh_hz, shaft_hz, shaft_names = order_lines(scene.gearbox, rpm)
    f1_hz = model.excitation_frequency(rpm) / (2 * np.pi * study.time_unit_s)
    amplitudes = {k: np.array(v) for k, v in records.items()}
    classes = sweep_classes(previous, cfg.sweep_direction, rpm) if source.startswith(
        "sweep") else np.full(rpm.size, -1, dtype=np.int64)
    modes_hz, modes_rpm = natural_frequencies(previous)
    lines, evidence, lines_summary = label_points(
        scene, rpm, f1_hz, np.outer(f1_hz, order), amplitudes, R * P * S, classes, modes_hz,
        cfg.max_order * float(np.max(mesh_hz)))
    lines_summary["modes_rpm"] = modes_rpm
    names = {"dte": tuple(gm.contacts[j].name for j in mesh),
             "mesh_force": tuple(gm.contacts[j].name for j in mesh),
             "bearing_force": tuple(f"{b}:{c}" for b, _, _ in bearings for c in ("X", "Y"))}
    res = NvhResult(rpm=rpm, order=order, freq_hz=np.outer(model.excitation_frequency(rpm)
                                                           / (2 * np.pi * study.time_unit_s),
                                                           order),
                    amplitudes=amplitudes, channels=names, lines=lines, evidence=evidence,
                    motion_class=classes,
                    units={"dte": "m", "mesh_force": "N", "bearing_force": "N"},
                    parseval=parseval, mesh_hz=mesh_hz, shaft_hz=shaft_hz,
                    shaft_names=shaft_names, source=source, erp_w=erp_w, erp_note=note,
                    erp_per_bin=np.array(erp_bins) if smap is not None else None,
                    surface=smap, velocity_fields=fields, study=study, branch=branch, ods=ods)
    summary = {"status": "ok" if not warnings else "partial", "points": int(rpm.size),
               "source": source, "record_periods": R, "samples_per_period": S,
               "resolution_orders": 1.0 / (R * P),
               "window": "none (whole excitation periods)",
               "parseval_max_rel_error": parseval, "settle_wall_s": t_settle,
               "lines": lines_summary, "points_evidence": point_summary(rpm, classes, evidence,
                                                                      lines.get("dte")),
               "wall_s": time.perf_counter() - t_start}
    if erp_w is not None:
        k = int(np.argmax(erp_w))
        parseval["erp"] = float(np.max(np.abs(res.erp_per_bin.sum(axis=1) - erp_w)
                                       / np.maximum(erp_w, np.finfo(float).tiny)))
        summary.update({"erp_max_w": float(erp_w[k]), "erp_max_db": float(erp_db(erp_w[k])),
                        "erp_max_at_rpm": float(rpm[k]), "surface_area_m2": smap.area,
                        "surface_facets": int(smap.areas.size), "rho_air": cfg.rho_air,
                        "c_air": cfg.c_air, "velocity_fields_rpm": sorted(fields),
                        "ods_order": float(order[ods["bin"]]),
                        "ods_erp_share": ods["erp_share"]})
    else:
        summary["erp"] = note
    if branch is not None:
        summary["branch_spectra"] = {
            "points": int(branch.rpm.size), "stable": int(branch.stable.sum()),
            "n_periods": sorted({int(n) for n in branch.n_periods}),
            "record": "one orbit period (n_periods excitation periods) per point",
            "max_closure_rel": float(branch.closure.max()),
            "parseval_max_rel_error": branch.parseval}
    return AnalysisOutcome(summary=summary, result=res, warnings=tuple(warnings),
                           solver=Outcome.combine(solves))
