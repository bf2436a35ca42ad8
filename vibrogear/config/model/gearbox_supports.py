"""The supports of a gearbox scene: its rolling-element bearings (``[[gearbox.bearings]]``)
and external torsional couplings (``[[gearbox.couplings]]``); the schema is described in
:mod:`.gearbox`."""
from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

from ..base import ConfigError, spec
from .bearing_catalogue import ElementSet, boundary_dimensions, element_set

__all__ = ["GearboxBearingConfig", "ExternalCouplingConfig", "BEARING_EXPONENTS",
           "MAX_TORQUE_ORDERS", "MAX_ORDER_DENOMINATOR", "MAX_ORDER_PERIOD",
           "MAX_COMMON_PERIOD", "torque_order_ratios", "order_period"]

#: torque orders per coupling, the largest denominator of an order (0.5: 2, 1/3: 3, ...),
#: and the longest whole excitation period the orders may make, in mesh periods
MAX_TORQUE_ORDERS, MAX_ORDER_DENOMINATOR, MAX_ORDER_PERIOD = 20, 12, 1000
#: the period limit of the meshes: where the meshes exciting at their own mesh frequencies
#: repeat together only after more mesh periods of meshes[0] than this, shooting and
#: continuation are refused (an orbit of 17+ mesh periods costs as many periods per flow,
#: with the monodromy of the whole period) and the sampling solvers (sweep, states, map, nvh)
#: sample per mesh period of meshes[0]: the response is "multi-frequency forced".  Torque
#: orders alone keep their whole period up to MAX_ORDER_PERIOD.
MAX_COMMON_PERIOD = 16


def _check_order(term, path: str) -> None:
    """One [order, amplitude N m(, phase deg)] entry of torque_orders; ConfigError naming it."""
    if len(term) not in (2, 3):
        raise ConfigError(path, f"expected [order, amplitude N m] or [order, amplitude N m, "
                          f"phase deg], got {len(term)} numbers")
    order, amp = term[0], term[1]
    if not (math.isfinite(order) and 0.0 < order <= 1000.0):
        raise ConfigError(f"{path}[0]", f"order must be a number > 0 and <= 1000, got {order!r}")
    f = Fraction(order).limit_denominator(MAX_ORDER_DENOMINATOR)
    if abs(float(f) - order) > 1e-9 * order:
        raise ConfigError(f"{path}[0]", f"order {order!r} must be a ratio of integers with a "
                          f"denominator <= {MAX_ORDER_DENOMINATOR} (e.g. 0.5, 1.5, 2): the "
                          "excitation must repeat after a whole number of mesh periods")
    if not (math.isfinite(amp) and 0.0 <= amp <= 1e8):
        raise ConfigError(f"{path}[1]", f"amplitude must be a number >= 0 and <= 1e8 N m, got "
                          f"{amp!r}")
    if len(term) == 3 and not math.isfinite(term[2]):
        raise ConfigError(f"{path}[2]", f"phase must be a finite number [deg], got {term[2]!r}")


def torque_order_ratios(gearbox) -> tuple[tuple, ...]:
    """(coupling index, order, amplitude N m, phase deg, n) per torque order of the scene's
    couplings: n = order p_s / z, the order's frequency over the mesh frequency of the
    driving speed (z the teeth of meshes[0].gear_a, p_s the coupling shaft's speed ratio),
    an exact fraction; the excitation repeats after lcm(denominators of n) mesh periods."""
    if not any(c.torque_orders for c in gearbox.couplings):
        return ()
    shaft_p, _ = gearbox.exact_speed_ratios()
    m0 = gearbox.meshes[0] if gearbox.meshes else None
    z = gearbox.gears[gearbox.gear_index(m0.gear_a, "")].teeth if m0 else 1
    out = []
    for i, c in enumerate(gearbox.couplings):
        p_s = abs(shaft_p[gearbox.shaft_index(c.shaft, "")])
        out += [(i, order, amp, phase, order * p_s / z) for order, amp, phase in c.order_terms()]
    return tuple(out)


def order_period(terms) -> int:
    """Mesh periods after which the excitation with these torque-order ``terms``
    (:func:`torque_order_ratios`) repeats: the least common multiple of the denominators of
    their fractions n (1 without orders)."""
    return math.lcm(1, *(t[4].denominator for t in terms))


