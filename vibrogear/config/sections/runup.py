"""[runup]: run-up / run-down transients of a gearbox (``vibrogear runup``).

The driving speed is either a ramp (``rpm_start``, ``rpm_end``, ``rate`` in rpm/s) or a
``table`` of (time s, rpm) pairs, linear between them: exactly one of the two.  The run
starts from the static equilibrium at the start speed, held ``settle_periods`` mesh periods
at that speed (not recorded).  ``directions = ["up", "down"]`` also runs the profile
backwards (rpm_end -> rpm_start), from the static equilibrium at its own start speed.
``inertia_torque`` (default true) applies the inertia torque of the acceleration (the
d'Alembert force of the accelerating rigid rotation of the gear train, -M r dOmega/dt);
``"both"`` runs each direction with and without it (``<d>`` and ``<d>_no_inertia``).
"""
from __future__ import annotations

from dataclasses import dataclass

from ..base import ConfigError, spec

__all__ = ["RunupConfig", "MAX_RUNUP_BYTES", "gearbox_orders"]

_RAMP = ("rpm_start", "rpm_end", "rate")

#: bytes of the result per sample: time, profile and held speed, phase; per kept contact
#: its deformation and rate (the run's peak, with the concatenation, is about twice this)
_BYTES_PER_SAMPLE = 4 * 8
_BYTES_PER_SAMPLE_ROW = 2 * 8
#: the largest run-up result (all runs together) accepted: far above any run-up of minutes
#: (gear_pair at 5 rpm/s over 800 rpm, up and down: 3.4 GB), far below a run of 1e7 s
MAX_RUNUP_BYTES = 16 * 2**30


def gearbox_orders(gearbox, mesh_orders) -> tuple[tuple[str, ...], tuple[float, ...], int]:
    """(names, orders per driving-shaft revolution, teeth of the excitation mesh's gear_a)
    from the [gearbox] config alone (speed ratios from the tooth counts, no FE model): each
    mesh's ``mesh_orders`` harmonics (``G1_1x``) and 1x of each shaft (``driving_1x``)."""
    shaft_p, gear_p = gearbox.speed_ratios()
    names, orders = [], []
    for m in gearbox.meshes:
        ka = gearbox.gear_index(m.gear_a, "")
        f1 = gearbox.gears[ka].teeth * abs(gear_p[ka])
        for h in mesh_orders:
            names.append(f"{m.name}_{h}x")
            orders.append(float(h * f1))
    for sh, p in zip(gearbox.shafts, shaft_p):
        names.append(f"{sh.name}_1x")
        orders.append(float(abs(p)))
    teeth = (gearbox.gears[gearbox.gear_index(gearbox.meshes[0].gear_a, "")].teeth
             if gearbox.meshes else 1)
    return tuple(names), tuple(orders), int(teeth)


