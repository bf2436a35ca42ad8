"""Shared builders for the rotor tests (not collected: no test_ prefix)."""
from __future__ import annotations

from vibrogear.config.base import build
from vibrogear.config.model.rotor import RotorConfig
from vibrogear.models.rotor.model import build_rotor_model

#: Friswell et al. (2010) steel: E = 211 GN/m^2, G = 81.2 GN/m^2, rho = 7810 kg/m^3
FRISWELL_STEEL = {"E": 211e9, "G": 81.2e9, "rho": 7810.0}


def rotor_from_dict(data: dict):
    return build_rotor_model(build(RotorConfig, data, "rotor"))


def friswell_two_disc(elements=6, *, kxx=1e6, kyy=1e6, kxy=0.0, c=0.0, left_disc_at=0.5):
    """Examples 5.9.1 / 5.9.2 / 5.9.4 / 5.9.5: 1.5 m shaft, 50 mm, discs at 0.5 (or 1/3 L)
    and 1.0 m (0.28 m and 0.35 m diameter, 70 mm thick), bearings at both ends."""
    return rotor_from_dict({
        "material": FRISWELL_STEEL,
        "sections": [{"length": 1.5, "outer_diameter": 0.05, "elements": elements}],
        "discs": [{"position": left_disc_at, "outer_diameter": 0.28, "inner_diameter": 0.05,
                   "width": 0.07},
                  {"position": 1.0, "outer_diameter": 0.35, "inner_diameter": 0.05,
                   "width": 0.07}],
        "bearings": [{"position": z, "kxx": kxx, "kyy": kyy, "kxy": kxy, "cxx": c, "cyy": c}
                     for z in (0.0, 1.5)]})


def friswell_overhung(elements=6):
    """Example 5.9.9: 1.5 m shaft, 50 mm, bearings (10 MN/m) at 0 and 1.0 m, disc (0.35 m
    diameter, 70 mm thick) at the free end 1.5 m."""
    return rotor_from_dict({
        "material": FRISWELL_STEEL,
        "sections": [{"length": 1.5, "outer_diameter": 0.05, "elements": elements}],
        "discs": [{"position": 1.5, "outer_diameter": 0.35, "inner_diameter": 0.05,
                   "width": 0.07}],
        "bearings": [{"position": z, "kxx": 1e7, "kyy": 1e7} for z in (0.0, 1.0)]})
