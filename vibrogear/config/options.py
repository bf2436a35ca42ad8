"""The solvers' own options, defined and validated once, and the continuation parameter a
model declares.

These frozen dataclasses live in the config layer (the lowest one) so that a scene section
*is* the solver's options object ([integration], [shooting]) or builds it
(:meth:`~vibrogear.config.sections.common.ContinuationSettings.options`), while the solvers
import them from here (``vibrogear.solvers.integrator.integrate.IntegrationOptions`` is this class).
Their ranges are the :func:`~vibrogear.config.base.spec` metadata of the fields: ``build``
checks them while reading a scene (naming the field path), and ``__post_init__`` checks the
same metadata and the cross-field invariants for objects made in code, so there is one
definition and one set of rules.  A violation is a :class:`ConfigError` (a ValueError)
naming the field.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .base import ConfigError, check, spec

__all__ = ["Parameter", "OMEGA", "RPM", "IntegrationOptions", "ShootingOptions",
           "SweepOptions", "ContinuationSteps", "ContinuationOptions", "NnmSteps", "NnmMethod",
           "check_fields", "check_range"]


@dataclass(frozen=True)
class Parameter:
    """A model's continuation parameter: ``name`` (in results and files), ``unit``, axis
    ``label`` and ``key``, the stem of the scene keys that give it: ``<key>_min`` and
    ``<key>_max`` for a range ([sweep], [continuation]), ``<key>`` for one value
    ([time_response])."""
    name: str
    unit: str
    label: str
    key: str


#: the impact pair's parameter: the nondimensional excitation frequency (paper eq. (12))
OMEGA = Parameter(name="Omega", unit="", label="Omega", key="omega")
#: a gearbox's parameter: the driving-shaft speed
RPM = Parameter(name="rpm", unit="rpm", label="driving speed [rpm]", key="rpm")


def check_fields(obj) -> None:
    """The ranges of ``obj``'s numeric fields (their spec metadata); path = field name."""
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            check(v, f.metadata, f.name)


def check_step_order(obj) -> None:
    """``ds_min <= ds <= ds_max`` of a continuation's steps, else a ConfigError naming ds."""
    if not obj.ds_min <= obj.ds <= obj.ds_max:
        raise ConfigError("ds", f"must satisfy ds_min <= ds <= ds_max ({obj.ds_min:g} <= "
                          f"ds <= {obj.ds_max:g}), got {obj.ds:g}")


def fields_of(obj, cls) -> dict:
    """The fields of dataclass ``cls`` that ``obj`` carries, as keyword arguments."""
    return {f.name: getattr(obj, f.name) for f in dataclasses.fields(cls)}


def check_range(obj, path: str, lo: str, hi: str) -> None:
    """``obj.lo < obj.hi``, else a ConfigError naming ``path.hi``."""
    a, b = getattr(obj, lo), getattr(obj, hi)
    if not a < b:
        raise ConfigError(f"{path}.{hi}" if path else hi,
                          f"must be greater than {lo} = {a:g}, got {b:g}")


@dataclass(frozen=True)
class IntegrationOptions:
    """[integration]: the compiled Dormand-Prince 5(4) integrator (solvers/integrator/integrate.py)."""
    rtol: float = spec(1e-9, gt=0.0, lt=1.0)
    atol: float = spec(1e-11, gt=0.0)
    max_steps: int = spec(5_000_000, gt=0)
    max_events_per_step: int = spec(20, gt=0, doc="consecutive contact events without a "
                                    "regular step before the run stops (chattering)")
    max_step_periods: float = spec(0.125, gt=0.0, doc="largest step as a fraction of the "
                                   "excitation period")
    event_log: int = spec(10_000, ge=0, doc="event times kept (all are counted)")
    max_error: float = spec(0.01, gt=0.0, doc="a run whose accumulated error estimate per "
                            "excitation period exceeds this fraction of the solution's size "
                            "is INACCURATE")
    max_deformation: float = spec(10.0, gt=1.0, doc="a run in which a contact deforms more "
                                  "than this many times its physical scale (gap + static "
                                  "deflection + kinematic error) is DIVERGED")
    max_events_per_period: float = spec(16.0, gt=0.0, doc="a run with more contact events "
                                        "per contact and excitation period is INACCURATE")

    def __post_init__(self):
        check_fields(self)


