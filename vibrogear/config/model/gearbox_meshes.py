"""Gearbox scene schema, ``[[gearbox.gears]]`` and ``[[gearbox.meshes]]``: the gear wheels
(teeth, module, helix, blank inertia, free gears) and the meshes that pair them (mean
stiffness or ISO 6336-1 gear data, its variation as Fourier terms or a square wave, the
transmission error, damping and backlash), with the check that a stiffness series stays
positive over a mesh period (:func:`stiffness_wave_minimum`).  :mod:`.gearbox` holds the
``[gearbox]`` table that lists them; its docstring shows the keys in a scene."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..base import ConfigError, spec

__all__ = ["GearConfig", "MeshConfig", "stiffness_wave_minimum"]


def stiffness_wave_minimum(cos, sin=()) -> tuple[float, float]:
    """(min over a mesh period of k(t)/k_mean = 1 + sum_h a_h cos(h theta) + b_h sin(h theta),
    where: theta / 2 pi in [0, 1)): a grid of 64 points per harmonic (at least 256), the
    lowest refined by Newton steps on k' = 0 (the actual minimum, not a bound)."""
    H = max(len(cos), len(sin))
    if H == 0:
        return 1.0, 0.0
    a, b = np.zeros(H), np.zeros(H)
    a[:len(cos)], b[:len(sin)] = cos, sin
    h = np.arange(1, H + 1, dtype=float)
    theta = np.linspace(0.0, 2 * np.pi, max(256, 64 * H), endpoint=False)
    k = 1.0 + np.cos(np.outer(theta, h)) @ a + np.sin(np.outer(theta, h)) @ b
    t = float(theta[int(np.argmin(k))])
    best = float(k.min())
    for _ in range(8):
        c, sn = np.cos(h * t), np.sin(h * t)
        d1 = float(h @ (-a * sn + b * c))
        d2 = float((h * h) @ (-a * c - b * sn))
        if d2 <= 0.0:
            break
        t -= d1 / d2
        val = 1.0 + float(np.cos(h * t) @ a + np.sin(h * t) @ b)
        best = min(best, val)
    return best, (t / (2 * np.pi)) % 1.0


@dataclass(frozen=True, kw_only=True)
class GearConfig:
    name: str = spec()
    shaft: str = spec(doc="shaft name")
    position: float = spec(ge=0.0, doc="[m] along the shaft; must be a node")
    teeth: int = spec(ge=5, le=10_000)
    module: float = spec(gt=0.0, lt=1.0, doc="normal module [m]")
    helix_angle: float = spec(0.0, gt=-60.0, lt=60.0, doc="[deg]")
    width: float = spec(gt=0.0, doc="face width [m]")
    inner_diameter: float = spec(0.0, ge=0.0, doc="bore [m]")
    density: float | None = spec(None, gt=0.0, doc="[kg/m^3], default: the shaft's material")
    mass: float | None = spec(None, gt=0.0, doc="[kg]; with Id and Ip instead of the "
                              "pitch-diameter disc")
    Id: float | None = spec(None, ge=0.0, doc="diametral inertia [kg m^2]")
    Ip: float | None = spec(None, gt=0.0, doc="polar inertia [kg m^2]")
    free: bool = spec(False, doc="freely rotating on its own bearing (extra torsional DOF)")
    torsional_damping: float = spec(0.0, ge=0.0, doc="free gear: drag to its shaft [N m s/rad]")
    drag_torque: float = spec(0.0, ge=0.0, doc="free gear: steady drag torque of its bearing "
                              "[N m], opposing its spin relative to the shaft")

    @property
    def pitch_diameter(self) -> float:
        return self.module * self.teeth / math.cos(math.radians(self.helix_angle))

    def validate(self, path: str) -> None:
        given = [self.mass is not None, self.Id is not None, self.Ip is not None]
        if any(given) and not all(given):
            missing = [n for n, g in zip(("mass", "Id", "Ip"), given) if not g][0]
            raise ConfigError(f"{path}.{missing}", "missing: mass, Id and Ip go together "
                              "(or none: the inertia of the pitch-diameter disc)")
        if all(given) and self.density is not None:
            raise ConfigError(f"{path}.density", "give either density (geometric disc) or "
                              "mass, Id and Ip, not both")
        if self.drag_torque and not self.free:
            raise ConfigError(f"{path}.drag_torque", "only a free gear has a drag torque")
        if not self.inner_diameter < self.pitch_diameter:
            raise ConfigError(f"{path}.inner_diameter", f"must be < the pitch diameter "
                              f"{self.pitch_diameter:g} m, got {self.inner_diameter:g}")


