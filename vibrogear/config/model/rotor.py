"""Rotor scene schema: one rotating shaft with discs, free gears and bearings (SI units).

Coordinates: the shaft axis is ``z`` (positions are measured along it from the left end of
the first section); ``x`` and ``y`` are the lateral directions.  Speeds are in rpm.

```toml
[rotor]
name = "driven shaft"
[rotor.material]                 # default material of every section
E = 211e9                        # Young's modulus [Pa]
nu = 0.3                         # Poisson ratio, -1 < nu < 0.5 (or give G instead)
rho = 7810.0                     # density [kg/m^3]
internal_damping = 0.0           # viscous internal (material) damping eta_v [s]

[[rotor.sections]]               # stepped / hollow shaft: consecutive sections
length = 0.5                     # [m]
outer_diameter = 0.05            # [m]
inner_diameter = 0.0             # [m], < outer_diameter
elements = 4                     # Timoshenko elements in this section

[[rotor.discs]]                  # rigid disc or fixed gear
position = 0.5                   # [m], must be a node
outer_diameter = 0.28            # geometry (mass and inertias computed) ...
inner_diameter = 0.05
width = 0.07
# mass = 33.0; Id = 0.2; Ip = 0.4 # ... or given directly (all three)

[[rotor.free_gears]]             # gear on its own bearing: extra torsional DOF
position = 0.25
mass = 5.0; Id = 0.01; Ip = 0.02 # or geometry as for discs
torsional_stiffness = 0.0        # [N m/rad] between shaft and gear (0: freely rotating)
torsional_damping = 0.0          # [N m s/rad]
speed_ratio = 1.0                # gear spin / shaft spin (scales its gyroscopic term)

[[rotor.bearings]]               # linear bearing to ground
position = 0.0
kxx = 1e6; kyy = 1e6             # [N/m]; also kxy, kyx, kzz (axial)
cxx = 0.0; cyy = 0.0             # [N s/m]; also cxy, cyx, czz

[rotor.modes]
count = 12                       # modes to report (or cutoff_hz)
speed_rpm = 0.0                  # spin speed of the modal analysis

[rotor.campbell]
rpm_min = 0.0
rpm_max = 4000.0
n_speeds = 31
orders = [1.0]                   # excitation orders drawn; 1x always recommended
```
"""
from __future__ import annotations

from dataclasses import dataclass

from ..base import ConfigError, spec

__all__ = ["MaterialConfig", "ShaftSectionConfig", "DiscConfig", "FreeGearConfig",
           "BearingConfig", "RotorModesConfig", "CampbellConfig", "RotorConfig",
           "node_positions", "POSITION_TOL"]

#: a feature position matches a node when closer than this fraction of the shaft length
POSITION_TOL = 1e-6


@dataclass(frozen=True)
class MaterialConfig:
    E: float = spec(gt=0.0, doc="Young's modulus [Pa]")
    rho: float = spec(gt=0.0, doc="density [kg/m^3]")
    nu: float | None = spec(None, gt=-1.0, lt=0.5, doc="Poisson ratio (give nu or G)")
    G: float | None = spec(None, gt=0.0, doc="shear modulus [Pa] (give nu or G)")
    internal_damping: float = spec(0.0, ge=0.0, doc="viscous internal damping eta_v [s]")

    def validate(self, path: str) -> None:
        if (self.nu is None) == (self.G is None):
            raise ConfigError(f"{path}.nu", "give exactly one of nu (-1 < nu < 0.5) and G (> 0)")
        if self.G is not None:
            nu = self.poisson
            if not -1.0 < nu < 0.5:
                raise ConfigError(f"{path}.G", f"implies Poisson ratio E/(2G) - 1 = {nu:.4g}, "
                                  "which must lie in (-1, 0.5)")

    @property
    def poisson(self) -> float:
        return self.nu if self.nu is not None else self.E / (2.0 * self.G) - 1.0

    @property
    def shear_modulus(self) -> float:
        return self.G if self.G is not None else self.E / (2.0 * (1.0 + self.nu))