@dataclass(frozen=True)
class ShootingOptions:
    """[shooting]: Newton on the periodicity residual u(T) - u0 (solvers/periodic/shooting.py); the
    tolerance is also the continuation corrector's."""
    tol: float = spec(1e-9, gt=0.0, lt=1.0, doc="periodicity residual tolerance (relative)")
    max_iter: int = spec(25, ge=1, le=1000)

    def __post_init__(self):
        check_fields(self)


@dataclass(frozen=True, kw_only=True)
class SweepOptions:
    """The settings of :func:`vibrogear.solvers.sequential.sweep.sweep` (sequential continuation)."""
    transient_periods: int = spec(200, ge=0, le=1_000_000)
    extra_transient_periods: int = spec(800, ge=0, le=10_000_000,
                                        doc="more transient allowed while not yet settled "
                                        "(the budget is transient_periods + this)")
    record_periods: int = spec(32, ge=1, le=100_000)
    directions: tuple[str, ...] = spec(("up", "down"), min_len=1, max_len=2,
                                       choices=("up", "down"))
    max_period: int = spec(8, ge=1, le=64, doc="largest n classified as period-n")
    period_tol: float = spec(1e-5, gt=0.0, lt=1.0, doc="relative Poincare-sample tolerance")
    accuracy: float = spec(1e-3, gt=0.0, lt=1.0, doc="error asked of the recorded motion: max "
                           "|delta - delta_exact| over the record window / the range of delta "
                           "(delta: the monitored mesh deformation); sets the integrator's "
                           "rtol/atol of a gearbox sweep or time response unless [integration] "
                           "rtol is given")
    segments: int = spec(1, ge=1, le=1000, doc="independent pieces per direction, each "
                         "starting from the static equilibrium (parallel work units)")
    workers: int | None = spec(None, ge=1, le=4096, doc="local worker processes "
                               "(default: all cores; 1: serial; under mpirun: the ranks)")
    lyapunov: bool = spec(True, doc="largest Lyapunov exponent (with its 95 % interval) of "
                          "points without a period: it tells chaotic from quasi-periodic")
    shoot: bool = spec(True, doc="a point without a period is shot from its settled state "
                       "(Newton on the period map, periods 1 and 2) before it is called "
                       "quasi-periodic or chaotic: a stable orbit makes it periodic (a slow "
                       "transient, not a torus); an unstable one is reported beside the class")
    second_tolerance: bool = spec(False, doc="record every point's window again at rtol/10 "
                                  "from the same settled state; the change of each statistic "
                                  "is reported as its tolerance error (<name>_tol_err); not on "
                                  "chaotic points, where two records differ by sampling alone "
                                  "(the batch-means <name>_err covers it; tol_err_measured = 0)")
    resolution_rel: float = spec(1e-3, gt=0.0, lt=1.0, doc="engineering resolution of the "
                                 "motion class, relative part: a point is periodic where the "
                                 "stroboscopic samples of every mesh deformation and mesh force "
                                 "repeat within this fraction of the quantity's range over the "
                                 "record (or the absolute floors below, whichever is larger)")
    resolution_length: float = spec(1e-9, ge=0.0, le=1e-3, doc="absolute floor of a "
                                    "deformation's resolution [m] (models with physical units)")
    resolution_force: float = spec(1.0, ge=0.0, le=1e6, doc="absolute floor of a force's "
                                   "resolution [N] (models with physical units)")
    settle_window: int | None = spec(None, ge=4, le=100000, doc="periods per window of the "
                                     "transient's statistics test (three windows at least "
                                     "before a transient can stop; default max(record_periods, "
                                     "32))")

    @classmethod
    def of(cls, section) -> "SweepOptions":
        """The solver's settings of a section that extends them ([sweep], [map]), without the
        section's own fields (grid, loads)."""
        return cls(**{f.name: getattr(section, f.name) for f in dataclasses.fields(cls)})

    def __post_init__(self):
        check_fields(self)
        d = tuple(self.directions)
        if not d or len(set(d)) != len(d) or any(x not in ("up", "down") for x in d):
            raise ConfigError("directions", f"must be 'up', 'down' or both, got {list(d)}")
        if self.max_period > self.record_periods:
            raise ConfigError("max_period", f"must be <= record_periods = "
                              f"{self.record_periods}, got {self.max_period}")


