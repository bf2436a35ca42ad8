"""Config sections shared by all scenes: the impact pair and the analysis options."""
from __future__ import annotations

from dataclasses import dataclass

from .base import ConfigError, check_name, spec

__all__ = ["SceneInfo", "ImpactPairConfig", "IntegrationConfig", "SweepConfig",
           "ShootingConfig", "ContinuationConfig", "TimeResponseConfig", "ReportConfig",
           "CriticalDampingConfig", "ANALYSES"]

#: analyses a scene may list, with what each is for
ANALYSES = {
    "time_response": "time response from the initial state",
    "sweep": "sequential continuation (brute-force bifurcation diagram) up and down in the parameter",
    "continuation": "shooting + pseudo-arclength continuation of periodic orbits with Floquet stability",
    "report": "work-precision study: integrator tolerance and shooting residual against run time",
    "critical_damping": "bisection in zeta for the damping where the primary-resonance folds meet",
    "modes": "modal analysis (rotor or housing)",
    "campbell": "Campbell diagram of a rotor",
    "housing_sweep": "housing geometry sweep: first frequencies against one housing parameter",
    "housing_convergence": "housing mesh convergence: frequency error vs DOF vs wall time, P1 and P2",
    "reduction_accuracy": "gearbox reduction level: frequency error, MAC and response error vs run time",
}


@dataclass(frozen=True)
class SceneInfo:
    name: str = spec(doc="scene name, used in plot titles and as the output folder out/<name>")
    analyses: tuple[str, ...] = spec(min_len=1, choices=tuple(ANALYSES))
    description: str = spec("", doc="free text")

    def validate(self, path: str) -> None:
        check_name(self.name, f"{path}.name")
        seen = set()
        for i, a in enumerate(self.analyses):
            if a in seen:
                raise ConfigError(f"{path}.analyses[{i}]", f"{a!r} listed twice")
            seen.add(a)


@dataclass(frozen=True)
class ImpactPairConfig:
    """Paper eqs (12)-(15): q'' + 2 zeta q' + kappa q + g(q) = f_m + f_p cos(Omega tau)."""
    zeta: float = spec(ge=0.0, lt=1.0, doc="damping ratio (0 allowed: undamped)")
    kappa: float = spec(ge=0.0, le=1.0, doc="inner/outer stiffness ratio K/K1")
    f_m: float = spec(doc="static (mean) load")
    f_p: float = spec(ge=0.0, doc="amplitude of the harmonic load")
    b_r: float = spec(gt=0.0, doc="half clearance (backlash) b_r")
    contact_damping: float = spec(0.0, ge=0.0, doc="extra damping acting only in contact")


@dataclass(frozen=True)
class IntegrationConfig:
    rtol: float = spec(1e-9, gt=0.0, lt=1.0)
    atol: float = spec(1e-11, gt=0.0)
    max_steps: int = spec(5_000_000, gt=0)
    max_events_per_step: int = spec(20, gt=0)


def _check_range(obj, path: str, lo: str, hi: str) -> None:
    a, b = getattr(obj, lo), getattr(obj, hi)
    if not a < b:
        raise ConfigError(f"{path}.{hi}", f"must be greater than {lo} = {a:g}, got {b:g}")


@dataclass(frozen=True)
class SweepConfig:
    omega_min: float = spec(gt=0.0)
    omega_max: float = spec(gt=0.0)
    n_points: int = spec(200, ge=2, le=1_000_000)
    transient_periods: int = spec(200, ge=0, le=1_000_000)
    extra_transient_periods: int = spec(800, ge=0, le=10_000_000,
                                        doc="more transient allowed while not yet periodic")
    record_periods: int = spec(32, ge=1, le=100_000)
    directions: tuple[str, ...] = spec(("up", "down"), min_len=1, max_len=2, choices=("up", "down"))
    max_period: int = spec(8, ge=1, le=64, doc="largest n classified as period-n")
    period_tol: float = spec(1e-5, gt=0.0, lt=1.0, doc="relative Poincare-sample tolerance")
    segments: int = spec(1, ge=1, le=1000, doc="independent pieces per direction, each "
                         "starting from the static equilibrium (parallel work units)")
    workers: int | None = spec(None, ge=1, le=4096, doc="local worker processes "
                               "(default: all cores; 1: serial; under mpirun: the ranks)")

    def validate(self, path: str) -> None:
        _check_range(self, path, "omega_min", "omega_max")
        if self.max_period > self.record_periods:
            raise ConfigError(f"{path}.max_period",
                              f"must be <= record_periods = {self.record_periods}")