#: contact-law exponent of each bearing type ("spring" has no contacts)
BEARING_EXPONENTS = {"ball": 1.5, "roller": 10.0 / 9.0, "linear": 1.0}


@dataclass(frozen=True, kw_only=True)
class GearboxBearingConfig:
    name: str = spec()
    shaft: str = spec()
    position: float = spec(ge=0.0, doc="[m]; must be a node")
    type: str | None = spec(None, choices=("ball", "roller", "linear", "spring"),
                            doc="ball (Hertz 3/2), roller (10/9), linear (one-sided linear "
                            "contacts) or spring (linear, no contact loss); default: from "
                            "the designation, else ball")
    stiffness: float | None = spec(None, gt=0.0, le=1e14, doc="contact constant per element "
                                   "[N/m^p] (spring: isotropic [N/m]); an override: without "
                                   "it the constant follows from designation, boundary "
                                   "dimensions or element set (Harris / Palmgren)")
    designation: str = spec("", doc="catalogue designation, e.g. \"6210-2Z\", \"33014\", "
                            "\"NU 210\" (ISO 15 / ISO 355 boundary dimensions)")
    bore_diameter: float | None = spec(None, gt=0.0, lt=10.0, doc="boundary dimension d [m]")
    outer_diameter: float | None = spec(None, gt=0.0, lt=10.0, doc="boundary dimension D [m]")
    width: float | None = spec(None, gt=0.0, lt=10.0, doc="boundary dimension B (tapered: T) [m]")
    element_diameter: float | None = spec(None, gt=0.0, lt=1.0, doc="rolling-element "
                                          "diameter D_w [m] (tapered: mean)")
    pitch_diameter: float | None = spec(None, gt=0.0, lt=10.0, doc="pitch diameter d_m [m]")
    element_length: float | None = spec(None, gt=0.0, lt=1.0, doc="effective roller length "
                                        "l [m] (rollers)")
    contact_angle: float | None = spec(None, ge=0.0, lt=60.0, doc="contact angle [deg] "
                                       "(tapered rollers, angular-contact balls)")
    outer_shaft: str = spec("", doc="shaft carrying the outer ring (a shaft running in "
                            "another); default: the housing (or ground)")
    outer_position: float | None = spec(None, ge=0.0, doc="[m] along outer_shaft; must be "
                                        "a node")
    clearance: float = spec(0.0, ge=0.0, lt=0.01, doc="radial clearance [m]")
    elements: int | None = spec(None, ge=3, le=200, doc="rolling elements (default: the bore's)")
    angle_offset: float = spec(0.0, doc="angle of element 0 without housing [deg]")
    axial_stiffness: float = spec(0.0, ge=0.0, doc="[N/m]")
    damping: float = spec(0.0, ge=0.0, doc="radial and axial viscous damping [N s/m], always active")
    contact_damping: float = spec(0.0, ge=0.0, doc="per element, only in contact [N s/m]")
    # anisotropic linear bearing (type "spring"), rotor frame X = -x, Y = z (up) of the housing
    kxx: float | None = spec(None, ge=0.0, le=1e14, doc="spring: [N/m] (default: stiffness)")
    kyy: float | None = spec(None, ge=0.0, le=1e14, doc="spring: [N/m] (default: stiffness)")
    kxy: float = spec(0.0, ge=-1e14, le=1e14, doc="spring: force X per displacement Y [N/m]")
    kyx: float = spec(0.0, ge=-1e14, le=1e14, doc="spring: force Y per displacement X [N/m]")
    cxx: float | None = spec(None, ge=0.0, doc="spring: [N s/m] (default: damping)")
    cyy: float | None = spec(None, ge=0.0, doc="spring: [N s/m] (default: damping)")
    cxy: float = spec(0.0, doc="spring: [N s/m]")
    cyx: float = spec(0.0, doc="spring: [N s/m]")

    def __post_init__(self):
        if self.type is None:      # the designation's kind, else a ball bearing
            kind = ("ball" if not self.designation else
                    boundary_dimensions(self.designation, "designation").kind)
            object.__setattr__(self, "type", "ball" if kind == "ball" else "roller")

    @property
    def geometric(self) -> bool:
        """The contact constant follows from the geometry (no ``stiffness`` override)."""
        return self.stiffness is None and self.type in ("ball", "roller") and bool(
            self.designation or self.bore_diameter is not None
            or self.element_diameter is not None)

    def element_set(self, path: str = "") -> ElementSet | None:
        """The rolling elements (given, or by the rule of :mod:`.bearing_catalogue`); None
        where the bearing gives no geometry."""
        if not (self.designation or self.bore_diameter is not None
                or self.element_diameter is not None):
            return None
        if self.designation:
            bd = boundary_dimensions(self.designation, f"{path}.designation")
            kind, d, D, B = bd.kind, bd.d, bd.D, bd.B
        else:
            kind = "ball" if self.type == "ball" else (
                "tapered" if self.contact_angle else "cylindrical")
            d, D, B = self.bore_diameter, self.outer_diameter, self.width
        if d is None or D is None or B is None:
            if self.element_diameter is None or self.pitch_diameter is None or \
                    self.elements is None or (kind != "ball" and self.element_length is None):
                raise ConfigError(f"{path}.outer_diameter", "give the boundary dimensions "
                                  "bore_diameter, outer_diameter and width [m], or the full "
                                  "element set: elements, element_diameter, pitch_diameter "
                                  "(and element_length for rollers)")
            d = D = B = 0.0
        elif not d < D:
            raise ConfigError(f"{path}.outer_diameter", f"must be > bore_diameter {d:g} m, "
                              f"got {D:g}")
        return element_set(kind, d, D, B, count=self.elements,
                           element_diameter=self.element_diameter,
                           pitch_diameter=self.pitch_diameter,
                           element_length=self.element_length, contact_angle=self.contact_angle)

    @property
    def exponent(self) -> float:
        return BEARING_EXPONENTS.get(self.type, 1.0)

    def radial_matrices(self):
        """Spring bearing: ((kxx, kxy), (kyx, kyy)) [N/m] and ((cxx, cxy), (cyx, cyy))
        [N s/m] in the rotor frame; the force on the journal is -K d - C d'."""
        k = self.stiffness if self.stiffness is not None else 0.0
        kxx = k if self.kxx is None else self.kxx
        kyy = k if self.kyy is None else self.kyy
        cxx = self.damping if self.cxx is None else self.cxx
        cyy = self.damping if self.cyy is None else self.cyy
        return ((kxx, self.kxy), (self.kyx, kyy)), ((cxx, self.cxy), (self.cyx, cyy))

    def validate(self, path: str) -> None:
        aniso = [n for n in ("kxx", "kyy", "kxy", "kyx", "cxx", "cyy", "cxy", "cyx")
                 if getattr(self, n)]
        if aniso and self.type != "spring":
            raise ConfigError(f"{path}.{aniso[0]}", f"only a 'spring' bearing has a stiffness "
                              f"matrix; this one is {self.type!r}")
        if self.designation or self.bore_diameter is not None or \
                self.element_diameter is not None:
            if self.type not in ("ball", "roller"):
                raise ConfigError(f"{path}.type", f"a {self.type!r} bearing takes stiffness, "
                                  "not a designation or geometry")
            es = self.element_set(path)
            if (es.kind == "ball") != (self.type == "ball"):
                raise ConfigError(f"{path}.type", f"{self.type!r} contradicts the "
                                  f"{es.kind} bearing the geometry describes; leave type out")
        if (self.outer_shaft == "") != (self.outer_position is None):
            raise ConfigError(f"{path}.outer_position", "outer_shaft and outer_position go "
                              "together (a bearing between two shafts)")
        if self.stiffness is None and not self.geometric and (
                self.type != "spring" or self.kxx is None or self.kyy is None):
            missing = "stiffness" if self.type != "spring" else \
                ("kxx" if self.kxx is None else "kyy")
            raise ConfigError(f"{path}.{missing}", "missing required key: give stiffness, "
                              "or a designation, boundary dimensions or element set (a spring "
                              "bearing takes stiffness, or kxx and kyy)")
        if self.type == "spring" and self.clearance:
            raise ConfigError(f"{path}.clearance", "a 'spring' bearing has no clearance (0); "
                              "use type 'linear' for one-sided linear contacts")