@dataclass(frozen=True, kw_only=True)
class ContinuationSteps:
    """Steps and limits of pseudo-arclength continuation.  ``ds``, ``ds_min``, ``ds_max``
    are in the parameter's unit: a step along the parameter axis moves it by ``ds``."""
    ds: float = spec(0.02, gt=0.0)
    ds_min: float = spec(1e-6, gt=0.0)
    ds_max: float = spec(0.1, gt=0.0)
    max_points: int = spec(2000, ge=2, le=1_000_000)
    max_corrector_iter: int = spec(8, ge=1, le=100)
    period_doubling_branch: bool = spec(True, doc="switch onto the period-2 branch at the "
                                        "first PD")

    def __post_init__(self):
        check_fields(self)
        check_step_order(self)

    def steps(self) -> dict:
        """These fields as keyword arguments (for :class:`ContinuationOptions`)."""
        return fields_of(self, ContinuationSteps)


@dataclass(frozen=True, kw_only=True)
class ContinuationOptions(ContinuationSteps):
    """The options of :func:`vibrogear.solvers.periodic.continuation.continuation`: the steps and
    the parameter range [param_min, param_max] the branch is traced in."""
    param_min: float
    param_max: float

    def __post_init__(self):
        super().__post_init__()
        check_range(self, "", "param_min", "param_max")


@dataclass(frozen=True, kw_only=True)
class NnmSteps:
    """Steps, limits and labels of the NNM continuation in energy (shared by ``[nnm]``,
    :class:`~vibrogear.config.sections.nnm.NnmConfig`, and the solver's
    :class:`NnmMethod`, so that their rules are written once).  The steps are relative:
    times the orbit's distance from the static state in state space."""
    ds: float = spec(0.05, gt=0.0, le=10.0, doc="first relative step")
    ds_min: float = spec(1e-4, gt=0.0, le=10.0, doc="smallest relative step")
    ds_max: float = spec(0.3, gt=0.0, le=10.0, doc="largest relative step")
    max_points: int = spec(200, ge=2, le=1_000_000, doc="points per backbone")
    phase: str = spec("monitor", choices=("monitor", "mode"), doc="phase condition: the "
                      "velocity of the monitored contact's deformation (or of the start "
                      "mode's coordinate) zero at t = 0")
    stability_tol: float = spec(1e-6, gt=0.0, lt=1.0, doc="a nontrivial multiplier with "
                                "|mu| > 1 + stability_tol makes the orbit unstable")
    rational_max: int = spec(5, ge=1, le=20, doc="largest p, q of an internal resonance p:q")
    rational_tol: float = spec(0.01, gt=0.0, lt=0.5, doc="relative distance of a frequency "
                               "ratio from p/q that labels an internal resonance")

    def __post_init__(self):
        check_fields(self)
        if self.phase not in ("monitor", "mode"):
            raise ConfigError("phase", f"expected 'monitor' or 'mode', got {self.phase!r}")
        check_step_order(self)

    def steps(self) -> dict:
        """These fields as keyword arguments (for :class:`NnmMethod`)."""
        return fields_of(self, NnmSteps)


@dataclass(frozen=True, kw_only=True)
class NnmMethod(NnmSteps):
    """The settings of :func:`vibrogear.solvers.periodic.nnm.nnm_branch`: the steps
    (:class:`NnmSteps`), the energy range in model units, the integrator's options, the
    periodicity tolerance and the corrector's limits.  ``[nnm]`` builds it
    (:meth:`~vibrogear.config.sections.nnm.NnmConfig.method`)."""
    energy_min: float
    energy_max: float
    integration: IntegrationOptions = IntegrationOptions(rtol=1e-10, atol=1e-12)
    tol: float = spec(1e-9, gt=0.0, lt=1.0, doc="periodicity residual relative to "
                      "|u0 - u_s|")
    max_corrector_iter: int = spec(8, ge=1, le=100)
    max_angle: float = spec(0.35, gt=0.0)
    quasi_newton: bool = True
    #: the branch also ends (LEFT_RANGE) once the monitored deformation's largest excursion
    #: from its static value ``delta_static`` exceeds this (an amplitude range; None: no)
    excursion_max: float | None = None
    delta_static: float = 0.0

    def __post_init__(self):
        super().__post_init__()
        if not 0.0 < self.energy_min:
            raise ConfigError("energy_min", f"must be > 0, got {self.energy_min:g}")
        if not self.energy_min < self.energy_max:
            raise ConfigError("energy_max", f"must be greater than energy_min = "
                              f"{self.energy_min:g}, got {self.energy_max:g}")
