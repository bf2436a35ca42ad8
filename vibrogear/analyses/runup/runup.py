"""Run-up and run-down transients (``vibrogear runup``, section [runup]).

The driving speed follows the section's profile (:mod:`vibrogear.solvers.sequential.ramp`: chunks of
constant speed, excitation phase continuous), from the static equilibrium at the start
speed.  Against the instantaneous speed the analysis returns, per direction:

* per mesh period, for each mesh: the envelope (min / max of the deformation) and the
  contact losses (monitored mesh: the integrator's located events, which see between the
  samples; the other meshes: from the samples);
* order tracks (:mod:`vibrogear.analyses.runup.order_tracking`) of each mesh deformation: the
  mesh orders (``mesh_orders`` x each mesh frequency) and 1x of every shaft, in orders of
  the driving shaft;
* the waterfall (spectrogram) of the monitored mesh deformation.

The inertia torque of the acceleration (``[runup] inertia_torque``, default true) is
applied through :meth:`~vibrogear.models.gearbox.model.GearboxModel.inertia_force`;
``inertia_torque = "both"`` also runs each direction without it (run key
``<direction>_no_inertia``) and the summary compares the two (``inertia_effect``: peak
upper envelope of the monitored mesh and its speed, with and without).

The report (:mod:`vibrogear.report.writers.runup`) writes ``runup.npz``, ``runup.csv`` and
the figures.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from ...config.sections.runup import MAX_RUNUP_BYTES, gearbox_orders
from ...models.contact_law import flank
from ...pipeline.executors import run_units
from ...pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ...solvers.sequential.ramp import RampResult, SpeedProfile, ramp
from ...status import Outcome
from .order_tracking import Waterfall, order_tracks, waterfall
from ..study import Study, integration_options

__all__ = ["RunupResult", "RunupRun", "run", "shaft_orders", "period_table", "jump_speed",
           "run_key", "inertia_effect", "MAX_RUNUP_BYTES", "runup_arrays"]


@dataclass(frozen=True, eq=False)
class RunupRun:
    direction: str
    time_s: np.ndarray          # (P,) start of each mesh period [s]
    rpm: np.ndarray             # (P,) mean speed over each mesh period [param unit]
    env_min: np.ndarray         # (meshes, P) deformation envelope [display unit]
    env_max: np.ndarray
    losses: np.ndarray          # (meshes, P) contact losses per mesh period
    tracks: dict                # mesh name -> OrderTracks of its deformation [display unit]
    track_rpm: np.ndarray       # (windows,) speed at the order-tracking window centres
    waterfall: Waterfall        # of the monitored mesh deformation [display unit]
    waterfall_rpm: np.ndarray   # (segments,) speed at the segment centres
    ramp: RampResult            # the solver's result (counters, status)
    jump: dict | None = None    # jump_speed of the monitored mesh's upper envelope
    inertia_torque: bool = True  # run with the inertia torque of the acceleration
    key: str = ""               # run_key: the direction, "<direction>_no_inertia" in "both"

    @property
    def main(self) -> bool:
        """The direction's main run (the other one of inertia_torque = "both" is not)."""
        return self.key in ("", self.direction)


@dataclass(frozen=True, eq=False)
class RunupResult:
    """A run-up / run-down: per run (direction; with the inertia torque or not) and mesh
    period the speed, the deformation envelope and contact losses of every mesh, order tracks
    and the waterfall.  :meth:`arrays`: the arrays of ``runup.npz`` (names and units:
    :mod:`vibrogear.report.writers.runup`); :meth:`plot`: the envelopes over the speed."""
    study: Study
    mesh_names: tuple[str, ...]
    order_names: tuple[str, ...]
    orders: np.ndarray          # per order name: cycles per driving-shaft revolution
    runs: tuple[RunupRun, ...]
    teeth: int                  # mesh periods per driving-shaft revolution

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays of ``runup.npz``, by the same names (:func:`runup_arrays`)."""
        return runup_arrays(self)

    def plot(self):
        """The deformation envelopes of every mesh against the speed
        (``runup_envelope.png``, without the steady state overlaid) as a matplotlib Figure."""
        from ...report.plots.runup import plot_envelopes
        return plot_envelopes(self)


def shaft_orders(scene, mesh_orders) -> tuple[tuple[str, ...], np.ndarray, int]:
    """(names, orders per driving-shaft revolution, teeth of the excitation mesh): each
    mesh's ``mesh_orders`` harmonics (``G1_1x``) and 1x of each shaft (``driving_1x``);
    an impact pair has the excitation's harmonics (``excitation_1x``)."""
    gb = scene.gearbox
    if gb is None:
        return tuple(f"excitation_{h}x" for h in mesh_orders), np.array(mesh_orders, float), 1
    names, orders, teeth = gearbox_orders(gb, mesh_orders)     # from the config alone
    return names, np.array(orders, dtype=float), teeth