@dataclass(frozen=True)
class ShaftSectionConfig:
    length: float = spec(gt=0.0, doc="[m]")
    outer_diameter: float = spec(gt=0.0, doc="[m]")
    inner_diameter: float = spec(0.0, ge=0.0, doc="[m], 0 for a solid shaft")
    elements: int | None = spec(None, ge=1, le=100_000, doc="Timoshenko elements in the "
                                "section; default: meshed for you (a gearbox shaft: nodes at "
                                "every gear, bearing, coupling and disc, elements no longer "
                                "than [gearbox] max_element_length; a [rotor] section: 1)")
    material: MaterialConfig | None = spec(None, doc="overrides [rotor.material]")

    def validate(self, path: str) -> None:
        if not self.inner_diameter < self.outer_diameter:
            raise ConfigError(f"{path}.inner_diameter", f"must be < outer_diameter = "
                              f"{self.outer_diameter:g}, got {self.inner_diameter:g}")


def _validate_inertia(obj, path: str) -> None:
    given = [obj.mass is not None, obj.Id is not None, obj.Ip is not None]
    geometry = obj.outer_diameter is not None or obj.width is not None
    if any(given) and geometry:
        raise ConfigError(f"{path}.mass", "give either mass, Id, Ip or the geometry "
                          "(outer_diameter, width), not both")
    if any(given) and not all(given):
        missing = [n for n, g in zip(("mass", "Id", "Ip"), given) if not g][0]
        raise ConfigError(f"{path}.{missing}", "missing: mass, Id and Ip go together")
    if not any(given):
        for name in ("outer_diameter", "width"):
            if getattr(obj, name) is None:
                raise ConfigError(f"{path}.{name}", "missing: give the geometry "
                                  "(outer_diameter, width) or mass, Id and Ip")
        if not obj.inner_diameter < obj.outer_diameter:
            raise ConfigError(f"{path}.inner_diameter", f"must be < outer_diameter = "
                              f"{obj.outer_diameter:g}, got {obj.inner_diameter:g}")


@dataclass(frozen=True)
class DiscConfig:
    """Rigid disc or fixed gear at a node: mass, diametral Id and polar Ip inertia."""
    position: float = spec(ge=0.0, doc="[m] along the shaft; must be a node")
    mass: float | None = spec(None, ge=0.0, doc="[kg]")
    Id: float | None = spec(None, ge=0.0, doc="diametral inertia [kg m^2]")
    Ip: float | None = spec(None, ge=0.0, doc="polar inertia [kg m^2]")
    outer_diameter: float | None = spec(None, gt=0.0, doc="[m]")
    inner_diameter: float = spec(0.0, ge=0.0, doc="bore [m]")
    width: float | None = spec(None, gt=0.0, doc="[m]")
    density: float | None = spec(None, gt=0.0, doc="[kg/m^3], default: rotor material")
    name: str = spec("", doc="label")

    def validate(self, path: str) -> None:
        _validate_inertia(self, path)


@dataclass(frozen=True)
class FreeGearConfig:
    """Gear on its own bearing: lateral inertia moves with the shaft node, the polar inertia
    sits on an extra torsional DOF joined to the shaft by a torsional spring/damper."""
    position: float = spec(ge=0.0, doc="[m]; must be a node")
    mass: float | None = spec(None, ge=0.0)
    Id: float | None = spec(None, ge=0.0)
    Ip: float | None = spec(None, gt=0.0)
    outer_diameter: float | None = spec(None, gt=0.0)
    inner_diameter: float = spec(0.0, ge=0.0)
    width: float | None = spec(None, gt=0.0)
    density: float | None = spec(None, gt=0.0)
    torsional_stiffness: float = spec(0.0, ge=0.0, doc="[N m/rad], 0: freely rotating")
    torsional_damping: float = spec(0.0, ge=0.0, doc="[N m s/rad]")
    speed_ratio: float = spec(1.0, doc="gear spin speed / shaft spin speed")
    name: str = spec("")

    def validate(self, path: str) -> None:
        _validate_inertia(self, path)


