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

from .base import ConfigError, spec

__all__ = ["RunupConfig"]

_RAMP = ("rpm_start", "rpm_end", "rate")


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

    @property
    def rpm_range(self) -> tuple[float, float]:
        rpm = self.profile()[1]
        return min(rpm), max(rpm)
