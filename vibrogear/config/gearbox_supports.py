"""The supports of a gearbox scene: its rolling-element bearings (``[[gearbox.bearings]]``)
and external torsional couplings (``[[gearbox.couplings]]``); the schema is described in
:mod:`.gearbox`."""
from __future__ import annotations

from dataclasses import dataclass

from .base import ConfigError, spec

__all__ = ["GearboxBearingConfig", "ExternalCouplingConfig", "BEARING_EXPONENTS"]

#: contact-law exponent of each bearing type ("spring" has no contacts)
BEARING_EXPONENTS = {"ball": 1.5, "roller": 10.0 / 9.0, "linear": 1.0}


@dataclass(frozen=True, kw_only=True)
class GearboxBearingConfig:
    name: str = spec()
    shaft: str = spec()
    position: float = spec(ge=0.0, doc="[m]; must be a node")
    type: str = spec("ball", choices=("ball", "roller", "linear", "spring"))
    stiffness: float | None = spec(None, gt=0.0, le=1e14, doc="contact constant [N/m^p] "
                                   "(spring: isotropic [N/m]); required but for a spring "
                                   "bearing with kxx and kyy")
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
        if self.stiffness is None and (self.type != "spring" or self.kxx is None
                                       or self.kyy is None):
            missing = "stiffness" if self.type != "spring" else \
                ("kxx" if self.kxx is None else "kyy")
            raise ConfigError(f"{path}.{missing}", "missing required key (a spring bearing "
                              "takes stiffness, or kxx and kyy)")
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
    twist: float = spec(ge=0.0, lt=1.0, doc="static twist angle [rad] (the static load)")
    damping: float = spec(0.0, ge=0.0, doc="torsional damping [N m s/rad]")
