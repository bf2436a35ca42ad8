"""Config sections shared by all scenes: the impact pair and the analysis options.

The sections that take the continuation parameter ([sweep], [continuation],
[time_response]) read it under the keys of the parameter the model declares
(:class:`~vibrogear.config.options.Parameter`: ``omega_min``/``omega_max``/``omega`` for the
impact pair, ``rpm_min``/``rpm_max``/``rpm`` for gearboxes): one settings class each, and
one class per parameter made by :func:`with_parameter`, which adds the keys as fields and
reads them back as ``param_min``/``param_max`` (or ``param``).  Errors name the key the
user wrote, because it is the field's name.  [integration] and [shooting] are the solvers'
own options objects; [continuation] builds the solver's
:class:`~vibrogear.config.options.ContinuationOptions` (:meth:`ContinuationSettings.options`).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar

from ..base import ConfigError, check_name, spec
from ..verbs import VERBS
from ..options import (OMEGA, RPM, ContinuationOptions, ContinuationSteps, IntegrationOptions,
    Parameter, ShootingOptions, SweepOptions, check_range)

__all__ = ["SceneInfo", "FiguresConfig", "ReductionAccuracyConfig", "ImpactPairConfig", "IntegrationOptions", "ShootingOptions",
           "SweepSettings", "ContinuationSettings", "TimeResponseSettings", "with_parameter",
           "SweepConfig", "ContinuationConfig", "TimeResponseConfig", "RpmSweepConfig",
           "RpmContinuationConfig", "RpmTimeResponseConfig", "ReportConfig",
           "CriticalDampingConfig", "ContinuationOptions", "ANALYSES"]

#: analyses a scene may list, with what each is for (the verb registry)
ANALYSES = {name: v.help for name, v in VERBS.items()}


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
    PARAMETER: ClassVar[Parameter] = OMEGA


class _ParameterRange:
    """The parameter range of a section whose range keys :func:`with_parameter` names
    (``range_keys``: rpm_min / rpm_max or omega_min / omega_max), checked and read alike."""
    range_keys: ClassVar[tuple[str, ...]] = ()

    def validate(self, path: str) -> None:
        if len(self.range_keys) == 2:
            check_range(self, path, *self.range_keys)

    def param_range(self) -> tuple[float, float]:
        """(min, max) of the parameter range, in the parameter's unit, whatever its keys."""
        return float(self.param_min), float(self.param_max)


@dataclass(frozen=True, kw_only=True)
class SweepSettings(_ParameterRange, SweepOptions):
    """[sweep]: the solver's settings (:class:`SweepOptions`), the number of grid points and
    the parameter range (see :func:`with_parameter`)."""
    n_points: int = spec(200, ge=2, le=1_000_000)


@dataclass(frozen=True, kw_only=True)
class ContinuationSettings(_ParameterRange, ContinuationSteps):
    """[continuation]: the solver's steps (:class:`ContinuationSteps`, ds in the parameter's
    unit), where to start, and the parameter range (see :func:`with_parameter`)."""
    start: str = spec("max", choices=("min", "max"), doc="end of the range to start from")
    transient_periods: int = spec(300, ge=0, doc="periods integrated to find the starting orbit")
    from_sweep: bool = spec(False, doc="also start a branch (both ways) from each distinct "
                            "period-n window of the sweep (this run's, or sweep.npz in the "
                            "output folder)")
    from_sweep_max_points: int = spec(40, ge=2, le=1_000_000, doc="points of each half-branch "
                                      "started from a sweep window")
    rtol: float | None = spec(None, gt=0.0, lt=1.0, doc="the integrator's rtol for shooting and continuation "
                              "(atol = 1e-6 rtol); default: [integration] as written")

    def options(self) -> ContinuationOptions:
        """The solver's options: this section's steps over [param_min, param_max]."""
        return ContinuationOptions(param_min=self.param_min, param_max=self.param_max,
                                   **self.steps())


@dataclass(frozen=True, kw_only=True)
class TimeResponseSettings:
    """[time_response] less the parameter value (see :func:`with_parameter`)."""
    periods: float = spec(100.0, gt=0.0)
    samples_per_period: int = spec(64, ge=4, le=100_000)


