"""[nvh]: spectra of the steady response and the housing's equivalent radiated power
(``vibrogear nvh SCENE``).

The steady points are the settled end states of a [sweep] that ran before in the same run
(``use_sweep``, direction ``sweep_direction``), else ``n_speeds`` speeds from ``rpm_min`` to
``rpm_max`` settled here by the sweep solver (upward, ``transient_periods``).  From each
settled state ``record_periods`` whole excitation (mesh) periods are integrated with
``samples_per_period`` samples each (a power of two, at least 4 x ``max_order``: the
highest mesh order shown, below the Nyquist order samples_per_period / 2).  ERP uses
``rho_air`` and ``c_air``; the RMS surface normal velocity is written at the speeds
``velocity_rpms`` (the nearest steady point each; none given: the point of largest ERP).

``branch_spectra = true`` adds the spectra of every point of the branches of a
[continuation] that ran before nvh in the same run (list it first in ``scene.analyses``):
one orbit period (n_periods excitation periods) from each point's u0, the exact line
spectrum of the periodic orbit, unstable ones included (``spectra_branch.npz``).  The steady
points above are still needed (a sweep before, or the own grid).
"""
from __future__ import annotations

from dataclasses import dataclass

from ..base import ConfigError, spec
from ..options import check_range

__all__ = ["NvhConfig"]


@dataclass(frozen=True, kw_only=True)
class NvhConfig:
    """[nvh]: where the steady points come from, the record, orders, ERP constants."""
    rpm_min: float | None = spec(None, gt=0.0, le=1e6, doc="own speed grid, lower end [rpm] "
                                 "(used when no sweep ran before)")
    rpm_max: float | None = spec(None, gt=0.0, le=1e6, doc="own speed grid, upper end [rpm]")
    n_speeds: int = spec(20, ge=1, le=100_000, doc="speeds of the own grid")
    use_sweep: bool = spec(True, doc="take the steady points of a [sweep] that ran before "
                           "in the same run")
    sweep_direction: str = spec("up", choices=("up", "down"), doc="which sweep direction's "
                                "end states to take")
    transient_periods: int = spec(150, ge=0, le=1_000_000, doc="mesh periods to settle each "
                                  "point of the own grid")
    record_periods: int = spec(8, ge=1, le=4096, doc="whole mesh periods recorded per point "
                               "(frequency resolution = mesh frequency / record_periods)")
    samples_per_period: int = spec(64, ge=4, le=65536, doc="samples per mesh period, a power "
                                   "of two")
    max_order: float = spec(4.0, gt=0.0, le=4096.0, doc="highest mesh order shown (spectra "
                            "are stored up to the Nyquist order samples_per_period / 2)")
    rho_air: float = spec(1.2, gt=0.0, le=1e4, doc="density of the air [kg/m^3]")
    c_air: float = spec(343.0, gt=0.0, le=1e5, doc="speed of sound in the air [m/s]")
    velocity_rpms: tuple[float, ...] = spec((), max_len=50, gt=0.0, le=1e6,
                                            doc="speeds [rpm] at which the RMS surface "
                                            "velocity field is written (nearest point)")
    branch_spectra: bool = spec(False, doc="also the spectra of the branch points of a "
                                "[continuation] that ran before in the same run (one orbit "
                                "period each)")

    def validate(self, path: str) -> None:
        n = self.samples_per_period
        if n & (n - 1):
            raise ConfigError(f"{path}.samples_per_period",
                              f"expected a power of two (4 .. 65536), got {n}")
        if n < 4 * self.max_order:
            raise ConfigError(f"{path}.samples_per_period", f"expected >= 4 x max_order = "
                              f"{4 * self.max_order:g} (orders up to max_order well below the "
                              f"Nyquist order samples_per_period / 2), got {n}")
        has = (self.rpm_min is not None, self.rpm_max is not None)
        if any(has) and not all(has):
            missing = "rpm_max" if has[0] else "rpm_min"
            raise ConfigError(f"{path}.{missing}", "give both rpm_min and rpm_max (the own "
                              "speed grid), or neither")
        if all(has):
            check_range(self, path, "rpm_min", "rpm_max")

    def own_grid(self) -> bool:
        return self.rpm_min is not None
