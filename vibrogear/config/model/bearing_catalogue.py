"""Rolling bearings by catalogue designation: ISO boundary dimensions and the rolling-element
set a documented rule gives where a catalogue would.

Boundary dimensions (bore d, outside diameter D, width B; tapered roller bearings: total
width T) are facts of the standards: ISO 15 (radial bearings, dimension series 10, 02, 03)
and ISO 355 (tapered roller bearings, series 302, 320, 330).  A designation's last two digits
are the bore code: 00 = 10 mm, 01 = 12, 02 = 15, 03 = 17, from 04 on 5 x the code.  Suffixes
after a space, ``-`` or ``/`` (seals ``-2Z``, ``-2RS``, clearance ``/C3``) and letters after
the digits (``E``, ``J2``) do not change the boundary dimensions and are ignored.

The rolling-element set is not part of a designation: manufacturers do not publish it.  The
rule (``element_set``) below takes typical proportions of each bearing type; every value it
assumes is reported as assumed.  Give the element set (``elements``, ``element_diameter``,
``pitch_diameter``, ``element_length``, ``contact_angle``) where the datasheet or the
design tool has it.

* pitch diameter d_m = (d + D) / 2;
* deep-groove ball bearing: ball diameter D_w = 0.3 (D - d); the number of balls fills the
  Conrad assembly angle of 186 deg: Z = floor(186 deg / (2 asin(D_w / d_m))) + 1
  (Harris, *Rolling Bearing Analysis*, ch. 1: the fill angle of a Conrad assembly);
  groove conformities f_i = 0.52, f_o = 0.53; contact angle 0;
* cylindrical roller bearing: D_w = 0.25 (D - d), effective length l = 0.6 B, rollers
  spaced at 1.25 D_w on the pitch circle: Z = floor(pi d_m / (1.25 D_w)); contact angle 0;
* tapered roller bearing: mean D_w = 0.22 (D - d), effective length l = 0.55 T, Z =
  floor(pi d_m / (1.25 D_w)), contact angle 12 deg (typical of series 302, 320, 330).

Units: the table is in mm (as the standards print it); :func:`boundary_dimensions` returns
metres.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..base import ConfigError

__all__ = ["BoundaryDimensions", "ElementSet", "boundary_dimensions", "element_set",
           "bearing_kind", "CONRAD_FILL_DEG", "SERIES"]

#: Conrad-assembly fill angle [deg] (the balls of a deep-groove bearing fill at most this arc)
CONRAD_FILL_DEG = 186.0

# ISO 15: bore code -> (D, B) [mm] per dimension series; d from the bore code
_ISO15 = {
    "60": {0: (26, 8), 1: (28, 8), 2: (32, 9), 3: (35, 10), 4: (42, 12), 5: (47, 12),
           6: (55, 13), 7: (62, 14), 8: (68, 15), 9: (75, 16), 10: (80, 16), 11: (90, 18),
           12: (95, 18), 13: (100, 18), 14: (110, 20), 15: (115, 20), 16: (125, 22)},
    "62": {0: (30, 9), 1: (32, 10), 2: (35, 11), 3: (40, 12), 4: (47, 14), 5: (52, 15),
           6: (62, 16), 7: (72, 17), 8: (80, 18), 9: (85, 19), 10: (90, 20), 11: (100, 21),
           12: (110, 22), 13: (120, 23), 14: (125, 24), 15: (130, 25), 16: (140, 26),
           17: (150, 28), 18: (160, 30), 19: (170, 32), 20: (180, 34)},
    "63": {0: (35, 11), 1: (37, 12), 2: (42, 13), 3: (47, 14), 4: (52, 15), 5: (62, 17),
           6: (72, 19), 7: (80, 21), 8: (90, 23), 9: (100, 25), 10: (110, 27), 11: (120, 29),
           12: (130, 31), 13: (140, 33), 14: (150, 35), 15: (160, 37), 16: (170, 39)},
}
# ISO 355 (metric tapered roller bearings): bore code -> (D, T) [mm]
_ISO355 = {
    "302": {4: (47, 15.25), 5: (52, 16.25), 6: (62, 17.25), 7: (72, 18.25), 8: (80, 19.75),
            9: (85, 20.75), 10: (90, 21.75), 11: (100, 22.75), 12: (110, 23.75),
            13: (120, 24.75), 14: (125, 26.25), 15: (130, 27.25), 16: (140, 28.25)},
    "320": {5: (47, 15), 6: (55, 17), 7: (62, 18), 8: (68, 19), 9: (75, 20), 10: (80, 20),
            11: (90, 23), 12: (95, 23), 13: (100, 23), 14: (110, 25), 15: (115, 25),
            16: (125, 29)},
    "330": {5: (47, 17), 6: (55, 20), 7: (62, 21), 8: (68, 22), 9: (75, 24), 10: (80, 24),
            11: (90, 27), 12: (95, 27), 13: (100, 27), 14: (110, 31), 15: (115, 31),
            16: (125, 36)},
}
#: series prefix -> (bearing kind, table, dimension series); cylindrical roller bearings
#: (NU, NJ, NUP, N) share the ISO 15 dimensions of the ball series with the same digits
SERIES = {"60": ("ball", _ISO15["60"]), "62": ("ball", _ISO15["62"]),
          "63": ("ball", _ISO15["63"]), "302": ("tapered", _ISO355["302"]),
          "320": ("tapered", _ISO355["320"]), "330": ("tapered", _ISO355["330"])}
for _p in ("NU", "NJ", "NUP", "N"):
    for _s in ("2", "3", "10"):
        SERIES[f"{_p}{_s}"] = ("cylindrical", _ISO15["60" if _s == "10" else "6" + _s])

_DESIGNATION = re.compile(r"\s*(NUP|NU|NJ|N)?(\d{3,5})([A-Z0-9]*)(?:[\s/-].*)?\s*$")


def _bore_of_code(code: int) -> float:
    return {0: 10.0, 1: 12.0, 2: 15.0, 3: 17.0}.get(code, 5.0 * code)


@dataclass(frozen=True)
class BoundaryDimensions:
    """A catalogue bearing: kind ("ball", "cylindrical", "tapered"), d, D, B [m]."""
    designation: str
    kind: str
    d: float
    D: float
    B: float


def boundary_dimensions(designation: str, path: str = "designation") -> BoundaryDimensions:
    """The ISO 15 / ISO 355 boundary dimensions of ``designation`` (e.g. "6210-2Z", "33014",
    "NU 210 E"); ConfigError naming ``path`` and the series known otherwise."""
    m = _DESIGNATION.match(designation.replace("NU ", "NU").replace("NJ ", "NJ"))
    if m is not None:
        prefix, digits = m.group(1) or "", m.group(2)
        series, code = prefix + digits[:-2], int(digits[-2:])
        if series in SERIES and code in SERIES[series][1]:
            kind, table = SERIES[series]
            D, B = table[code]
            return BoundaryDimensions(designation, kind, _bore_of_code(code) / 1e3,
                                      D / 1e3, B / 1e3)
    known = ", ".join(sorted({f"{k}xx" for k in SERIES}))
    raise ConfigError(path, f"{designation!r} is not a designation of the built-in ISO 15 / "
                      f"ISO 355 table (series {known}); give the boundary dimensions d, D, B "
                      "and the type instead, or the element set")


def bearing_kind(bearing_type: str) -> str:
    """"ball", "cylindrical" or "tapered" from a REXS ``bearing_type`` or a scene type."""
    t = bearing_type.lower()
    if "taper" in t:
        return "tapered"
    if "ball" in t:
        return "ball"
    return "cylindrical"


@dataclass(frozen=True)
class ElementSet:
    """The rolling elements of one row, SI units; ``assumed`` names the values the rule set."""
    kind: str                   # "ball", "cylindrical", "tapered"
    count: int
    element_diameter: float     # D_w [m]
    pitch_diameter: float       # d_m [m]
    element_length: float       # effective roller length l [m] (0 for balls)
    contact_angle: float        # [deg]
    inner_conformity: float     # f_i = r_i / D_w (balls)
    outer_conformity: float     # f_o = r_o / D_w (balls)
    assumed: tuple[str, ...] = ()


def element_set(kind: str, d: float, D: float, B: float, *, count: int | None = None,
                element_diameter: float | None = None, pitch_diameter: float | None = None,
                element_length: float | None = None,
                contact_angle: float | None = None) -> ElementSet:
    """The element set from the boundary dimensions by the rule of the module docstring;
    any value given is kept, every value the rule supplies is listed in ``assumed``."""
    assumed = []

    def pick(name, given, rule):
        if given is not None:
            return given
        assumed.append(name)
        return rule

    dm = pick("pitch_diameter", pitch_diameter, 0.5 * (d + D))
    factor = {"ball": 0.3, "cylindrical": 0.25, "tapered": 0.22}[kind]
    dw = pick("element_diameter", element_diameter, factor * (D - d))
    if kind == "ball":
        length = 0.0
        z_rule = int(math.floor(math.radians(CONRAD_FILL_DEG) / (2 * math.asin(dw / dm)))) + 1
    else:
        length = pick("element_length", element_length, (0.6 if kind == "cylindrical" else 0.55) * B)
        z_rule = int(math.floor(math.pi * dm / (1.25 * dw)))
    z = pick("elements", count, z_rule)
    alpha = pick("contact_angle", contact_angle, 12.0 if kind == "tapered" else 0.0)
    return ElementSet(kind, int(z), float(dw), float(dm), float(length), float(alpha),
                      0.52, 0.53, tuple(assumed))