def with_parameter(settings: type, parameter: Parameter, name: str, *, single: bool = False):
    """``settings`` plus the model's parameter under its scene keys: ``<key>_min`` and
    ``<key>_max`` (read back as ``param_min``, ``param_max``), or ``<key>`` (``param``) when
    ``single``.  The class is named ``name`` (bound to that name in this module)."""
    key = parameter.key
    if single:
        keys = (key,)
        fields = [(key, float, spec(gt=0.0, doc=f"{parameter.label} of the run"))]
        ns = {"param": property(lambda self: getattr(self, key))}
    else:
        keys = (f"{key}_min", f"{key}_max")
        fields = [(k, float, spec(gt=0.0, doc=f"{parameter.label}, {end} of the range"))
                  for k, end in zip(keys, ("lower", "upper"))]
        ns = {"param_min": property(lambda self: getattr(self, keys[0])),
              "param_max": property(lambda self: getattr(self, keys[1])),
              "range_keys": keys}
    ns["parameter"] = parameter
    cls = dataclasses.make_dataclass(name, fields, bases=(settings,), namespace=ns,
                                     frozen=True, kw_only=True)
    cls.__module__ = __name__
    cls.__doc__ = f"{settings.__doc__.split(' (see')[0]}, over {parameter.name} " \
                  f"(keys {', '.join(keys)})."
    return cls


SweepConfig = with_parameter(SweepSettings, OMEGA, "SweepConfig")
ContinuationConfig = with_parameter(ContinuationSettings, OMEGA, "ContinuationConfig")
TimeResponseConfig = with_parameter(TimeResponseSettings, OMEGA, "TimeResponseConfig",
                                    single=True)
RpmSweepConfig = with_parameter(SweepSettings, RPM, "RpmSweepConfig")
RpmContinuationConfig = with_parameter(ContinuationSettings, RPM, "RpmContinuationConfig")
RpmTimeResponseConfig = with_parameter(TimeResponseSettings, RPM, "RpmTimeResponseConfig",
                                       single=True)


@dataclass(frozen=True)
class ReportConfig:
    omega: float = spec(gt=0.0, doc="parameter at which the work-precision study runs")
    rtols: tuple[float, ...] = spec((1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10), min_len=2, gt=0.0, lt=1.0)
    periods: float = spec(20.0, gt=0.0)
    shooting_tols: tuple[float, ...] = spec((1e-4, 1e-6, 1e-8, 1e-10, 1e-12), min_len=2, gt=0.0,
                                            lt=1.0, doc="shooting tolerances (integrator rtol matched)")
    repeats: int = spec(5, ge=1, le=100, doc="timing repeats per point (best time is reported)")


@dataclass(frozen=True)
class FiguresConfig:
    """[figures]: what the figures show beyond their defaults (no effect on any result)."""
    motion_rows_per_contact: bool = spec(False, doc="the bifurcation diagrams' motion-class "
                                         "band also gets one row per contact group (mesh, "
                                         "bearing) and direction where the group's own class "
                                         "differs from the whole motion's (default: one row "
                                         "per sweep direction)")


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
        check_range(self, path, "omega_min", "omega_max")
        check_range(self, path, "zeta_lo", "zeta_hi")
        try:
            self.options()
        except ConfigError as exc:      # the continuation's own rules, named here
            raise ConfigError(f"{path}.{exc.path}", str(exc)[len(exc.path) + 2:]) from None

    def options(self) -> ContinuationOptions:
        """The options of each trial zeta's continuation (period-1 branch only)."""
        return ContinuationOptions(param_min=self.omega_min, param_max=self.omega_max,
                                   ds=self.ds, ds_max=self.ds_max, max_points=self.max_points,
                                   period_doubling_branch=False)


@dataclass(frozen=True, kw_only=True)
class ReductionAccuracyConfig:
    """Reduction-level study: master-mode counts -> frequency error, response error against
    the largest level, and run time; plus the linearised reduced model against the full
    (non-reduced) linearised model (all housing DOF) below ``f_max_hz``."""
    shaft_counts: tuple[int, ...] = spec((10, 20, 30), min_len=1, max_len=20, ge=7, le=10_000,
                                         doc="master modes per shaft, one entry per level")
    housing_counts: tuple[int, ...] = spec((20, 50, 100), min_len=1, max_len=20, ge=1,
                                           le=10_000, doc="housing master modes per level")
    rpm: float = spec(gt=0.0, le=1e6, doc="speed of the response comparison")
    transient_periods: int = spec(50, ge=0, le=100_000, doc="mesh periods dropped")
    record_periods: int = spec(20, ge=1, le=100_000, doc="mesh periods compared")
    f_max_hz: float = spec(5000.0, gt=0.0, doc="modes compared up to this frequency")
    full_model: bool = spec(True, doc="also compare with the full linearised model "
                                      "(assembles the housing's K and M)")
    frequency_level: bool = spec(True, doc="also the level of gearbox.master_modes = "
                                 "\"frequency\" (with and without the static correction)")
    rtol: float | None = spec(None, gt=0.0, lt=1.0, doc="the integrator's rtol for the study "
                              "(atol = 1e-6 rtol); default: [integration] as written")

    def validate(self, path: str) -> None:
        if len(self.shaft_counts) != len(self.housing_counts):
            raise ConfigError(f"{path}.housing_counts", f"needs one entry per level: "
                              f"{len(self.shaft_counts)} (as shaft_counts), got "
                              f"{len(self.housing_counts)}")