@dataclass(frozen=True)
class BearingConfig:
    """Linear bearing to ground; forces -K [ux, uy] - C [ux', uy'] and axial -kzz uz."""
    position: float = spec(ge=0.0, doc="[m]; must be a node")
    kxx: float = spec(0.0, ge=0.0, doc="[N/m]")
    kyy: float = spec(0.0, ge=0.0)
    kxy: float = spec(0.0)
    kyx: float = spec(0.0)
    kzz: float = spec(0.0, ge=0.0, doc="axial [N/m]")
    cxx: float = spec(0.0, ge=0.0, doc="[N s/m]")
    cyy: float = spec(0.0, ge=0.0)
    cxy: float = spec(0.0)
    cyx: float = spec(0.0)
    czz: float = spec(0.0, ge=0.0)
    name: str = spec("")


@dataclass(frozen=True)
class RotorModesConfig:
    count: int = spec(12, ge=1, le=10_000, doc="number of modes reported")
    cutoff_hz: float | None = spec(None, gt=0.0, doc="report modes up to this frequency instead")
    speed_rpm: float = spec(0.0, ge=0.0, le=1e7, doc="spin speed of the modal analysis")
    master_count: int = spec(30, ge=1, le=10_000, doc="free-shaft master modes (incl. rigid)")
    master_cutoff_hz: float | None = spec(None, gt=0.0, doc="master modes up to this frequency")


@dataclass(frozen=True)
class CampbellConfig:
    rpm_max: float = spec(gt=0.0, le=1e7)
    rpm_min: float = spec(0.0, ge=0.0)
    n_speeds: int = spec(31, ge=2, le=100_000)
    orders: tuple[float, ...] = spec((1.0,), min_len=1, max_len=20, gt=0.0)
    n_modes: int = spec(8, ge=1, le=1000, doc="frequency lines drawn")

    def validate(self, path: str) -> None:
        if not self.rpm_min < self.rpm_max:
            raise ConfigError(f"{path}.rpm_max", f"must be greater than rpm_min = "
                              f"{self.rpm_min:g}, got {self.rpm_max:g}")


def node_positions(sections: tuple[ShaftSectionConfig, ...]) -> list[float]:
    """Node coordinates [m] of the sections' uniform subdivisions (first node at 0)."""
    nodes = [0.0]
    for s in sections:
        z0 = nodes[-1]
        n = s.elements or 1
        nodes.extend(z0 + s.length * (k + 1) / n for k in range(n))
    return nodes


@dataclass(frozen=True)
class RotorConfig:
    material: MaterialConfig = spec(doc="default material")
    sections: tuple[ShaftSectionConfig, ...] = spec(min_len=1)
    discs: tuple[DiscConfig, ...] = spec(())
    free_gears: tuple[FreeGearConfig, ...] = spec(())
    bearings: tuple[BearingConfig, ...] = spec(())
    modes: RotorModesConfig = spec(RotorModesConfig())
    campbell: CampbellConfig | None = spec(None)
    name: str = spec("rotor")

    def validate(self, path: str) -> None:
        nodes = node_positions(self.sections)
        for group in ("discs", "free_gears", "bearings"):
            seen: dict[int, int] = {}
            for i, item in enumerate(getattr(self, group)):
                fpath = f"{path}.{group}[{i}].position"
                node = node_at(nodes, item.position, fpath)
                if group == "bearings" and node in seen:
                    raise ConfigError(fpath, f"node {node} (z = {nodes[node]:g} m) already has "
                                      f"bearing {seen[node]}; at most one bearing per node")
                seen[node] = i

    def node_of(self, position: float) -> int:
        return node_at(node_positions(self.sections), position, "position")


def node_at(nodes: list[float], z: float, path: str) -> int:
    length = nodes[-1]
    if not 0.0 <= z <= length * (1 + POSITION_TOL):
        raise ConfigError(path, f"value {z:g} outside the shaft: must be in [0, {length:g}] m")
    best = min(range(len(nodes)), key=lambda k: abs(nodes[k] - z))
    if abs(nodes[best] - z) > POSITION_TOL * length:
        lo = max(best - 1, 0)
        near = ", ".join(f"{nodes[k]:.6g}" for k in range(lo, min(best + 2, len(nodes))))
        raise ConfigError(path, f"z = {z:g} m is not a node; nearest nodes: {near} m "
                          "(change the section lengths or element counts)")
    return best