def period_table(r: RampResult, monitor_row: int | None, gaps) -> tuple:
    """Per whole excitation period: (first sample index, min, max, contact losses) of each
    sampled contact; the monitored one (row ``monitor_row``) merged with the integrator's
    per-chunk extrema and located contact losses."""
    sps, cpp = r.samples_per_period, r.chunks_per_period
    P = r.periods
    d = r.delta[:, :P * sps].reshape(r.delta.shape[0], P, sps)
    lo, hi = d.min(axis=2), d.max(axis=2)
    touch = flank(r.delta[:, :P * sps], gaps[0][:, None], gaps[1][:, None]) != 0
    lost = np.zeros_like(touch)
    lost[:, 1:] = touch[:, :-1] & ~touch[:, 1:]
    losses = lost.reshape(lost.shape[0], P, sps).sum(axis=2)
    if monitor_row is not None and P:
        n = P * cpp
        lo[monitor_row] = np.minimum(lo[monitor_row], r.monitor_min[:n].reshape(P, cpp).min(1))
        hi[monitor_row] = np.maximum(hi[monitor_row], r.monitor_max[:n].reshape(P, cpp).max(1))
        losses[monitor_row] = r.monitor_losses[:n].reshape(P, cpp).sum(1)
    return np.arange(P) * sps, lo, hi, losses