@dataclass(frozen=True, kw_only=True)
class MeshConfig:
    name: str = spec()
    gear_a: str = spec(doc="driving gear of the pair")
    gear_b: str = spec(doc="driven gear of the pair")
    pressure_angle: float = spec(20.0, gt=0.0, lt=45.0, doc="normal pressure angle [deg]")
    hand: int = spec(1, choices=(1, -1), doc="helix hand of gear_a (helical pairs)")
    stiffness: float | str | None = spec(None, gt=0.0, le=1e13, doc="mean mesh stiffness "
                                         "[N/m] along the normal, or \"iso6336\" (from the "
                                         "gear data, ISO 6336-1 method B); or give "
                                         "stiffness_levels")
    stiffness_levels: tuple[float, ...] = spec((), max_len=2, gt=0.0, le=1e13, doc="instead "
                                               "of stiffness: [k_single, k_double] [N/m], the "
                                               "mesh stiffness with one and with two tooth "
                                               "pairs in contact (a square wave)")
    double_contact_share: float | None = spec(None, gt=0.0, lt=1.0, doc="with "
                                              "stiffness_levels: the share of the mesh period "
                                              "with two pairs in contact (default: eps_alpha "
                                              "- 1 of ISO 6336-1's contact ratio)")
    level_terms: int = spec(20, ge=1, le=50, doc="with stiffness_levels: Fourier terms of "
                            "the square wave (Fejer-weighted: no overshoot; the peak "
                            "stiffness error is reported)")
    excite: bool = spec(True, doc="false: a constant spring at the mean stiffness (no "
                        "stiffness variation, no transmission error): one source at a time")
    damping: float = spec(0.0, ge=0.0, doc="mesh damping while in contact [N s/m]")
    backlash: float = spec(ge=0.0, lt=0.01, doc="circumferential backlash on the line of action [m]")
    stiffness_cos: tuple[float, ...] = spec((), max_len=50, gt=-1.0, lt=1.0, doc="mesh "
                                            "stiffness harmonics of this mesh's own mesh "
                                            "frequency, relative to the mean (accepted while "
                                            "the series' minimum over a mesh period stays > 0)")
    stiffness_sin: tuple[float, ...] = spec((), max_len=50, gt=-1.0, lt=1.0, doc="as "
                                            "stiffness_cos, sine terms")
    te_cos: tuple[float, ...] = spec((), max_len=50, doc="transmission error harmonics of "
                                     "this mesh's own mesh frequency [m]")
    te_sin: tuple[float, ...] = spec((), max_len=50, doc="as te_cos, sine terms [m]")
    # gear data of ISO 6336-1 (used by stiffness = "iso6336", else only reported)
    profile_shift_a: float = spec(0.0, ge=-1.0, le=2.0, doc="profile shift coefficient x of "
                                  "gear_a [-]")
    profile_shift_b: float = spec(0.0, ge=-1.0, le=2.0, doc="x of gear_b [-]")
    face_width: float | None = spec(None, gt=0.0, doc="common face width b [m] (default: the "
                                    "smaller gear width)")
    addendum: float = spec(1.0, gt=0.0, le=2.0, doc="basic-rack addendum h_aP / m_n [-]")
    dedendum: float = spec(1.25, gt=0.0, le=2.0, doc="basic-rack dedendum h_fP / m_n [-]")
    web_ratio: float = spec(1.0, gt=0.0, le=10.0, doc="gear blank: web thickness / face width "
                            "b_s / b (1: solid)")
    rim_ratio: float = spec(10.0, gt=0.0, doc="gear blank: rim thickness / module s_R / m_n")
    line_load: float | None = spec(None, gt=0.0, doc="K_A F_t / b [N/m]; below 1e5 N/m "
                                   "(100 N/mm) ISO scales c' down (default: not applied)")
    iso_harmonics: int = spec(3, ge=0, le=50, doc="stiffness harmonics of the single/double "
                              "contact alternation used with stiffness = \"iso6336\"")

    @property
    def iso6336(self) -> bool:
        return isinstance(self.stiffness, str)

    def validate(self, path: str) -> None:
        if isinstance(self.stiffness, str) and self.stiffness != "iso6336":
            raise ConfigError(f"{path}.stiffness", f"expected a number [N/m] (> 0, <= 1e13) "
                              f"or \"iso6336\", got {self.stiffness!r}")
        if self.gear_a == self.gear_b:
            raise ConfigError(f"{path}.gear_b", "must differ from gear_a")
        if self.stiffness is None and not self.stiffness_levels:
            raise ConfigError(f"{path}.stiffness", "missing required key: give stiffness "
                              "(a number [N/m] or \"iso6336\") or stiffness_levels = "
                              "[k_single, k_double] [N/m]")
        if self.stiffness_levels:
            self._check_levels(path)
        elif self.double_contact_share is not None:
            raise ConfigError(f"{path}.double_contact_share", "goes with stiffness_levels "
                              "(the square wave's double-contact share)")
        low, where = stiffness_wave_minimum(self.stiffness_cos, self.stiffness_sin)
        if low <= 0.0:
            raise ConfigError(f"{path}.stiffness_cos", f"the mesh stiffness goes negative: "
                              f"its minimum over a mesh period is {low:.3g} x the mean (at "
                              f"{where:.3f} of the period); lower the harmonics")

    def _check_levels(self, path: str) -> None:
        p = f"{path}.stiffness_levels"
        if len(self.stiffness_levels) != 2:
            raise ConfigError(p, f"expected [k_single, k_double] (2 numbers, N/m), got "
                              f"{len(self.stiffness_levels)}")
        if self.stiffness is not None:
            raise ConfigError(p, "give the stiffness once: stiffness (mean, with "
                              "stiffness_cos/sin) or stiffness_levels, not both")
        if self.stiffness_cos or self.stiffness_sin:
            raise ConfigError(p, "give the stiffness variation once: stiffness_levels (a "
                              "square wave) or stiffness_cos/stiffness_sin (its Fourier "
                              "series with stiffness), not both")
        k1, k2 = self.stiffness_levels
        if k2 < k1:
            raise ConfigError(p, f"k_double (two pairs in contact) must be >= k_single, got "
                              f"[{k1:g}, {k2:g}] N/m")

    @property
    def has_excitation(self) -> bool:
        return any(self.stiffness_cos + self.stiffness_sin + self.te_cos + self.te_sin) or \
            bool(self.stiffness_levels and self.stiffness_levels[0] != self.stiffness_levels[1])

    @property
    def excitation_harmonics(self) -> int:
        """Harmonics of its own mesh frequency this mesh excites at (0: none, or excite =
        false): its stiffness terms (given, the square wave's level_terms, or ISO 6336's
        iso_harmonics) and its transmission-error terms."""
        if not self.excite:
            return 0
        n = max(len(self.te_cos), len(self.te_sin), len(self.stiffness_cos),
                len(self.stiffness_sin))
        if self.stiffness_levels:
            n = max(n, self.level_terms if self.has_excitation else 0)
        elif self.iso6336 and not (self.stiffness_cos or self.stiffness_sin):
            n = max(n, self.iso_harmonics)
        return n
