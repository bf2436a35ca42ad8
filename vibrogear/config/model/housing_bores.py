"""The bores and clamped region of ``[housing]``: ``[[housing.bores]]`` (a parametric bearing
boss pair at (x, z), or an imported housing's shaft line through ``center`` along ``axis``)
and ``fixed_region`` (the box of an imported housing's clamped faces); the schema of
:mod:`.housing` uses them."""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..base import ConfigError, spec

__all__ = ["BoreConfig", "FixedRegionConfig"]


@dataclass(frozen=True, kw_only=True)
class BoreConfig:
    """One shaft.  Parametric: a bearing-boss pair with coaxial bores through the front and back
    walls at (``x``, ``z``).  Imported: the shaft line through ``center`` along ``axis``; every
    boundary face on the cylinder of ``bore_radius`` about it is a bore surface (see
    :mod:`vibrogear.geometry.housing_import`).  With an axis parallel to y, ``x`` and ``z`` are
    filled in from ``center`` (the gearbox takes the shaft axis from them)."""
    x: float | None = spec(None, gt=0.0, doc="bore axis position along the length, m (parametric)")
    z: float | None = spec(None, gt=0.0, doc="bore axis height above the box bottom, m (parametric)")
    center: tuple[float, float, float] | None = spec(None, doc="a point on the shaft axis, m (imported)")
    axis: tuple[float, float, float] | None = spec(None, doc="shaft axis direction (imported)")
    length: float | None = spec(None, gt=0.0, doc="only faces within center +- length/2 (imported)")
    bore_radius: float = spec(gt=0.0, doc="bore (bearing outer race) radius, m")
    boss_radius: float | None = spec(None, gt=0.0, doc="outer radius of the boss, m (parametric)")
    boss_length: float = spec(0.02, ge=0.0, doc="protrusion of the boss outside the wall, m")
    rolling_elements: int = spec(ge=3, le=200, doc="coupling points per bore (one per rolling element)")
    wall_rolling_elements: tuple[int, ...] = spec((), ge=3, le=200, max_len=10,
                                                  doc="coupling points of this axis's bore in each wall, "
                                                      "front, inner walls, back (parametric; default: "
                                                      "rolling_elements in every wall)")
    name: str = spec("", doc="label, e.g. 'input shaft'")

    def __post_init__(self) -> None:
        if self.center is not None and self.axis is not None and self.x is None and self.z is None:
            ax = self.axis
            n = math.sqrt(sum(a * a for a in ax))
            if n > 0 and math.hypot(ax[0], ax[2]) <= 1e-12 * n:      # parallel to y
                object.__setattr__(self, "x", float(self.center[0]))
                object.__setattr__(self, "z", float(self.center[2]))

    @property
    def unit_axis(self) -> tuple[float, float, float]:
        """The axis normalised (imported bores)."""
        n = math.sqrt(sum(a * a for a in self.axis))
        return tuple(a / n for a in self.axis)

    def validate(self, path: str) -> None:
        if self.center is not None or self.axis is not None:
            self._validate_line(path)
            return
        if self.boss_radius is not None and not self.bore_radius < self.boss_radius:
            raise ConfigError(f"{path}.boss_radius", f"must be greater than bore_radius = "
                              f"{self.bore_radius:g}, got {self.boss_radius:g}")

    def _validate_line(self, path: str) -> None:
        if self.center is None or self.axis is None:
            missing = "center" if self.center is None else "axis"
            raise ConfigError(f"{path}.{missing}", "missing required key: a bore given by its line "
                              "needs center = [x, y, z] and axis = [ax, ay, az]")
        for k, v in enumerate(self.center):
            if not math.isfinite(v):
                raise ConfigError(f"{path}.center[{k}]", f"must be a finite number, got {v!r}")
        n = math.sqrt(sum(a * a for a in self.axis))
        if not (math.isfinite(n) and n > 1e-12):
            raise ConfigError(f"{path}.axis", f"must be a non-zero finite vector (length > 1e-12), got "
                              f"{list(self.axis)} of length {n:g}")
        for k in ("boss_radius", "wall_rolling_elements"):
            if getattr(self, k):
                raise ConfigError(f"{path}.{k}", "only for the parametric housing (bores given by x "
                                  "and z); an imported housing's bores are in its file")
        ax = self.unit_axis
        if self.x is not None and self.z is not None and math.hypot(ax[0], ax[2]) <= 1e-12 and (
                abs(self.x - self.center[0]) > 1e-12 * max(1.0, abs(self.x))
                or abs(self.z - self.center[2]) > 1e-12 * max(1.0, abs(self.z))):
            raise ConfigError(f"{path}.x", f"give either x, z or center: x, z = {self.x:g}, {self.z:g} "
                              f"disagree with center = {list(self.center)}")
        if (self.x is not None or self.z is not None) and math.hypot(ax[0], ax[2]) > 1e-12:
            raise ConfigError(f"{path}.x", "give either x, z (parametric) or center and axis (imported)")


@dataclass(frozen=True, kw_only=True)
class FixedRegionConfig:
    """``fixed_region = { min = [x, y, z], max = [x, y, z] }``: every boundary face of an imported
    housing lying wholly inside this box (metres, after unit conversion) is clamped."""
    min: tuple[float, float, float] = spec(doc="box corner with the smallest coordinates, m")
    max: tuple[float, float, float] = spec(doc="box corner with the largest coordinates, m")

    def validate(self, path: str) -> None:
        for k, (a, b) in enumerate(zip(self.min, self.max)):
            if not (math.isfinite(a) and math.isfinite(b)):
                raise ConfigError(f"{path}.min", f"coordinates must be finite, got {list(self.min)}, "
                                  f"{list(self.max)}")
            if a > b:
                raise ConfigError(f"{path}.max[{k}]", f"must be >= min[{k}] = {a:g}, got {b:g}")
