"""[states]: every operating state at every speed (``vibrogear states SCENE``).

At each of ``n_points`` parameter values from ``<key>_min`` to ``<key>_max`` (the sweep's keys:
``rpm_*`` for a gearbox, ``omega_*`` for the impact pair; one point: ``<key>_min`` alone),
``starts`` random initial states are each integrated to settled motion by the sweep's own
point (transient until settled, record window, class with evidence: the inherited sweep
settings ``transient_periods``, ``record_periods``, ``max_period``, ``period_tol``, ...) and
the settled motions are grouped into attractors with their basin fractions.

Starts (``docs/states.md``): a gearbox's (any reduced model's) are the static equilibrium
disturbed: the static deflection scaled by a factor from [1 - a, 1 + a] (a =
``deformation_scale``), each two-sided contact (gear mesh) then set anywhere in its backlash
or up to a times its static penetration on either flank, and the velocities of the
linearised forced response at a random phase times a factor from [-b, b] (b =
``velocity_scale``).  The impact pair
may instead take starts uniform in the box ``q_range`` x ``v_range`` (q and dq/dtau).  The
random numbers of start k at speed i come from ``seed``, i and k alone: any split over
workers or a resumed run gives the same starts.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..base import ConfigError, spec
from ..options import OMEGA, RPM, SweepOptions, check_range

__all__ = ["StatesSettings", "StatesConfig", "RpmStatesConfig"]


@dataclass(frozen=True, kw_only=True)
class StatesSettings(SweepOptions):
    """[states]: the grid, the starts and their distribution, clustering and branches (see
    :func:`with_parameter`)."""
    n_points: int = spec(16, ge=1, le=100_000, doc="parameter values of the grid (1: <key>_min "
                         "alone)")
    starts: int = spec(32, ge=1, le=1_000_000, doc="random starts per parameter value (N)")
    seed: int = spec(0, ge=0, le=2**63 - 1, doc="seed of the random starts (reproducible)")
    batch: int = spec(8, ge=1, le=1_000_000, doc="starts per work unit (a unit is one "
                      "parameter value and a batch of its starts)")
    basin_tol: float | None = spec(None, gt=0.0, le=1.0, doc="stop a parameter value early "
                                   "once every basin's 95 % interval is narrower than this "
                                   "(starts run in rounds of `batch`); default: all starts")
    deformation_scale: float = spec(2.0, gt=0.0, le=1e6, doc="the static deflection is "
                                    "scaled by a factor from [1 - a, 1 + a], each mesh's "
                                    "penetration up to a times its static value")
    velocity_scale: float = spec(1.0, ge=0.0, le=1e6, doc="the linearised forced "
                                 "response's velocities at a random phase times a factor "
                                 "from [-b, b]")
    q_range: tuple[float, float] | None = spec(None, doc="impact pair only: starts uniform "
                                               "in q over [lo, hi] (with v_range)")
    v_range: tuple[float, float] | None = spec(None, doc="impact pair only: starts uniform "
                                               "in dq/dtau over [lo, hi] (with q_range)")
    cluster_tol: float = spec(1e-3, gt=0.0, lt=1.0, doc="two periodic motions are one "
                              "attractor when their stroboscopic points agree within this "
                              "fraction of the states' size (as the period test measures)")
    stat_tol: float = spec(0.05, gt=0.0, lt=1.0, doc="two non-periodic motions are one "
                           "attractor only when their impacts and rattle per mesh agree "
                           "within their errors (3-sigma level, Welch t) plus this fraction "
                           "of the largest value at that speed (docs/states.md)")
    branches: bool = spec(True, doc="continue a branch both ways from each distinct periodic "
                          "attractor that no branch found so far passes through")
    branch_max_points: int = spec(60, ge=2, le=100_000, doc="points per half-branch")
    range_keys: ClassVar[tuple[str, ...]] = ()

    def validate(self, path: str) -> None:
        if len(self.range_keys) == 2:
            lo, hi = self.range_keys
            if self.n_points > 1:
                check_range(self, path, lo, hi)
            elif getattr(self, hi) < getattr(self, lo):
                raise ConfigError(f"{path}.{hi}", f"must be >= {lo} = {getattr(self, lo):g}, "
                                  f"got {getattr(self, hi):g}")
        for key in ("q_range", "v_range"):
            r = getattr(self, key)
            if r is not None and not r[0] < r[1]:
                raise ConfigError(f"{path}.{key}", f"an interval [lo, hi] with lo < hi, got "
                                  f"[{r[0]:g}, {r[1]:g}]")
        if (self.q_range is None) != (self.v_range is None):
            missing = "v_range" if self.v_range is None else "q_range"
            raise ConfigError(f"{path}.{missing}", "missing: the box of starts needs both "
                              "q_range and v_range")

    def check_model(self, impact_pair, gearbox, path: str) -> None:
        """A box of starts is the impact pair's (a gearbox's starts are scaled from its
        static state)."""
        if impact_pair is None:
            for key in ("q_range", "v_range"):
                if getattr(self, key) is not None:
                    raise ConfigError(f"{path}.{key}", "a box of starts is for the impact "
                                      "pair only; a gearbox's starts are scaled from its static "
                                      "state (deformation_scale, velocity_scale)")

    @property
    def box(self) -> tuple | None:
        return None if self.q_range is None else (tuple(self.q_range), tuple(self.v_range))


def _with_parameter(parameter, name: str):
    from .common import with_parameter
    return with_parameter(StatesSettings, parameter, name)


StatesConfig = _with_parameter(OMEGA, "StatesConfig")
RpmStatesConfig = _with_parameter(RPM, "RpmStatesConfig")
StatesConfig.__module__ = RpmStatesConfig.__module__ = __name__
