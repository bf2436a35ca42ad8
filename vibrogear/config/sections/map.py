"""[map]: a speed x load operating map of a gearbox (``vibrogear map SCENE``).

The grid is ``n_speeds`` driving speeds from ``rpm_min`` to ``rpm_max`` times ``n_loads``
static loads.  The load is given either as the transmitted input torque (``torque_min`` /
``torque_max``, N m: the torque the static state carries at the motor couplings) or as the twist
of the motor coupling (``twist_min`` / ``twist_max``, rad), exactly one of the two; every
coupling's twist is scaled by the same factor, so the scene's load pattern (motor and load
side) is kept.  Each load row is a sweep over speed with this section's sweep settings
(:class:`~vibrogear.config.options.SweepOptions`: transient, record, directions, period
tolerance, workers, ...).  ``curves``: also locate the fold (LP) and period-doubling (PD)
points of the period-1 branch at each load by pseudo-arclength continuation in speed and
join them into curves in the (speed, load) plane.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..base import ConfigError, spec
from ..options import SweepOptions, check_range

__all__ = ["MapConfig"]


@dataclass(frozen=True, kw_only=True)
class MapConfig(SweepOptions):
    """[map]: speeds x loads, the sweep settings of each load row, and the bifurcation
    curves' continuation settings."""
    rpm_min: float = spec(gt=0.0, le=1e6, doc="driving speed, lower end [rpm]")
    rpm_max: float = spec(gt=0.0, le=1e6, doc="driving speed, upper end [rpm]")
    n_speeds: int = spec(40, ge=2, le=100_000, doc="speeds per load row")
    n_loads: int = spec(6, ge=1, le=10_000, doc="load rows")
    torque_min: float | None = spec(None, ge=0.0, le=1e9, doc="transmitted input torque, "
                                    "lower end [N m] (or give twist_min/twist_max)")
    torque_max: float | None = spec(None, ge=0.0, le=1e9, doc="input torque, upper end [N m]")
    twist_min: float | None = spec(None, ge=0.0, le=10.0, doc="twist of the motor coupling, "
                                   "lower end [rad] (or give torque_min/torque_max)")
    twist_max: float | None = spec(None, ge=0.0, le=10.0, doc="motor twist, upper end [rad]")
    rtol: float | None = spec(None, gt=0.0, lt=1.0, doc="the integrator's rtol for the map "
                              "(atol = 1e-6 rtol); default: [integration] rtol where given, "
                              "else the rtol the accuracy asks for (as a sweep's)")
    force_periods: int = spec(4, ge=1, le=1000, doc="mesh periods sampled after each point "
                              "for the largest mesh force")
    force_samples: int = spec(128, ge=8, le=100_000, doc="samples per mesh period for the "
                              "largest mesh force")
    curves: bool = spec(False, doc="locate LP and PD points of the period-1 branch at each "
                        "load (continuation in speed) and draw them as curves over the map")
    curve_margin: float = spec(150.0, gt=0.0, le=1e6, doc="rpm added on each side of the "
                               "previous load's bifurcation speeds: the next load's window")
    curve_ds: float = spec(20.0, gt=0.0, doc="continuation step [rpm]")
    curve_ds_max: float = spec(40.0, gt=0.0, doc="largest continuation step [rpm]")
    curve_max_points: int = spec(200, ge=2, le=100_000, doc="branch points per window")
    curve_transient_periods: int = spec(200, ge=0, le=1_000_000, doc="periods integrated "
                                        "to find each window's starting orbit")

    def validate(self, path: str) -> None:
        check_range(self, path, "rpm_min", "rpm_max")
        torque = (self.torque_min, self.torque_max)
        twist = (self.twist_min, self.twist_max)
        has_t, has_w = any(v is not None for v in torque), any(v is not None for v in twist)
        if has_t and has_w:
            raise ConfigError(f"{path}.twist_min", "give the load either as torque_min/"
                              "torque_max [N m] or as twist_min/twist_max [rad], not both")
        if not (has_t or has_w):
            raise ConfigError(f"{path}.torque_min", "missing: the load range, as torque_min/"
                              "torque_max [N m] or as twist_min/twist_max [rad]")
        keys = ("torque_min", "torque_max") if has_t else ("twist_min", "twist_max")
        for k in keys:
            if getattr(self, k) is None:
                raise ConfigError(f"{path}.{k}", f"missing: {keys[0]} and {keys[1]} go together")
        lo, hi = (getattr(self, k) for k in keys)
        if self.n_loads > 1:
            check_range(self, path, *keys)
        elif lo != hi:
            raise ConfigError(f"{path}.n_loads", f"one load needs {keys[0]} = {keys[1]}, got "
                              f"{lo:g} and {hi:g}; or set n_loads >= 2")
        if not self.curve_ds <= self.curve_ds_max:
            raise ConfigError(f"{path}.curve_ds_max", f"must be >= curve_ds = "
                              f"{self.curve_ds:g}, got {self.curve_ds_max:g}")

    def check_couplings(self, gearbox, path: str) -> None:
        """The load is scaled from the motor coupling: the scene needs one, with twist > 0
        (stiffness > 0 is the coupling's own rule)."""
        motors = [i for i, c in enumerate(gearbox.couplings) if c.role == "motor"]
        if not motors:
            raise ConfigError("gearbox.couplings", f"[{path}] scales the load of the motor "
                              "coupling: the scene needs a coupling with role = \"motor\"")
        if not gearbox.couplings[motors[0]].static_twist > 0:
            raise ConfigError(f"gearbox.couplings[{motors[0]}].twist", f"[{path}] scales the "
                              "scene's twists: the motor coupling needs twist > 0 (any value "
                              "sets the load pattern; the map's range sets the load), got 0")

    @property
    def load_kind(self) -> str:
        """"torque" or "twist": how the load range is given."""
        return "twist" if self.twist_min is not None else "torque"

    def speeds(self) -> np.ndarray:
        return np.linspace(self.rpm_min, self.rpm_max, self.n_speeds)

    def load_values(self) -> np.ndarray:
        """The load rows in the unit given (N m or rad)."""
        lo, hi = ((self.twist_min, self.twist_max) if self.load_kind == "twist"
                  else (self.torque_min, self.torque_max))
        return np.linspace(lo, hi, self.n_loads)