def jump_speed(rpm, q, smooth: int = 20) -> dict | None:
    """Where the (moving-averaged over ``smooth`` periods) envelope ``q`` changes fastest:
    its speed and the change across it (200 periods either side), or None if that change
    is below a quarter of the envelope's range."""
    q = np.asarray(q, float)
    if q.size < 4 * smooth:
        return None
    qs = np.convolve(q, np.ones(smooth) / smooth, mode="valid")
    k = int(np.argmax(np.abs(np.diff(qs))))
    a, b = qs[max(k - 200, 0)], qs[min(k + 200, qs.size - 1)]
    span = float(np.ptp(q))
    if span == 0.0 or abs(b - a) < 0.25 * span:
        return None
    return {"rpm": float(rpm[k + smooth // 2]), "before": float(a), "after": float(b)}


def run_key(cfg, direction: str, inertia: bool) -> str:
    """The run's name in the files: the direction; ``<direction>_no_inertia`` for the run
    without the inertia torque when ``inertia_torque = "both"``."""
    return direction if inertia or cfg.inertia_torque != "both" else f"{direction}_no_inertia"


def inertia_effect(with_: "RunupRun", without: "RunupRun", mesh: int) -> dict:
    """Peak of the upper envelope of mesh ``mesh`` and the speed where it lies, with and
    without the inertia torque; the change of the peak [%] and the speed shift."""
    i, j = int(np.argmax(with_.env_max[mesh])), int(np.argmax(without.env_max[mesh]))
    a, b = float(with_.env_max[mesh, i]), float(without.env_max[mesh, j])
    return {"peak_with": a, "peak_without": b,
            "peak_change_percent": 100.0 * (a - b) / abs(b) if b else None,
            "rpm_at_peak_with": float(with_.rpm[i]), "rpm_at_peak_without": float(without.rpm[j]),
            "peak_speed_shift": float(with_.rpm[i] - without.rpm[j])}


def _profile(cfg, study: Study, direction: str) -> SpeedProfile:
    times, rpm = cfg.profile()
    prof = SpeedProfile.of(times, rpm, study.time_unit_s)
    return prof if direction == "up" else prof.reversed()


#: chunks between two progress ticks of a run
_TICK_EVERY = 64


def _ramp_unit(model, kw, unit, emit):
    """One direction's ramp (a work unit of :func:`~vibrogear.pipeline.executors.run_units`:
    up and down run on two cores): progress ticks through ``emit``; returns the result."""
    key, prof, u0, force = unit
    count = iter(range(1, 1 << 62))

    def tick(t, p):
        if next(count) % _TICK_EVERY == 0:
            emit((key, p))

    return ramp(model, prof, u0, callback=tick, inertia_force=force, **kw)


def _ramps(study, ctx, cfg, rows, opts) -> dict:
    """{(direction, inertia): RampResult} of the section's directions and inertia variants
    (``inertia_torque = "both"``: with and without), in parallel."""
    model = study.model
    force = None
    if any(cfg.inertia_variants):
        gb = study.gearbox
        force = gb.inertia_force() if gb is not None and gb.rigid_inertia is not None \
            else np.zeros(model.n_modes)          # no rotating train: no inertia torque
    units, keys, est = [], [], 0
    for d in cfg.directions:
        prof = _profile(cfg, study, d)
        n = int(np.ceil(np.trapz(prof.params, prof.times) * model.omega_per_param
                        / (2 * np.pi) * cfg.chunks_per_period))
        u0 = study.start(float(prof.params[0]))
        for inertia in cfg.inertia_variants:
            est += n
            keys.append((d, inertia))
            units.append((run_key(cfg, d, inertia), prof, u0, force if inertia else None))
    kw = dict(options=opts, chunks_per_period=cfg.chunks_per_period,
              samples_per_period=cfg.samples_per_period, midpoint=cfg.midpoint,
              settle_periods=cfg.settle_periods, rows=rows)
    with ctx.progress(est // _TICK_EVERY, "runup " + " + ".join(u[0] for u in units)) as bar:
        def on_result(_i, item):
            bar.update(1, f"{item[0]} {item[1]:.5g} {study.param_unit}")
        # every rank (under mpirun) gets the same list of results
        got = dict(zip(keys, run_units(partial(_ramp_unit, model, kw), units,
                                       on_result=on_result)))
    for (d, inertia), r in got.items():
        if not r.ok:
            raise NumericalFailure(f"runup {run_key(cfg, d, inertia)}: {r.message}")
    return got


def _one_run(study, cfg, key, r: RampResult, rows, orders, teeth) -> RunupRun:
    direction, inertia = key
    model = study.model
    if r.periods == 0:               # the length check's estimate rounded up to one period
        raise NumericalFailure(f"runup {run_key(cfg, direction, inertia)}: the run holds no "
                               f"whole mesh period ({r.t.size} of {r.samples_per_period} "
                               "samples); a slower rate or a wider speed range")
    prof = r.profile
    ct = model.contacts
    mon = [i for i, j in enumerate(rows) if j == model.monitor]
    first, lo, hi, losses = period_table(r, mon[0] if mon else None,
                                         (ct.gap_hi[rows], ct.gap_lo[rows]))
    sps = cfg.samples_per_period
    P = r.periods
    rpm = r.param[:P * sps].reshape(P, sps).mean(axis=1)
    scale = study.monitor.scale
    revs = r.phase / (2 * np.pi * teeth)
    tracks = {}
    for i, j in enumerate(rows):
        name = ct.names[j] if ct.names else f"c{j}"
        tracks[name] = order_tracks(revs, scale * r.delta[i], orders,
                                    samples_per_rev=sps * teeth, window_revs=cfg.window_revs)
    any_track = next(iter(tracks.values()))
    track_rpm = np.interp(any_track.revs, revs, r.param)
    t_s = r.t * study.time_unit_s
    f_mesh = model.omega_per_param * prof.params.max() / (2 * np.pi * study.time_unit_s)
    wi = mon[0] if mon else 0
    wf = waterfall(t_s, scale * r.delta[wi], segment_s=cfg.spectrogram_s,
                   fs=sps * f_mesh, f_max=1.2 * f_mesh * max(orders.max() / teeth, 1.0))
    wf_rpm = np.interp(wf.time_s, t_s, r.param)
    return RunupRun(direction=direction, time_s=t_s[first], rpm=rpm, env_min=scale * lo,
                    env_max=scale * hi, losses=losses, tracks=tracks, track_rpm=track_rpm,
                    waterfall=wf, waterfall_rpm=wf_rpm, ramp=r,
                    jump=jump_speed(rpm, scale * hi[wi]), inertia_torque=inertia,
                    key=run_key(cfg, direction, inertia))


def run(study: Study, scene, ctx: RunContext) -> AnalysisOutcome:
    cfg = scene.runup
    model = study.model
    rows = study.contact_groups.get("mesh", study.contact_groups.get("clearance"))
    rows = np.asarray(rows if rows is not None else np.arange(model.contacts.count), int)
    if rows.size == 0:
        raise NumericalFailure("runup: the model has no mesh contact to follow")
    names, orders, teeth = shaft_orders(scene, cfg.mesh_orders)
    # the run's length (one mesh period at least, the result within MAX_RUNUP_BYTES) and the
    # tracked orders below Nyquist: decided from the config, as the scene's validation does
    # (vibrogear check); again here for a scene built without it
    cfg.check_gearbox(scene.gearbox, "runup")
    opts = integration_options(scene, record=True, section=scene.runup, study=study)
    ramps = _ramps(study, ctx, cfg, rows, opts)
    runs = tuple(_one_run(study, cfg, k, r, rows, orders, teeth) for k, r in ramps.items())
    ct = model.contacts
    mesh_names = tuple(ct.names[j] if ct.names else f"c{j}" for j in rows)
    summary = {"directions": list(cfg.directions),
               "rpm_range": list(cfg.rpm_range), "meshes": list(mesh_names),
               "orders": dict(zip(names, map(float, orders))),
               "rtol": opts.rtol, "atol": opts.atol, "inertia_torque": cfg.inertia_torque,
               "runs": {}}
    for run_ in runs:
        r = run_.ramp
        P = run_.rpm.size
        summary["runs"][run_.key] = {
            "direction": run_.direction, "inertia_torque": run_.inertia_torque,
            "duration_s": r.profile.duration * study.time_unit_s, "mesh_periods": P,
            "chunks": r.chunks, "steps": r.steps, "rejected": r.rejected,
            "rhs_calls": r.rhs_calls, "events": r.events, "solver_wall_s": r.wall_time,
            "steps_per_mesh_period": (r.steps - r.settle_steps) / max(P, 1),
            "periods_with_contact_loss": {n: int(np.sum(run_.losses[i] > 0))
                                          for i, n in enumerate(mesh_names)},
            "largest_envelope_change": run_.jump,
            "error_estimate": {"accumulated_local_error": r.error_estimate,
                               "phase_deviation_rad": r.phase_deviation,
                               "chunks_per_period": r.chunks_per_period,
                               "midpoint": r.midpoint},
        }
    if cfg.inertia_torque == "both":
        wi = next((i for i, j in enumerate(rows) if j == model.monitor), 0)
        by = {(r.direction, r.inertia_torque): r for r in runs}
        summary["inertia_effect"] = {
            "mesh": mesh_names[wi], "unit": study.monitor.unit,
            **{d: inertia_effect(by[d, True], by[d, False], wi) for d in cfg.directions}}
    return AnalysisOutcome(summary=summary, result=RunupResult(
        study=study, mesh_names=mesh_names, order_names=names, orders=orders, runs=runs,
        teeth=teeth), solver=Outcome.combine(r.ramp.outcome for r in runs))


def runup_arrays(result) -> dict:
    """The arrays of ``runup.npz`` (their names and units: :mod:`vibrogear.report.writers.runup`)."""
    out = {"meshes": np.array(result.mesh_names), "order_names": np.array(result.order_names),
           "orders": np.asarray(result.orders, float), "unit": np.array(result.study.monitor.unit),
           "directions": np.array(list(dict.fromkeys(r.direction for r in result.runs))),
           "runs": np.array([r.key or r.direction for r in result.runs]),
           "inertia_torque": np.array([r.inertia_torque for r in result.runs], dtype=bool)}
    for r in result.runs:
        d = r.key or r.direction
        out[f"{d}_time"] = r.time_s
        out[f"{d}_rpm"] = r.rpm
        out[f"{d}_track_rpm"] = r.track_rpm
        for i, name in enumerate(result.mesh_names):
            out[f"{d}_env_min_{name}"] = r.env_min[i]
            out[f"{d}_env_max_{name}"] = r.env_max[i]
            out[f"{d}_losses_{name}"] = r.losses[i].astype(np.int64)
            tr = r.tracks[name]
            for k, oname in enumerate(result.order_names):
                out[f"{d}_order_{name}_{oname}"] = tr.amplitude[k]
    return out