@dataclass(frozen=True, kw_only=True)
class ExternalCouplingConfig:
    name: str = spec()
    shaft: str = spec()
    position: float = spec(ge=0.0, doc="[m]; must be a node")
    role: str = spec(choices=("motor", "load"))
    stiffness: float = spec(gt=0.0, doc="torsional stiffness [N m/rad]")
    twist: float | None = spec(None, ge=0.0, lt=1.0, doc="static twist angle [rad] (the "
                               "static load); or give torque, or power with rpm")
    torque: float | None = spec(None, ge=0.0, le=1e8, doc="static torque [N m] the coupling "
                                "transmits in the static state of the elastic model (the load "
                                "path solves its twist)")
    power: float | None = spec(None, ge=0.0, le=1e6, doc="power [kW] the coupling transmits "
                               "at rpm: torque = power / (2 pi rpm / 60)")
    rpm: float | None = spec(None, gt=0.0, le=1e6, doc="speed of this coupling's shaft [rpm] "
                             "at which power is given (with power only)")
    damping: float = spec(0.0, ge=0.0, doc="torsional damping [N m s/rad]")
    torque_orders: tuple[tuple[float, ...], ...] = spec(
        (), doc=f"at most {MAX_TORQUE_ORDERS} entries: torque fluctuation by orders of this coupling's "
        "shaft speed (engine torsionals): [[order, amplitude N m], ...] or [[order, "
        "amplitude N m, phase deg], ...]; order > 0, a ratio of integers with a "
        f"denominator <= {MAX_ORDER_DENOMINATOR} (0.5, 1, 1.5, 2, ...)")

    def order_terms(self) -> tuple[tuple[Fraction, float, float], ...]:
        """(order as an exact fraction, amplitude [N m], phase [deg]) of each torque order."""
        return tuple((Fraction(t[0]).limit_denominator(MAX_ORDER_DENOMINATOR), float(t[1]),
                      float(t[2]) if len(t) > 2 else 0.0) for t in self.torque_orders)

    @property
    def static_torque(self) -> float:
        """The static torque [N m]: torque, power / (2 pi rpm / 60), or stiffness x twist."""
        if self.torque is not None:
            return self.torque
        if self.power is not None:
            return self.power * 1e3 / (self.rpm * 2.0 * math.pi / 60.0)
        return self.stiffness * self.twist

    @property
    def static_twist(self) -> float:
        """The static twist angle [rad]: twist, or the torque (given, or from power) over the
        stiffness."""
        if self.twist is not None:
            return self.twist
        return self.static_torque / self.stiffness

    @property
    def load_given(self) -> str:
        """Which key sets the load: "twist", "torque" or "power"."""
        return next(k for k in ("twist", "torque", "power") if getattr(self, k) is not None)

    def validate(self, path: str) -> None:
        given = [k for k in ("twist", "torque", "power") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ConfigError(f"{path}.{given[1] if given else 'twist'}",
                              "give exactly one of twist [rad], torque [N m] or power [kW] "
                              f"(with rpm), got {', '.join(given) if given else 'none'}")
        if (self.rpm is not None) != (self.power is not None):
            raise ConfigError(f"{path}.{'rpm' if self.power is not None else 'power'}",
                              "power [kW] and rpm [rpm] go together (torque = power / "
                              "(2 pi rpm / 60))")
        if len(self.torque_orders) > MAX_TORQUE_ORDERS:
            raise ConfigError(f"{path}.torque_orders", f"allows at most {MAX_TORQUE_ORDERS} "
                              f"entries, got {len(self.torque_orders)}")
        for i, term in enumerate(self.torque_orders):
            _check_order(term, f"{path}.torque_orders[{i}]")
        tw = self.static_twist
        if not tw < 1.0:
            raise ConfigError(f"{path}.{given[0]}", f"implies a twist of {tw:.4g} rad = "
                              f"torque {self.static_torque:.6g} N m / stiffness "
                              f"{self.stiffness:g} N m/rad; must be < 1 rad: raise the "
                              "stiffness or lower the load")