@dataclass(frozen=True)
class RunupConfig:
    rpm_start: float | None = spec(None, gt=0.0, doc="ramp: driving speed at t = 0 [rpm]")
    rpm_end: float | None = spec(None, gt=0.0, doc="ramp: driving speed at the end [rpm]")
    rate: float | None = spec(None, gt=0.0, doc="ramp: |d rpm / dt| [rpm/s]")
    table: tuple[tuple[float, float], ...] | None = spec(
        None, min_len=2, doc="(time s, rpm) pairs, times from 0 strictly increasing, rpm > 0")
    directions: tuple[str, ...] = spec(("up",), min_len=1, max_len=2, choices=("up", "down"),
                                       doc="up: the profile as given; down: run backwards")
    chunks_per_period: int = spec(4, ge=1, le=64, doc="chunks of constant speed per mesh period")
    samples_per_period: int = spec(64, ge=8, le=4096,
                                   doc="samples per mesh period (a multiple of chunks_per_period)")
    midpoint: bool = spec(True, doc="speed of a chunk at its midpoint (2nd order), else its start")
    settle_periods: int = spec(1000, ge=0, le=1_000_000,
                               doc="mesh periods held at the start speed before the run")
    window_revs: int = spec(8, ge=1, le=10_000,
                            doc="order tracking: window of driving-shaft revolutions")
    mesh_orders: tuple[int, ...] = spec((1, 2, 3), min_len=1, max_len=10, ge=1, le=100,
                                        doc="harmonics of each mesh frequency tracked")
    spectrogram_s: float = spec(0.05, gt=0.0, doc="waterfall: segment length [s]")
    inertia_torque: bool | str = spec(True, doc="apply the inertia torque of the "
                                      "acceleration (true / false), or \"both\": each "
                                      "direction with and without it")
    rtol: float | None = spec(None, gt=0.0, lt=1.0, doc="the integrator's rtol for the run "
                              "(atol = 1e-6 rtol); default: the [integration] section's where "
                              "given, else the rtol the [sweep] accuracy asks for")

    def validate(self, path: str) -> None:
        p = f"{path}." if path else ""
        if isinstance(self.inertia_torque, str) and self.inertia_torque != "both":
            raise ConfigError(f"{p}inertia_torque", f"expected true, false or \"both\", got "
                              f"{self.inertia_torque!r}")
        given = [k for k in _RAMP if getattr(self, k) is not None]
        if self.table is not None and given:
            raise ConfigError(f"{p}table", f"give either the ramp ({', '.join(_RAMP)}) or a "
                              f"table of (time s, rpm) pairs, not both ({given[0]} is set)")
        if self.table is None:
            missing = [k for k in _RAMP if getattr(self, k) is None]
            if len(missing) == len(_RAMP):
                raise ConfigError(f"{p}table", "missing: give a ramp (rpm_start, rpm_end, "
                                  "rate [rpm/s]) or a table of (time s, rpm) pairs")
            if missing:
                raise ConfigError(f"{p}{missing[0]}", "missing required key of the ramp: "
                                  "expected a number > 0 (rpm_start, rpm_end, rate all needed)")
            if self.rpm_end == self.rpm_start:
                raise ConfigError(f"{p}rpm_end", f"must differ from rpm_start = "
                                  f"{self.rpm_start:g} (a constant speed: give a table)")
        else:
            times = [t for t, _ in self.table]
            if times[0] != 0.0:
                raise ConfigError(f"{p}table[0][0]", f"the first time must be 0 s, got "
                                  f"{times[0]:g}")
            for i in range(1, len(times)):
                if not times[i] > times[i - 1]:
                    raise ConfigError(f"{p}table[{i}][0]", f"times must increase strictly: "
                                      f"{times[i]:g} after {times[i - 1]:g}")
            for i, (_, rpm) in enumerate(self.table):
                if not rpm > 0.0:
                    raise ConfigError(f"{p}table[{i}][1]", f"rpm must be > 0, got {rpm:g}")
        for i, d in enumerate(self.directions):
            if d in self.directions[:i]:
                raise ConfigError(f"{p}directions[{i}]", f"{d!r} is given twice: give \"up\", "
                                  "\"down\" or both, once each")
        if self.samples_per_period % self.chunks_per_period:
            raise ConfigError(f"{p}samples_per_period", f"must be a multiple of "
                              f"chunks_per_period = {self.chunks_per_period}, got "
                              f"{self.samples_per_period}")
        nyquist = self.samples_per_period / 2
        for i, h in enumerate(self.mesh_orders):
            if not h < nyquist:
                raise ConfigError(f"{p}mesh_orders[{i}]", f"harmonic {h} of the mesh frequency "
                                  f"is not below the Nyquist limit of samples_per_period = "
                                  f"{self.samples_per_period} samples per mesh period (harmonics "
                                  f"< {nyquist:g}); raise samples_per_period or drop the order")

    def profile(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """(times s, rpm) of the profile as given (direction "up")."""
        if self.table is not None:
            return tuple(t for t, _ in self.table), tuple(r for _, r in self.table)
        duration = abs(self.rpm_end - self.rpm_start) / self.rate
        return (0.0, duration), (self.rpm_start, self.rpm_end)

    @property
    def inertia_variants(self) -> tuple[bool, ...]:
        """With / without the inertia torque: the runs of each direction (the first is the
        main one)."""
        return (True, False) if self.inertia_torque == "both" else (bool(self.inertia_torque),)

    def mesh_periods(self, gearbox) -> float:
        """Mesh periods of ``meshes[0]`` in the profile as given: the integral of rpm dt / 60
        x teeth x |speed ratio| of its gear_a (the profile is linear between its points, so
        the trapezoidal rule is exact)."""
        times, rpm = self.profile()
        revs = sum((times[i + 1] - times[i]) * (rpm[i] + rpm[i + 1]) / 2.0
                   for i in range(len(times) - 1)) / 60.0
        if not gearbox.meshes:
            return revs
        _, gear_p = gearbox.speed_ratios()
        ka = gearbox.gear_index(gearbox.meshes[0].gear_a, "")
        return revs * gearbox.gears[ka].teeth * abs(gear_p[ka])

    def check_gearbox(self, gearbox, path: str = "runup") -> float:
        """The checks of the run-up against the [gearbox] config (no FE model needed; the
        scene's validation runs them when it runs runup, so ``vibrogear check`` reports them):
        a mesh to follow; a run of at least one whole mesh period (nothing to report below)
        whose samples fit in memory (:data:`MAX_RUNUP_BYTES`, summed over the runs), else a
        ConfigError naming ``runup.rate`` (or ``runup.table``); every tracked order (each
        mesh's harmonics, each shaft's 1x) below the samples' Nyquist order, else one naming
        ``runup.mesh_orders`` (an order above it would be read as its alias).  Returns the
        run's length in mesh periods."""
        p = f"{path}." if path else ""
        if not gearbox.meshes:
            raise ConfigError("gearbox.meshes", f"[{path}] follows the mesh deformations: "
                              "the gearbox needs at least one mesh")
        periods = self.mesh_periods(gearbox)
        field = f"{p}table" if self.table is not None else f"{p}rate"
        duration = self.profile()[0][-1]
        if not periods >= 1.0:
            raise ConfigError(field, f"the run lasts {duration:.3g} s: {periods:.3g} mesh "
                              "periods, less than the one whole mesh period a run-up reports; "
                              + ("a longer table" if self.table is not None else
                                 "a slower rate or a wider speed range"))
        runs = len(self.directions) * len(self.inertia_variants)
        rows = len(gearbox.meshes)
        need = runs * periods * self.samples_per_period * (
            _BYTES_PER_SAMPLE + _BYTES_PER_SAMPLE_ROW * rows)
        if need > MAX_RUNUP_BYTES:
            raise ConfigError(field, f"the run lasts {duration:.4g} s: {periods:.4g} mesh "
                              f"periods x {self.samples_per_period} samples x {rows} meshes x "
                              f"{runs} runs need {need / 2**30:.3g} GiB; at most "
                              f"{MAX_RUNUP_BYTES / 2**30:g} GiB: "
                              + ("a shorter table" if self.table is not None else
                                 "a faster rate or a narrower speed range")
                              + " (or fewer samples_per_period)")
        names, orders, teeth = gearbox_orders(gearbox, self.mesh_orders)
        nyquist = self.samples_per_period * teeth / 2
        for name, o in zip(names, orders):
            if not o < nyquist:
                raise ConfigError(f"{p}mesh_orders", f"order {name} ({o:g} per driving-shaft "
                                  f"revolution) is not below the Nyquist order {nyquist:g} of "
                                  f"samples_per_period = {self.samples_per_period} samples per "
                                  f"mesh period ({teeth} mesh periods per revolution); raise "
                                  "samples_per_period or drop the order")
        return periods

    @property
    def rpm_range(self) -> tuple[float, float]:
        rpm = self.profile()[1]
        return min(rpm), max(rpm)
