"""Closed form: the first bending frequency of a clamped-free Timoshenko beam (Huang 1961's
frequency equation, shear coefficient of Cowper for a rectangle unless given)."""
from __future__ import annotations

import math

from scipy.optimize import brentq

__all__ = ["timoshenko_cantilever_f1"]


def timoshenko_cantilever_f1(*, E, nu, rho, L, b, h, kappa=None):
    """First bending frequency (Hz) of a clamped-free Timoshenko beam bending across h."""
    A, I = b * h, b * h ** 3 / 12
    G = E / (2 * (1 + nu))
    kappa = 10 * (1 + nu) / (12 + 11 * nu) if kappa is None else kappa
    r2, s2 = I / (A * L ** 2), E * I / (kappa * G * A * L ** 2)

    def eq(bb):
        root = math.sqrt((r2 - s2) ** 2 + 4 / bb ** 2)
        al = math.sqrt(0.5 * (-(r2 + s2) + root))
        be = math.sqrt(0.5 * ((r2 + s2) + root))
        return (2 + (bb ** 2 * (r2 - s2) ** 2 + 2) * math.cosh(bb * al) * math.cos(bb * be)
                - bb * (r2 + s2) / math.sqrt(1 - bb ** 2 * r2 * s2) * math.sinh(bb * al)
                * math.sin(bb * be))

    bb = brentq(eq, 1.0, 5.0)          # b = sqrt(rho A L^4 omega^2 / (E I)); EB: b = 1.8751^2
    omega = bb * math.sqrt(E * I / (rho * A * L ** 4))
    return omega / (2 * math.pi)
