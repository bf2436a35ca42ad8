"""A periodic sweep point checked against the stable continuation branches: the stable orbit
through its speed, shot from the branch points that bracket it, and the distance of its
extrema from the sweep's (shared by the gear-pair and the seed-scene agreement tests)."""
from __future__ import annotations

import numpy as np

from vibrogear.config.options import ShootingOptions
from vibrogear.solvers.periodic.shooting import shoot

__all__ = ["stable_orbits_through", "extrema_error"]


def _bracket(br_param, param):
    """Indices (a, b) of consecutive branch points around ``param``."""
    for a in range(br_param.size - 1):
        lo, hi = sorted((br_param[a], br_param[a + 1]))
        if lo <= param <= hi:
            yield a, a + 1


def stable_orbits_through(model, br: dict, n: int, p: float, options, tol: float,
                          max_multiplier: float = 1.0) -> list:
    """The stable period-``n`` orbits at ``p``, shot from the linear interpolation of each
    pair of consecutive points of ``branch.npz`` (``br``) around ``p`` of which one is
    stable; with ``max_multiplier`` > 1 also, from any pair, those whose largest |Floquet
    multiplier| is at most that (weakly unstable: a torus or a doubled orbit around them
    smaller than the sweep's resolution)."""
    found = []
    for b in np.unique(br["branch"][br["n_periods"] == n]):
        sel = np.flatnonzero(br["branch"] == b)
        for a, c in _bracket(br["param"][sel], p):
            a, c = sel[a], sel[c]
            if not (br["stable"][a] or br["stable"][c]) and max_multiplier <= 1.0:
                continue
            s = (p - br["param"][a]) / (br["param"][c] - br["param"][a])
            guess = (1 - s) * br["u0"][a] + s * br["u0"][c]
            orb = shoot(model, p, guess, n_periods=n, options=options,
                        shooting=ShootingOptions(tol=tol, max_iter=8))
            if orb.converged and (orb.stable or np.max(np.abs(orb.floquet)) <= max_multiplier):
                found.append(orb)
    return found


def extrema_error(found: list, sw: dict, k: int) -> float:
    """The smallest distance of an orbit's extrema from sweep point ``k``'s, relative to
    the point's largest |extremum|."""
    scale = max(abs(sw["qmax"][k]), abs(sw["qmin"][k]))
    return min(max(abs(o.monitor_max - sw["qmax"][k]), abs(o.monitor_min - sw["qmin"][k]))
               for o in found) / scale
