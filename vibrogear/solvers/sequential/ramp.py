"""Transients under a varying speed (run-up / run-down) by chunks of constant speed.

The model's excitation is periodic in the phase W t (W = omega_per_param * param) and its
spin is s = spin_per_param * param, both at one fixed parameter per :func:`integrate`
call.  A speed profile param(t) is followed by chunks that each advance the excitation
phase by dphi = 2 pi / chunks_per_period at a constant parameter p_k:

* chunk k starts at the accumulated phase phi_k = k dphi and lasts dt_k = dphi / W_k; it is
  integrated over the model's local time [t0, t0 + dt_k] with t0 = (phi_k mod 2 pi P) / W_k
  (P = the forcing's common period in base periods, ``forcing_period_multiple``: 2 pi P is the
  excitation's whole period in phase),
  so the excitation cos(n_h W_k t) continues the phase of the chunk before (the state is
  carried over unchanged);
* ``midpoint=True`` (default): W_k = W(t_k + dt_k / 2), the speed at the chunk's midpoint
  (predicted with dt = dphi / W(t_k)): the applied phase departs from the exact integral of
  W by at most |W'| dt^2 / 8 inside a chunk and not at all at its ends for a linear
  profile: the response converges at second order in dt.  ``midpoint=False``: the speed
  at the chunk start (first order).

Each chunk's first trial step is the one the chunk before proposed (not a fresh start
from a tiny step: 47 instead of 52 steps per mesh period on two_stage at 1500-1800 rpm,
one chunk per period).

Samples are taken at every 2 pi / samples_per_period of phase, so each excitation period
holds exactly ``samples_per_period`` of them and the samples are uniform in the phase (in
the shaft angle of a gearbox): the order tracking needs no interpolation.  Only the
contact deformations of ``rows`` are kept (the states of a long run would not fit in
memory); the monitored contact's extrema and contact losses are also kept per chunk from
the integrator (they see between the samples).

What the chunks of constant speed would leave out, the inertia torque of the acceleration,
is applied: the model's coordinates are deviations from the
rigid rotation of the gear train at the prescribed speed, so an accelerating profile adds
the d'Alembert force -M r dOmega/dt (modal: -Phi^T M r dOmega/dt, r the rigid rotation per
unit driving-shaft angle).  Given ``inertia_force`` (the modal force per unit d param / dt,
:meth:`~vibrogear.models.gearbox.model.GearboxModel.inertia_force`), each chunk adds it times
the profile's mean slope over the chunk to the constant forcing F0: constant within a
linear segment (one model per slope, packed once), so the chunks leave nothing out of a
piecewise-linear profile but the steps of the acceleration at its knots, which are the
profile's own.  At a constant speed the slope is zero and the model is used unchanged
(bit for bit the run without it).  Its size: a quasi-static mesh shift J_eff alpha / (k r_b)
(tests/unit/test_runup_inertia.py), J_eff the inertia the mesh accelerates less what the
couplings to the prescribed discs carry: on two_stage -0.06 % of the G1 deformation at
300 rpm/s, -0.6 % at 3000 rpm/s, below the chaotic rattle's spread; but the free gear's
inertia torque exceeds its drag at 3000 rpm/s, moving it to its other flank in a run-down
(README, run-up).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from ...config.options import IntegrationOptions
from ...models.contact_law import harmonic_series
from ...models.reduced import Forcing, ReducedModel
from ..integrator.integrate import integrate
from ...status import Outcome, Status

__all__ = ["SpeedProfile", "RampResult", "ramp"]


def _frozen(a) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class SpeedProfile:
    """param(t), linear between the knots ``times`` (model time units, from 0, increasing)."""
    times: np.ndarray
    params: np.ndarray

    def __post_init__(self):
        t, p = _frozen(self.times), _frozen(self.params)
        if t.ndim != 1 or t.shape != p.shape or t.size < 2:
            raise ValueError("times and params must be 1-D of equal length >= 2")
        if t[0] != 0.0 or np.any(np.diff(t) <= 0.0):
            raise ValueError("times must start at 0 and increase strictly")
        if np.any(p <= 0.0) or not np.all(np.isfinite(p)):
            raise ValueError("params must be finite and > 0")
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "params", p)

    @property
    def duration(self) -> float:
        return float(self.times[-1])

    def at(self, t):
        return np.interp(t, self.times, self.params)

    def reversed(self) -> "SpeedProfile":
        """The same profile run backwards in time (a run-up becomes a run-down)."""
        return SpeedProfile(self.duration - self.times[::-1], self.params[::-1])

    @staticmethod
    def of(times, params, time_unit: float = 1.0) -> "SpeedProfile":
        """A profile from times in seconds (``time_unit``: seconds per model time unit)."""
        return SpeedProfile(np.asarray(times, float) / time_unit, params)


@dataclass(frozen=True, eq=False)
class RampResult:
    profile: SpeedProfile
    rows: np.ndarray            # contact indices kept
    t: np.ndarray               # (n,) model time of the samples
    param: np.ndarray           # (n,) the profile's parameter at t
    held: np.ndarray            # (n,) the parameter held by the sample's chunk
    phase: np.ndarray           # (n,) excitation phase [rad]: j 2 pi / samples_per_period
    delta: np.ndarray           # (len(rows), n) contact deformations
    delta_dot: np.ndarray       # (len(rows), n) their rates (model units)
    samples_per_period: int
    chunks_per_period: int
    midpoint: bool
    chunk_t: np.ndarray         # (chunks,) start time of each chunk
    chunk_param: np.ndarray     # (chunks,) parameter held
    monitor_min: np.ndarray     # (chunks,) monitored contact: extrema over the chunk
    monitor_max: np.ndarray
    monitor_losses: np.ndarray  # (chunks,) contact losses of the monitored contact
    u_end: np.ndarray
    status: Status
    message: str
    chunks: int
    steps: int
    rejected: int
    rhs_calls: int
    events: int
    wall_time: float
    error_estimate: float       # sum of the integrator's accumulated local error estimates
    phase_deviation: float      # max over chunks of |applied - exact phase| inside a chunk [rad]
    settle_steps: int = 0
    inertia_torque: bool = False  # the inertia force of the acceleration was applied

    @property
    def outcome(self) -> Outcome:
        return Outcome(self.status, self.message, {
            "chunks": self.chunks, "steps": self.steps, "rejected": self.rejected,
            "rhs_calls": self.rhs_calls, "events": self.events}, self.wall_time,
            {"accumulated_local_error": self.error_estimate,
             "phase_deviation_rad": self.phase_deviation})

    @property
    def ok(self) -> bool:
        return self.status == Status.OK

    @property
    def periods(self) -> int:
        """Whole excitation periods sampled."""
        return self.t.size // self.samples_per_period



def _phase_periods(model) -> int:
    """Base periods after which the forcing's phase repeats: its common period (also where
    the sampling solvers use base periods, ``multi_frequency``); a long count where it has
    none within the model's limit (the phase then simply accumulates)."""
    return model.forcing_period_multiple or 2 ** 40

