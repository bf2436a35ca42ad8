"""The exact backbone of the conservative impact pair: its nonlinear normal mode in closed form.

The conservative pair (damping and harmonic forcing removed, the static load f_m kept) is

    q'' + r(q) = 0,    r(q) = kappa q + g(q) - f_m,

with g the dead zone of half width b: g = (1 - kappa)(q - b) for q > b, (1 - kappa)(q + b)
for q < -b, 0 inside.  So r is piecewise linear with three regions, each of the form
r = k (q - c):

    region      interval      stiffness k   centre c
    lower       q < -b        1             f_m - (1 - kappa) b
    clearance   |q| <= b      kappa         f_m / kappa
    upper       q > b         1             f_m + (1 - kappa) b

With kappa > 0 every stiffness is positive, r is increasing and the potential
V(q) = int_0^q r is convex: the static state q_s is the one centre that lies in its own
region, and every energy level E > 0 above it (E = V(q) + q'^2 / 2 - V(q_s)) is one periodic
orbit between the turning points q_min < q_s < q_max, V(q_min) = V(q_max) = V(q_s) + E.

Derivation.  In a region V(q) = V_c + k (q - c)^2 / 2 (V_c fixed by continuity of V at the
region's ends), so at level L = V(q_s) + E the speed is |q'| = sqrt(k (R^2 - (q - c)^2)) with
R^2 = 2 (L - V_c) / k, and the time to cross [q_a, q_b] inside the region is

    t = (asin((q_b - c) / R) - asin((q_a - c) / R)) / sqrt(k).

A turning point in a region is c + R (above the static state) or c - R (below it).  The
period is twice the sum of the region times between q_min and q_max, and omega = 2 pi / T.
Without a static load (f_m = 0) the orbit is symmetric: omega = sqrt(kappa) up to the
amplitude A = b; beyond it the orbit crosses the clearance (V = kappa q^2 / 2, level
L = V(A), R_in = sqrt(2 L / kappa)) and turns in the upper region (c = (1 - kappa) b,
R_out = A - c), so T = 4 [asin(b / R_in) / sqrt(kappa) + pi / 2 - asin((b - c) / R_out)].
Nothing here
shares code with the solvers it checks.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["ImpactBackbone", "BackbonePoint"]


@dataclass(frozen=True)
class BackbonePoint:
    energy: float        # above the static state
    omega: float         # circular frequency of the orbit
    period: float
    q_min: float
    q_max: float

    @property
    def amplitude(self) -> float:
        """max |q| over the orbit."""
        return max(abs(self.q_min), abs(self.q_max))


@dataclass(frozen=True)
class ImpactBackbone:
    """The exact NNM of the conservative impact pair (see the module docstring)."""
    kappa: float
    b: float
    f_m: float = 0.0

    def __post_init__(self):
        if not (self.kappa > 0 and self.b >= 0):
            raise ValueError("need kappa > 0 and b >= 0")

    # ------------------------------------------------------------------ regions
    def _regions(self):
        k, b, f = self.kappa, self.b, self.f_m
        return ((-math.inf, -b, 1.0, f - (1 - k) * b),
                (-b, b, k, f / k),
                (b, math.inf, 1.0, f + (1 - k) * b))

    def potential(self, q: float) -> float:
        """V(q) = int_0^q r(s) ds (V(0) = 0)."""
        k, b, f = self.kappa, self.b, self.f_m
        inner = lambda s: 0.5 * k * s * s - f * s          # noqa: E731
        if -b <= q <= b:
            return inner(q)
        c1, c3 = self._regions()[0][3], self._regions()[2][3]
        if q > b:
            return inner(b) + 0.5 * (q - c3) ** 2 - 0.5 * (b - c3) ** 2
        return inner(-b) + 0.5 * (q - c1) ** 2 - 0.5 * (-b - c1) ** 2

    def _offsets(self):
        """(lo, hi, k, c, V_c) per region: V = V_c + k (q - c)^2 / 2 there."""
        out = []
        for lo, hi, k, c in self._regions():
            ref = hi if math.isinf(lo) else lo
            out.append((lo, hi, k, c, self.potential(ref) - 0.5 * k * (ref - c) ** 2))
        return out

    @property
    def static(self) -> float:
        """The static state q_s: the centre inside its own region."""
        for lo, hi, _, c in self._regions():
            if lo <= c <= hi:
                return c
        raise AssertionError("kappa > 0 has one static state")

    @property
    def linear_omega(self) -> float:
        """sqrt of the stiffness of the static state's region: the small-amplitude limit
        (q_s strictly inside a region; 1.0 where it sits on a boundary)."""
        qs = self.static
        for lo, hi, k, c in self._regions():
            if lo < qs < hi:
                return math.sqrt(k)
        return 1.0

    # ------------------------------------------------------------------ turning points
    def _turning(self, level: float, upper: bool) -> float:
        qs = self.static
        for lo, hi, k, c, vc in self._offsets():
            if level < vc:
                continue
            R = math.sqrt(2 * (level - vc) / k)
            q = c + R if upper else c - R
            if lo <= q <= hi and (q >= qs if upper else q <= qs):
                return q
        raise AssertionError("no turning point")          # V is convex and unbounded

    def at_energy(self, energy: float) -> BackbonePoint:
        """The orbit of energy ``energy`` > 0 above the static state."""
        if not energy > 0:
            raise ValueError("energy must be > 0")
        level = self.potential(self.static) + energy
        q_lo, q_hi = self._turning(level, False), self._turning(level, True)
        half = 0.0
        for lo, hi, k, c, vc in self._offsets():
            a, b = max(lo, q_lo), min(hi, q_hi)
            if b <= a:
                continue
            R = math.sqrt(max(2 * (level - vc) / k, 0.0))
            # at a turning point (q - c) / R = +-1 exactly: asin is taken there as +-pi/2,
            # not from the rounded quotient (asin(1 - eps) = pi/2 - sqrt(2 eps))
            hi_ang = math.pi / 2 if b == q_hi else math.asin(max(-1.0, min(1.0, (b - c) / R)))
            lo_ang = -math.pi / 2 if a == q_lo else math.asin(max(-1.0, min(1.0, (a - c) / R)))
            half += (hi_ang - lo_ang) / math.sqrt(k)
        T = 2 * half
        return BackbonePoint(energy=energy, omega=2 * math.pi / T, period=T, q_min=q_lo,
                             q_max=q_hi)

    def at_q_max(self, q_max: float) -> BackbonePoint:
        """The orbit whose upper turning point is ``q_max`` > q_s."""
        qs = self.static
        if not q_max > qs:
            raise ValueError("q_max must lie above the static state")
        return self.at_energy(self.potential(q_max) - self.potential(qs))

    def onset_energy(self) -> float:
        """The energy at which the orbit first reaches a region boundary (+-b)."""
        qs = self.static
        return min(self.potential(e) - self.potential(qs) for e in (-self.b, self.b)
                   if e != qs)