@dataclass(frozen=True)
class ShootingConfig:
    tol: float = spec(1e-9, gt=0.0, lt=1.0, doc="periodicity residual tolerance (relative)")
    max_iter: int = spec(25, ge=1, le=1000)


@dataclass(frozen=True)
class ContinuationConfig:
    omega_min: float = spec(gt=0.0)
    omega_max: float = spec(gt=0.0)
    start: str = spec("max", choices=("min", "max"), doc="end of the range to start from")
    ds: float = spec(0.02, gt=0.0)
    ds_min: float = spec(1e-6, gt=0.0)
    ds_max: float = spec(0.1, gt=0.0)
    max_points: int = spec(2000, ge=2, le=1_000_000)
    max_corrector_iter: int = spec(8, ge=1, le=100)
    period_doubling_branch: bool = spec(True, doc="switch onto the period-2 branch at the first PD")
    transient_periods: int = spec(300, ge=0, doc="periods integrated to find the starting orbit")

    def validate(self, path: str) -> None:
        _check_range(self, path, "omega_min", "omega_max")
        if not self.ds_min <= self.ds <= self.ds_max:
            raise ConfigError(f"{path}.ds", f"must satisfy ds_min <= ds <= ds_max "
                              f"({self.ds_min:g} <= ds <= {self.ds_max:g}), got {self.ds:g}")


@dataclass(frozen=True)
class TimeResponseConfig:
    omega: float = spec(gt=0.0, doc="excitation parameter of the run")
    periods: float = spec(100.0, gt=0.0)
    samples_per_period: int = spec(64, ge=4, le=100_000)


@dataclass(frozen=True)
class ReportConfig:
    omega: float = spec(gt=0.0, doc="parameter at which the work-precision study runs")
    rtols: tuple[float, ...] = spec((1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10), min_len=2, gt=0.0, lt=1.0)
    periods: float = spec(20.0, gt=0.0)
    shooting_tols: tuple[float, ...] = spec((1e-4, 1e-6, 1e-8, 1e-10, 1e-12), min_len=2, gt=0.0,
                                            lt=1.0, doc="shooting tolerances (integrator rtol matched)")
    repeats: int = spec(5, ge=1, le=100, doc="timing repeats per point (best time is reported)")


@dataclass(frozen=True)
class CriticalDampingConfig:
    """Bisection in zeta; one continuation over [omega_min, omega_max] per trial zeta."""
    zeta_lo: float = spec(ge=0.0, lt=1.0, doc="a damping whose primary resonance has a fold pair")
    zeta_hi: float = spec(gt=0.0, lt=1.0, doc="a damping whose primary resonance has no folds")
    omega_min: float = spec(gt=0.0, doc="continuation window: around the primary resonance only")
    omega_max: float = spec(gt=0.0)
    tol: float = spec(1e-4, gt=0.0, lt=1.0, doc="width of the final zeta bracket")
    ds: float = spec(0.02, gt=0.0)
    ds_max: float = spec(0.05, gt=0.0)
    max_points: int = spec(3000, ge=2, le=1_000_000)
    transient_periods: int = spec(300, ge=0, doc="periods integrated to find the starting orbit")
    curve_points: int = spec(6, ge=0, le=100, doc="extra zetas below the cusp, for the plot only")

    def validate(self, path: str) -> None:
        _check_range(self, path, "omega_min", "omega_max")
        _check_range(self, path, "zeta_lo", "zeta_hi")
        if not self.ds <= self.ds_max:
            raise ConfigError(f"{path}.ds", f"must be <= ds_max = {self.ds_max:g}, got {self.ds:g}")