def ramp(model: ReducedModel, profile: SpeedProfile, u0, *,
         options: IntegrationOptions = IntegrationOptions(), chunks_per_period: int = 4,
         samples_per_period: int = 64, midpoint: bool = True, settle_periods: int = 0,
         rows=None, callback=None, inertia_force=None) -> RampResult:
    """Integrate ``model`` from ``u0`` along ``profile`` (see the module docstring).

    ``settle_periods``: base (mesh) periods integrated first at the start speed, rounded up
    to whole excitation periods (not
    sampled; they end at phase 0).  ``rows``: contacts whose deformation is sampled
    (default all).  ``callback(t, param)`` after each chunk; returning False stops the run
    (status STOPPED_BY_CALLBACK, what was done is returned).  ``inertia_force``: (m,)
    modal force per unit d param / dt (model units), applied times each chunk's mean
    slope (the inertia torque of the acceleration; None: left out)."""
    wall = time.perf_counter()
    if samples_per_period % chunks_per_period:
        raise ValueError("samples_per_period must be a multiple of chunks_per_period")
    if inertia_force is not None and np.shape(inertia_force) != (model.n_modes,):
        raise ValueError(f"inertia_force must have {model.n_modes} entries (one per mode)")
    ct = model.contacts
    rows = np.arange(ct.count) if rows is None else np.asarray(rows, dtype=int)
    m = model.n_modes
    C = ct.directions[rows]
    run = _Run(u=np.array(u0, dtype=float))
    a_W = model.omega_per_param
    if settle_periods > 0:
        p0 = float(profile.params[0])
        # whole excitation periods, so that the chunks continue its phase from 0 (the
        # forcing's own common period, also where the solvers sample per base period)
        P = model.forcing_period_multiple or 1     # none: the slow phases restart there
        whole = -(-settle_periods // P) * P
        tr = integrate(model, p0, run.u, 0.0, whole * model.base_period(p0),
                       options=options)
        run.settle_steps = tr.steps
        run.add(tr)
        if not tr.ok:
            run.status, run.message = tr.status, f"settling at the start speed: {tr.message}"
        run.u = tr.u_end
        run.h = tr.next_first_step
    dphi = 2 * np.pi / chunks_per_period
    spc = samples_per_period // chunks_per_period
    dphi_s = 2 * np.pi / samples_per_period
    T_end = profile.duration
    slopes = np.diff(profile.params) / np.diff(profile.times)               # d param / dt
    rates = np.abs(slopes) * a_W                                             # |dW/dt|
    accelerated = {}                                 # slope -> model with the inertia force
    t, k = 0.0, 0
    while run.status == Status.OK and t < T_end * (1 - 1e-13):
        W = a_W * float(profile.at(t))
        dt = dphi / W
        if midpoint:
            W = a_W * float(profile.at(t + 0.5 * dt))
            dt = dphi / W
        n = spc
        if t + dt >= T_end:           # the last chunk: cut at the end of the profile
            dt = T_end - t
            W = a_W * float(profile.at(t + 0.5 * dt)) if midpoint else W
            n = min(spc, int(np.floor(W * dt / dphi_s * (1 - 1e-12))) + 1)
        p = W / a_W
        t0 = (k % (chunks_per_period * _phase_periods(model))) * dphi / W
        t_eval = t0 + np.arange(n) * dphi_s / W
        chunk_model = model if inertia_force is None else _with_inertia(
            model, inertia_force, _chunk_slope(profile, slopes, t, dt), accelerated)
        tr = integrate(chunk_model, p, run.u, t0, t0 + dt, t_eval=t_eval, options=options,
                       first_step=run.h)
        run.add(tr)
        if not tr.ok:
            run.status = tr.status
            run.message = f"chunk {k} at t = {t:.6g}, {model.param_name} = {p:.6g}: {tr.message}"
            break
        x, v = tr.u[:, :m], tr.u[:, m:]
        run.parts.append((t + (t_eval - t0), np.full(n, p), C @ x.T, C @ v.T))
        run.chunk.append((t, p, tr.monitor_min, tr.monitor_max, tr.monitor_losses))
        i = np.searchsorted(profile.times, t + 0.5 * dt) - 1
        rate = float(np.max(rates[max(i - 1, 0):i + 2]))
        run.deviation = max(run.deviation, rate * dt * dt / (8.0 if midpoint else 2.0))
        run.u = tr.u_end
        run.h = tr.next_first_step
        t += dt
        k += 1
        if callback is not None and callback(t, p) is False:
            run.status = Status.STOPPED_BY_CALLBACK
            run.message = f"{run.status.message} at t = {t:.6g}"
            break
    res = _result(model, profile, rows, run, samples_per_period, chunks_per_period, midpoint,
                  time.perf_counter() - wall)
    return replace(res, inertia_torque=inertia_force is not None)


def _chunk_slope(profile: SpeedProfile, slopes, t: float, dt: float) -> float:
    """d param / dt over the chunk [t, t + dt]: its segment's slope (the same float for
    every chunk of a segment), the mean slope where the chunk spans a knot."""
    last = slopes.size - 1
    i = min(max(int(np.searchsorted(profile.times, t, side="right")) - 1, 0), last)
    j = min(max(int(np.searchsorted(profile.times, t + dt, side="left")) - 1, 0), last)
    if i == j:
        return float(slopes[i])
    return float((profile.at(t + dt) - profile.at(t)) / dt)


def _with_inertia(model: ReducedModel, force, slope: float, cache: dict) -> ReducedModel:
    """``model`` with F0 + force * slope (the model itself at slope 0: bit for bit)."""
    if slope == 0.0:
        return model
    out = cache.get(slope)
    if out is None:
        fo = model.forcing
        out = cache[slope] = replace(model, forcing=Forcing(
            fo.F0 + slope * np.asarray(force, dtype=float), fo.Fc, fo.Fs))
    return out


@dataclass
class _Run:
    """What the chunk loop accumulates: samples, chunk records, the state, the outcome and
    the counters (summed in :meth:`add`, the one place)."""
    u: np.ndarray
    parts: list = field(default_factory=list)
    chunk: list = field(default_factory=list)
    status: Status = Status.OK
    message: str = "ok"
    counters: np.ndarray = field(default_factory=lambda: np.zeros(4, dtype=np.int64))
    err: float = 0.0
    deviation: float = 0.0
    settle_steps: int = 0
    h: float | None = None       # the step the last chunk's controller proposed next

    def add(self, tr) -> None:
        """Count an integration: steps, rejected, rhs calls, events; its error estimate."""
        self.counters += tr.counts
        self.err += tr.error_estimate


def _result(model, profile, rows, run: _Run, sps, cpp, midpoint, wall) -> RampResult:
    ct = model.contacts
    nr = rows.size
    parts, chunk, counters = run.parts, run.chunk, run.counters
    if parts:
        t = np.concatenate([q[0] for q in parts])
        held = np.concatenate([q[1] for q in parts])
        cx = np.hstack([q[2] for q in parts])
        cv = np.hstack([q[3] for q in parts])
    else:
        t = held = np.zeros(0)
        cx = cv = np.zeros((nr, 0))
    phase = np.arange(t.size) * (2 * np.pi / sps)
    # the excitation's own phase is W_k t_local = phase mod 2 pi: e(t) from it directly,
    # e'(t) = W_k de/dphase
    W = held * model.omega_per_param
    e, de = harmonic_series(ct.error_cos[rows], ct.error_sin[rows], 1.0,
                            np.mod(phase, 2 * np.pi * _phase_periods(model)),
                            orders=model.harmonic_orders)
    delta = cx - e
    delta_dot = cv - de * W
    ch = np.array(chunk, dtype=float).reshape(-1, 5)
    return RampResult(
        profile=profile, rows=rows, t=t, param=profile.at(t), held=held, phase=phase,
        delta=delta, delta_dot=delta_dot, samples_per_period=sps, chunks_per_period=cpp,
        midpoint=midpoint, chunk_t=ch[:, 0], chunk_param=ch[:, 1], monitor_min=ch[:, 2],
        monitor_max=ch[:, 3], monitor_losses=ch[:, 4].astype(np.int64), u_end=run.u,
        status=run.status, message=run.message if run.status else "ok", chunks=len(chunk),
        steps=int(counters[0]), rejected=int(counters[1]), rhs_calls=int(counters[2]),
        events=int(counters[3]), wall_time=wall, error_estimate=float(run.err),
        phase_deviation=float(run.deviation), settle_steps=run.settle_steps)
