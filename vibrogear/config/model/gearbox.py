"""Gearbox scene schema: ``[gearbox]`` (shafts, gears, meshes, bearings, external couplings).

Frames.  The *housing frame* is the one of ``[housing]``: x along the housing length, y along
the shafts (front wall y = 0), z up.  Every shaft is a rotor of ``vibrogear.models.rotor.model``
whose own axis is z; a shaft's *rotor frame* is (X, Y, Z) = (-x, z, y) of the housing frame
(right-handed, Y up), so all shafts share one orientation.  A shaft's axis sits at the
housing-frame (x, z) of its bore (or of its ``x``/``z`` fields when there is no housing) and
its node at rotor coordinate ``position`` lies at housing y = ``y0 + position``.

Speeds.  The driving shaft is ``shafts[0]``; it spins about +Z at the scene's speed (rpm).
The other shafts' speed ratios follow from the tooth counts of the fixed gears that mesh
(external pairs reverse the sense).  Every mesh excites (its stiffness variation and
kinematic transmission error) at its own mesh frequency, z_j p_j / (z_0 p_0) times that of
``meshes[0]`` (an exact fraction of the tooth counts), the base frequency of every
analysis; the excitation repeats after the common period (:meth:`GearboxConfig.common_period`).
``excite = false`` makes a mesh a constant spring at its mean stiffness.

```toml
[gearbox]
name = "two-stage gearbox"

gravity = [0.0, 0.0, -9.81]  # [m/s^2], housing frame (default 0): a static load
master_modes = "count"      # or "frequency": shaft modes up to frequency_factor (2) x the
                            # highest mesh harmonic at the top speed + static correction

[[gearbox.shafts]]
name = "driving"
bore = "input"              # housing bore pair carrying this shaft (or x = ..., z = ... without housing)
y0 = -0.03                  # housing y of the shaft's node at position 0 [m]
master_count = 30           # free-shaft master modes (incl. rigid-body) ... or master_cutoff_hz
modal_damping = 0.01        # damping ratio of the elastic shaft modes
[gearbox.shafts.material]   # as [rotor.material]
[[gearbox.shafts.sections]] # as [[rotor.sections]]
[[gearbox.shafts.discs]]    # rigid discs that are not gears (as [[rotor.discs]])

[[gearbox.gears]]
name = "z1"; shaft = "driving"; position = 0.12
teeth = 25; module = 0.003  # normal module [m]
helix_angle = 0.0           # [deg]
width = 0.03; inner_diameter = 0.04
free = false                # true: rotates freely on its own bearing (rattling gear)
# mass = 1.2; Id = 8e-4; Ip = 1.5e-3  # [kg], [kg m^2]: instead of the pitch-diameter disc

[[gearbox.meshes]]
name = "G1"; gear_a = "z1"; gear_b = "z2"   # gear_a drives gear_b
pressure_angle = 20.0       # normal pressure angle [deg]
stiffness = 4e8             # mean mesh stiffness [N/m], or "iso6336" (ISO 6336-1 method B
                            # from teeth, module, helix, pressure angle and:)
# stiffness_levels = [3.0e8, 5.2e8]  # instead of stiffness: [k_single, k_double] [N/m], a
# double_contact_share = 0.557       # square wave (default share: eps_alpha - 1, ISO 6336)
# level_terms = 20          # Fourier terms of the square wave (Fejer-weighted)
excite = true               # false: a constant spring (no stiffness variation, no TE)
profile_shift_a = 0.0       # profile shift coefficients x [-]
profile_shift_b = 0.0
face_width = 0.025          # [m] (default: the smaller gear width)
addendum = 1.0; dedendum = 1.25   # basic rack h_aP/m_n, h_fP/m_n
iso_harmonics = 3           # single/double contact harmonics used with "iso6336"
damping = 300.0             # [N s/m], acts while in contact
backlash = 1e-4             # [m]
stiffness_cos = [0.15]      # relative mesh-stiffness harmonics of the mesh frequency
te_cos = [5e-6]             # kinematic transmission error harmonics [m]

[[gearbox.bearings]]
name = "A"; shaft = "driving"; position = 0.02
type = "ball"               # ball (Hertz 3/2), roller (10/9), linear (one-sided linear contacts)
                            # or spring (linear isotropic spring, no contact loss)
stiffness = 8e9             # contact constant [N/m^p] (spring: [N/m])
clearance = 5e-6            # radial clearance [m]
axial_stiffness = 5e7       # [N/m]
damping = 200.0             # radial and axial viscous damping [N s/m], always active
# kxx = 2e8; kyy = 3e8; kxy = 0; kyx = 0; cxx = 200; cyy = 300   # spring: anisotropic
#                           # [N/m], [N s/m] in the rotor frame X = -x, Y = z (up)

[[gearbox.couplings]]
name = "motor"; shaft = "driving"; position = 0.0
role = "motor"              # motor: the disc leads the node; load: it lags
stiffness = 2e4             # torsional [N m/rad]
twist = 0.025               # static twist angle delta phi [rad]
```
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from fractions import Fraction
from typing import ClassVar

from ..base import ConfigError, ErrorList, spec
from ..options import RPM, Parameter
from .gearbox_supports import (BEARING_EXPONENTS, MAX_COMMON_PERIOD, MAX_ORDER_PERIOD,
                               ExternalCouplingConfig, GearboxBearingConfig, order_period,
                               torque_order_ratios)
from .shaft_mesh import MAX_ELEMENT_LENGTH, mesh_sections, with_nodes_at
from .gearbox_meshes import GearConfig, MeshConfig
from .rotor import DiscConfig, MaterialConfig, ShaftSectionConfig, node_at, node_positions

__all__ = ["GearboxConfig", "ShaftConfig", "GearConfig", "MeshConfig", "GearboxBearingConfig",
           "ExternalCouplingConfig", "BEARING_EXPONENTS", "MAX_COMMON_PERIOD",
           "SHOOTING_ANALYSES"]

#: the analyses that shoot periodic orbits over the common excitation period: refused
#: beyond the period limit (MAX_COMMON_PERIOD)
SHOOTING_ANALYSES = ("continuation", "map")


@dataclass(frozen=True, kw_only=True)
class ShaftConfig:
    name: str = spec(doc="shaft name (gears, bearings and couplings refer to it)")
    material: MaterialConfig = spec(doc="as [rotor.material]")
    sections: tuple[ShaftSectionConfig, ...] = spec(min_len=1)
    discs: tuple[DiscConfig, ...] = spec((), doc="rigid discs that are not gears")
    bore: str = spec("", doc="name of the housing bore pair carrying the shaft")
    x: float | None = spec(None, doc="axis x in the housing frame [m] (scenes without housing)")
    z: float | None = spec(None, doc="axis height z in the housing frame [m] (no housing)")
    y0: float = spec(0.0, doc="housing-frame y of the node at position 0 [m]")
    master_count: int = spec(30, ge=1, le=10_000, doc="free-shaft master modes (incl. rigid)")
    master_cutoff_hz: float | None = spec(None, gt=0.0, doc="all free-shaft modes up to this")
    modal_damping: float = spec(0.0, ge=0.0, lt=1.0, doc="damping ratio of the elastic modes")

    def node(self, position: float, path: str) -> int:
        return node_at(node_positions(self.sections), position, path)


@dataclass(frozen=True, kw_only=True)
class GearboxConfig:
    PARAMETER: ClassVar[Parameter] = RPM      # continued in the driving-shaft speed [rpm]
    shafts: tuple[ShaftConfig, ...] = spec(min_len=1, max_len=20)
    gears: tuple[GearConfig, ...] = spec(())
    meshes: tuple[MeshConfig, ...] = spec((), max_len=20)
    bearings: tuple[GearboxBearingConfig, ...] = spec(min_len=1)
    couplings: tuple[ExternalCouplingConfig, ...] = spec(())
    name: str = spec("gearbox")
    modes_rpm: float | None = spec(None, ge=0.0, le=1e6, doc="driving speed at which the "
                                   "'modes' analysis linearises [rpm] (default: the time "
                                   "response's, else the middle of the sweep range, else 0)")
    gravity: tuple[float, float, float] = spec((0.0, 0.0, 0.0), doc="gravitational "
                                               "acceleration in the housing frame [m/s^2], "
                                               "e.g. [0, 0, -9.81]; a static load")
    master_modes: str = spec("count", choices=("count", "frequency"), doc="shaft master "
                             "modes: each shaft's master_count / master_cutoff_hz, or by the "
                             "frequency criterion: all modes up to frequency_factor x the "
                             "highest excitation frequency the shaft carries at the scene's "
                             "highest speed (mesh frequency x harmonics)")
    frequency_factor: float = spec(2.0, ge=1.0, le=100.0, doc="master_modes = \"frequency\": "
                                   "cutoff / highest excitation frequency")
    static_correction: bool | None = spec(None, doc="add the static deflection shapes under "
                                          "the shaft's coupling forces (residual "
                                          "flexibility; default: on with master_modes = "
                                          "\"frequency\", off with \"count\")")

    max_element_length: float = spec(MAX_ELEMENT_LENGTH, gt=0.0, le=10.0, doc="longest "
                                     "shaft element [m] where a shaft's sections give no "
                                     "element counts (meshed for you: nodes at every gear, "
                                     "bearing, coupling, disc and section change)")

    def __post_init__(self):
        """Shafts whose sections give no element counts are meshed here: split at every
        feature, elements no longer than ``max_element_length`` (:mod:`.shaft_mesh`)."""
        shafts = list(self.shafts)
        for k, sh in enumerate(shafts):
            given = [sec.elements is not None for sec in sh.sections]
            if any(given) and not all(given):
                raise ConfigError(f"shafts[{k}].sections[{given.index(True)}].elements",
                                  "give elements in every section of a shaft or in none "
                                  "(none: the shaft is meshed for you)")
            feats = [x.position for grp in (self.gears, self.bearings, self.couplings)
                     for x in grp if x.shaft == sh.name]
            feats += [b.outer_position for b in self.bearings if b.outer_shaft == sh.name]
            feats += [d.position for d in sh.discs]
            if all(given):      # counted by hand: a feature between nodes gets its own node
                shafts[k] = dataclasses.replace(sh, sections=with_nodes_at(sh.sections, feats))
                continue
            rows = [dict(length=s.length, outer_diameter=s.outer_diameter,
                         inner_diameter=s.inner_diameter, material=s.material)
                    for s in sh.sections]
            split = mesh_sections(rows, feats, max_element=self.max_element_length,
                                  path=f"shafts[{k}].sections")
            secs = tuple(ShaftSectionConfig(length=r["length"], outer_diameter=r["outer_diameter"],
                                            inner_diameter=r["inner_diameter"],
                                            material=r["material"],
                                            elements=r["elements"])
                         for r in split)
            shafts[k] = dataclasses.replace(sh, sections=secs)
        object.__setattr__(self, "shafts", tuple(shafts))

    def shaft_index(self, name: str, path: str) -> int:
        for i, s in enumerate(self.shafts):
            if s.name == name:
                return i
        raise ConfigError(path, f"unknown shaft {name!r}; shafts are "
                          f"{', '.join(repr(s.name) for s in self.shafts)}")

    def gear_index(self, name: str, path: str) -> int:
        for i, g in enumerate(self.gears):
            if g.name == name:
                return i
        raise ConfigError(path, f"unknown gear {name!r}; gears are "
                          f"{', '.join(repr(g.name) for g in self.gears) or 'none'}")

    def validate(self, path: str) -> None:
        g = math.sqrt(sum(c * c for c in self.gravity))
        if g > 1000.0:
            raise ConfigError(f"{path}.gravity", f"|g| = {g:g} m/s^2 out of range: must be "
                              "<= 1000 (e.g. [0, 0, -9.81] for z up)")
        for group in ("shafts", "gears", "meshes", "bearings", "couplings"):
            seen = set()
            for i, item in enumerate(getattr(self, group)):
                if item.name in seen:
                    raise ConfigError(f"{path}.{group}[{i}].name", f"{item.name!r} used twice")
                seen.add(item.name)
        occupied: dict[tuple[int, int], str] = {}
        errs = ErrorList()            # every misplaced part, reported together
        for group in ("gears", "bearings", "couplings"):
            for i, item in enumerate(getattr(self, group)):
                p = f"{path}.{group}[{i}]"
                with errs.catch():
                    s = self.shaft_index(item.shaft, f"{p}.shaft")
                    node = self.shafts[s].node(item.position, f"{p}.position")
                    if group == "gears":
                        if (s, node) in occupied:
                            raise ConfigError(f"{p}.position", f"node already carries gear "
                                              f"{occupied[(s, node)]!r}")
                        occupied[(s, node)] = item.name
        errs.raise_if()
        for i, b in enumerate(self.bearings):
            if b.outer_shaft:
                p = f"{path}.bearings[{i}]"
                so = self.shaft_index(b.outer_shaft, f"{p}.outer_shaft")
                if b.outer_shaft == b.shaft:
                    raise ConfigError(f"{p}.outer_shaft", "must differ from shaft (the shaft "
                                      "the outer ring sits in)")
                self.shafts[so].node(b.outer_position, f"{p}.outer_position")
        bearing_nodes: dict[tuple[int, int], int] = {}
        for i, b in enumerate(self.bearings):
            s = self.shaft_index(b.shaft, "")
            key = (s, self.shafts[s].node(b.position, ""))
            if key in bearing_nodes:
                raise ConfigError(f"{path}.bearings[{i}].position",
                                  f"node already has bearing {bearing_nodes[key]}")
            bearing_nodes[key] = i
        for i, m in enumerate(self.meshes):
            p = f"{path}.meshes[{i}]"
            ga = self.gears[self.gear_index(m.gear_a, f"{p}.gear_a")]
            gb = self.gears[self.gear_index(m.gear_b, f"{p}.gear_b")]
            if ga.shaft == gb.shaft:
                raise ConfigError(f"{p}.gear_b", "gears of a mesh must sit on different shafts")
            if abs(ga.module - gb.module) > 1e-9 * ga.module:
                raise ConfigError(f"{p}.gear_b", f"module {gb.module:g} differs from gear_a's "
                                  f"{ga.module:g}")
            if abs(ga.helix_angle - gb.helix_angle) > 1e-9:
                raise ConfigError(f"{p}.gear_b", f"helix angle {gb.helix_angle:g} differs from "
                                  f"gear_a's {ga.helix_angle:g} (the hand is the mesh's `hand`)")
        if self.meshes:
            first = self.meshes[0]
            ga = self.gears[self.gear_index(first.gear_a, "")]
            gb = self.gears[self.gear_index(first.gear_b, "")]
            if ga.free or gb.free:
                raise ConfigError(f"{path}.meshes[0]", "the excitation mesh (meshes[0]) must "
                                  "join fixed gears: it carries the power")
        self.speed_ratios(path)
        self._check_order_period(path)

    def _check_order_period(self, path: str) -> None:
        """The torque orders' whole excitation period: at most MAX_ORDER_PERIOD mesh periods
        (named at the coupling whose order needs the longest)."""
        terms = torque_order_ratios(self)
        period = order_period(terms)
        if period > MAX_ORDER_PERIOD:
            i, order, _, _, n = max(terms, key=lambda t: t[4].denominator)
            raise ConfigError(f"{path}.couplings[{i}].torque_orders",
                              f"order {float(order):g} is {n.numerator}/{n.denominator} of the "
                              f"mesh frequency: with the other orders the excitation repeats "
                              f"only after {period} mesh periods (at most {MAX_ORDER_PERIOD}); "
                              "use orders whose ratios "
                              "to the mesh frequency share a denominator")

    def speed_ratios(self, path: str = "gearbox") -> tuple[list[float], list[float]]:
        """(shaft spin / driving-shaft spin per shaft, gear spin / driving-shaft spin per
        gear): fixed-gear meshes carry the kinematics from shafts[0]; a free gear takes the
        speed of the fixed gear it meshes with."""
        shaft_p, gear_p = self.exact_speed_ratios(path)
        return [float(p) for p in shaft_p], [float(p) for p in gear_p]

    def exact_speed_ratios(self, path: str = "gearbox") -> tuple[list[Fraction], list[Fraction]]:
        """:meth:`speed_ratios` as exact fractions of the tooth counts."""
        shaft_p: list[Fraction | None] = [Fraction(1)] + [None] * (len(self.shafts) - 1)
        gear_shaft = [self.shaft_index(g.shaft, "") for g in self.gears]
        pairs = [(self.gear_index(m.gear_a, ""), self.gear_index(m.gear_b, ""))
                 for m in self.meshes]
        changed = True
        while changed:
            changed = False
            for a, b in pairs:
                ga, gb = self.gears[a], self.gears[b]
                if ga.free or gb.free:
                    continue
                pa, pb = shaft_p[gear_shaft[a]], shaft_p[gear_shaft[b]]
                if pa is not None and pb is None:
                    shaft_p[gear_shaft[b]] = -pa * Fraction(ga.teeth, gb.teeth)
                    changed = True
                elif pb is not None and pa is None:
                    shaft_p[gear_shaft[a]] = -pb * Fraction(gb.teeth, ga.teeth)
                    changed = True
        for i, p in enumerate(shaft_p):
            if p is None:
                raise ConfigError(f"{path}.shafts[{i}]", f"shaft {self.shafts[i].name!r} is not "
                                  "driven: no chain of fixed-gear meshes joins it to shafts[0]")
        gear_p = [shaft_p[gear_shaft[k]] for k in range(len(self.gears))]
        for i, (a, b) in enumerate(pairs):
            ga, gb = self.gears[a], self.gears[b]
            if ga.free and gb.free:
                raise ConfigError(f"{path}.meshes[{i}]", f"mesh of two free gears ({ga.name!r}, "
                                  f"{gb.name!r}) has no defined speed")
            if ga.free:
                gear_p[a] = -gear_p[b] * Fraction(gb.teeth, ga.teeth)
            elif gb.free:
                gear_p[b] = -gear_p[a] * Fraction(ga.teeth, gb.teeth)
        return shaft_p, gear_p

    def mesh_frequency_ratios(self) -> tuple[Fraction, ...]:
        """Per mesh: its mesh frequency over that of meshes[0], an exact fraction
        z_j |p_j| / (z_0 |p_0|) (z the teeth of gear_a, p its speed ratio)."""
        if not self.meshes:
            return ()
        _, gear_p = self.exact_speed_ratios()
        f = [abs(gear_p[k]) * self.gears[k].teeth
             for k in (self.gear_index(m.gear_a, "") for m in self.meshes)]
        return tuple(x / f[0] for x in f)

    def mesh_period(self) -> int:
        """Mesh periods of meshes[0] after which the meshes' excitation repeats: the least
        common multiple of the denominators of every excited mesh's frequency ratio."""
        return math.lcm(1, *(r.denominator for r, m in zip(self.mesh_frequency_ratios(),
                                                            self.meshes)
                             if m.excitation_harmonics))

    def common_period(self) -> int:
        """The common excitation period in mesh periods of meshes[0]: the meshes' period
        and the torque orders' together (1: every source repeats each mesh period)."""
        return math.lcm(self.mesh_period(), order_period(torque_order_ratios(self)))

    def period_limit(self) -> int:
        """The longest common period the solvers span whole (shooting, continuation, the
        sampling of sweep, states and map): MAX_COMMON_PERIOD where the meshes' own period
        exceeds it, else MAX_ORDER_PERIOD (torque orders alone: a shaft order repeats once
        per revolution, z mesh periods, and engine-order studies shoot over it)."""
        return MAX_COMMON_PERIOD if self.mesh_period() > MAX_COMMON_PERIOD \
            else MAX_ORDER_PERIOD

    @property
    def multi_frequency(self) -> bool:
        """The excitation has no common period within :meth:`period_limit`: the solvers
        sample per mesh period of meshes[0], and nothing is shot."""
        return self.common_period() > self.period_limit()

    def period_sources(self) -> str:
        """The excitation's sources in words, for messages: each excited mesh with its
        tooth counts and frequency ratio, and the torque orders' period."""
        out = []
        for m, r in zip(self.meshes, self.mesh_frequency_ratios()):
            if not m.excitation_harmonics:
                continue
            za = self.gears[self.gear_index(m.gear_a, "")].teeth
            zb = self.gears[self.gear_index(m.gear_b, "")].teeth
            out.append(f"mesh {m.name!r} ({za}/{zb} teeth) at {r.numerator}/{r.denominator}")
        P = order_period(torque_order_ratios(self))
        if P > 1:
            out.append(f"the torque orders every {P} mesh periods")
        return "; ".join(out)

    def check_common_period(self, analyses, path: str = "gearbox") -> None:
        """Refuse the analyses that shoot over the common excitation period (continuation,
        a map with LP/PD curves: ``analyses`` lists those that do) beyond the period limit
        (:meth:`period_limit`), naming the meshes and their tooth counts; the others sample
        per mesh period."""
        what = [a for a in analyses if a in SHOOTING_ANALYSES]
        if not what or not self.multi_frequency:
            return
        P, lim = self.common_period(), self.period_limit()
        names = ", ".join("map (its LP/PD curves)" if a == "map" else a for a in what)
        raise ConfigError(f"{path}.meshes", f"{names}: shooting needs a common excitation "
                          f"period: the sources ({self.period_sources()} of meshes[0]'s mesh "
                          f"frequency) repeat together only every {P} mesh periods of "
                          f"meshes[0] (the limit for shooting is {lim}); "
                          "time_response, sweep, runup, nvh and states run (sampled per mesh "
                          "period: multi-frequency forced); or set excite = false on all but "
                          "one stage")
