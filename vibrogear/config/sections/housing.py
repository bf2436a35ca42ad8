"""The housing studies' scene sections: ``[housing_sweep]`` (first frequencies against one
housing parameter) and ``[housing_convergence]`` (frequency error against DOF and wall time)."""
from __future__ import annotations

from dataclasses import dataclass

from ..base import ConfigError, spec
from ..model.housing import HousingConfig

__all__ = ["HousingSweepConfig", "HousingConvergenceConfig"]


@dataclass(frozen=True, kw_only=True)
class HousingSweepConfig:
    """``[housing_sweep]``: first frequencies against one housing parameter."""
    parameter: str = spec(doc="dotted key under housing, e.g. 'housing.wall_thickness'")
    values: tuple[float, ...] | None = spec(None, min_len=1, doc="explicit parameter values")
    min: float | None = spec(None, doc="range start (with max, n)")
    max: float | None = spec(None)
    n: int = spec(5, ge=2, le=1000)
    n_freqs: int = spec(6, ge=1, le=1000)
    processes: int = spec(2, ge=1, le=64)
    reuse: bool = spec(True, doc="solve the points in order, each from the previous one's mesh nodes, factor "
                       "ordering and modes (all-hex parametric housings, whose mesh sizes are then the "
                       "base housing's for every point; a chain per process), to the fresh solve's "
                       "criterion at 1e-2; false: every point from nothing")

    def validate(self, path: str) -> None:
        if not self.parameter.startswith("housing.") or len(self.parameter) <= len("housing."):
            raise ConfigError(f"{path}.parameter", f"must be a dotted key under housing, e.g. "
                              f"'housing.wall_thickness', got {self.parameter!r}")
        if self.values is None and (self.min is None or self.max is None):
            raise ConfigError(f"{path}.values", "give either values or min, max (and n)")
        if self.values is None and not self.min < self.max:
            raise ConfigError(f"{path}.max", f"must be greater than min = {self.min:g}, got {self.max:g}")

    def points(self) -> tuple[float, ...]:
        if self.values is not None:
            return self.values
        return tuple(self.min + (self.max - self.min) * k / (self.n - 1) for k in range(self.n))

    def housing_points(self, housing: HousingConfig, path: str = "housing_sweep") -> tuple[HousingConfig, ...]:
        """The validated housing of each sweep point (ConfigError names the point and field)."""
        from ..base import as_data, build
        from ..overrides import set_path

        keys = self.parameter.split(".")[1:]
        base = as_data(housing)
        node = base
        try:
            for k in keys:
                node = node[int(k)] if isinstance(node, list) else node[k]
        except (KeyError, IndexError, ValueError, TypeError):
            raise ConfigError(f"{path}.parameter", f"{self.parameter!r} names no housing value") from None
        if isinstance(node, (dict, list, str, bool)):
            raise ConfigError(f"{path}.parameter", f"{self.parameter!r} is not a number")
        out = []
        pinned = pinned_hex_sizes(housing) if self.reuse and keys[0] != "mesh" else {}
        for i, v in enumerate(self.points()):
            data = as_data(housing)
            data["mesh"] = {**data["mesh"], **pinned}
            set_path(data, keys, int(round(v)) if isinstance(node, int) else float(v))
            try:
                out.append(build(HousingConfig, data, "housing"))
            except ConfigError as exc:
                raise ConfigError(f"{path}.values[{i}]", f"{self.parameter} = {v:g} gives an invalid "
                                  f"housing: {exc}") from None
        return tuple(out)


def pinned_hex_sizes(housing: HousingConfig) -> dict:
    """The hex mesh sizes of ``housing`` as explicit ``[housing.mesh]`` keys (those not set: its
    wall thickness's defaults), for a reusing sweep: every point then lays the same grid, so each
    moves the previous one's nodes instead of laying another (a rule relative to the swept wall
    would change the cell counts at nearly every point).  Empty for other housings."""
    if housing.source != "parametric" or housing.mesh.element != "hex":
        return {}
    rule = housing.hex_mesh
    given = {"size": housing.mesh.size, "edge_size": housing.mesh.edge_size, "bore_size": housing.mesh.bore_size}
    resolved = {"size": rule.size, "edge_size": rule.edge, "bore_size": rule.bore}
    return {k: resolved[k] for k, v in given.items() if v is None}


@dataclass(frozen=True, kw_only=True)
class HousingConvergenceConfig:
    """``[housing_convergence]``: frequency error vs DOF vs wall time for P1 and P2 meshes."""
    size_factors: tuple[float, ...] = spec((2.0, 1.5, 1.2, 1.0), min_len=3, gt=0.0,
                                           doc="mesh sizes in units of the housing's mesh size")
    p1_size_factors: tuple[float, ...] = spec((1.5, 1.0, 0.75), min_len=1, gt=0.0)
    n_freqs: int = spec(10, ge=1, le=500)
    target_error: float = spec(0.01, gt=0.0, lt=1.0)
    order: float | None = spec(None, gt=0.0, le=8.0, doc="convergence order for the Richardson reference "
                               "(default: median of the per-mode fits, clipped to [1, 4])")
