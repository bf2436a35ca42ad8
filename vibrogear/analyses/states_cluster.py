"""The settled motions of one parameter value grouped into attractors, with their basins.

* **Periodic** motions (the sweep point's period n > 0) are one attractor when they have the
  same n and their last n stroboscopic states (the cycle) agree after a cyclic shift: the
  largest difference, each block (positions, velocities) divided by its largest |value| over
  all cycles at this parameter value (as the period test scales), at most ``cluster_tol``.
* **Non-periodic** motions are one attractor when they have the same class (quasi-periodic,
  chaotic, not settled, ...) and their statistics agree: the extrema of the monitored
  deformation and, per mesh, the impacts per period and the rattle energy, each within 3
  combined standard errors (the record's batch-means ``_err``) plus ``stat_tol`` times the
  statistic's spread over all starts at this parameter value.

Grouping is greedy in start order (a motion joins the first attractor it agrees with: the
result does not depend on how the starts were split over workers).  The basin fraction of
an attractor is k / N_ok (k starts end there, N_ok starts settled without an integrator
failure) with its Wilson 95 % score interval (``scipy.stats.binomtest``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import binomtest

from ..solvers.sequential.motion import MOTION_LEGEND

__all__ = ["Attractor", "cluster_point", "wilson", "mesh_keys", "interval_widths"]


def wilson(k: int, n: int) -> tuple[float, float]:
    """The Wilson 95 % score interval of a proportion k / n ((0, 1) for n = 0)."""
    if n <= 0:
        return 0.0, 1.0
    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=0.95, method="wilson")
    return float(ci.low), float(ci.high)


def mesh_keys(records) -> tuple[str, ...]:
    """The meshes (two-sided contacts) the records report metrics for, in order."""
    keys = []
    for r in records:
        for k in r.metrics:
            if k.startswith("impacts_drive_") and not k.endswith("_err"):
                name = k[len("impacts_drive_"):]
                if name not in keys:
                    keys.append(name)
    return tuple(keys)


@dataclass(eq=False)
class Attractor:
    """One attractor at one parameter value (``members``: the starts that end on it)."""
    point: int                     # grid index
    param: float
    motion_class: int              # MOTION_LEGEND code
    period_n: int                  # 0: not periodic
    members: list = field(default_factory=list)
    n_ok: int = 0                  # starts that settled at this parameter value
    qmin: float = math.nan         # monitored deformation (mean over members; refined orbit)
    qmax: float = math.nan
    qmin_err: float = math.nan     # standard error over members (non-periodic)
    qmax_err: float = math.nan
    metrics: dict = field(default_factory=dict)   # per mesh: impacts, rattle (mean, err)
    u0: np.ndarray | None = None   # a member's state at phase 0 (periodic: on the orbit)
    cycle: np.ndarray | None = None
    refined: bool = False          # qmin/qmax from the shot orbit (periodic)
    stable: bool | None = None     # from the shot orbit's Floquet multipliers
    max_multiplier: float = math.nan
    seen_by_sweep: bool | None = None

    @property
    def count(self) -> int:
        return len(self.members)

    @property
    def fraction(self) -> float:
        return self.count / self.n_ok if self.n_ok else math.nan

    @property
    def ci(self) -> tuple[float, float]:
        return wilson(self.count, self.n_ok)

    @property
    def class_name(self) -> str:
        return MOTION_LEGEND[self.motion_class]

    def summary(self, unit_scale: float = 1.0) -> dict:
        """The plain record of the findings engine (qmin/qmax times ``unit_scale``)."""
        lo, hi = self.ci
        return {"class": self.class_name, "period_n": int(self.period_n),
                "basin_fraction": self.fraction, "basin_ci_95": [lo, hi],
                "starts": self.count, "qmin": self.qmin * unit_scale,
                "qmax": self.qmax * unit_scale, "refined_by_shooting": self.refined,
                "stable": self.stable, "max_multiplier": _num(self.max_multiplier),
                "impacts_per_period": {k: v["impacts"] for k, v in self.metrics.items()},
                "impacts_per_period_err": {k: v["impacts_err"] for k, v in self.metrics.items()},
                "rattle": {k: v["rattle"] for k, v in self.metrics.items()},
                "seen_by_sweep": self.seen_by_sweep}


def _num(x):
    x = float(x)
    return x if math.isfinite(x) else None


def _stat(r, name: str) -> tuple[float, float]:
    v = r.metrics.get(name, math.nan)
    e = r.metrics.get(f"{name}_err", math.nan)
    return float(v), (float(e) if math.isfinite(e) else 0.0)


def _mesh_stats(r, meshes) -> dict:
    """{mesh: ((impacts, err), (rattle, err))} of one record."""
    out = {}
    for g in meshes:
        d, ed = _stat(r, f"impacts_drive_{g}")
        b, eb = _stat(r, f"impacts_back_{g}")
        out[g] = ((d + b, math.hypot(ed, eb)), _stat(r, f"rattle_{g}"))
    return out


def _cycle_distance(a: np.ndarray, b: np.ndarray) -> float:
    return min(float(np.max(np.abs(a - np.roll(b, s, axis=0)))) for s in range(a.shape[0]))


def cluster_point(records, point: int, param: float, *, n_modes: int, cluster_tol: float,
                  stat_tol: float) -> tuple[list[Attractor], int, int]:
    """(attractors, N_ok, N_failed) of the records of one parameter value (any order: they
    are grouped in start order, ``record.index``)."""
    recs = sorted(records, key=lambda r: r.index)
    ok = [r for r in recs if r.ok]
    meshes = mesh_keys(ok)
    m = n_modes
    cycles = [np.atleast_2d(r.states) for r in ok if r.period_n > 0 and r.states is not None]
    sx = max((float(np.max(np.abs(c[:, :m]))) for c in cycles), default=1.0) or 1.0
    sv = max((float(np.max(np.abs(c[:, m:]))) for c in cycles), default=1.0) or 1.0
    qspread = (max(r.qmax for r in ok) - min(r.qmin for r in ok)) if ok else 0.0
    spread = {g: (max(_mesh_stats(r, meshes)[g][0][0] for r in ok),
                  max(_mesh_stats(r, meshes)[g][1][0] for r in ok)) for g in meshes}
    found: list[tuple[Attractor, list]] = []        # (attractor, member records)

    def scaled(c):
        c = np.array(c, dtype=float)
        c[:, :m] /= sx
        c[:, m:] /= sv
        return c

    def agree(a: float, ea: float, b: float, eb: float, scale: float) -> bool:
        if not (math.isfinite(a) and math.isfinite(b)):
            return math.isnan(a) and math.isnan(b)
        return abs(a - b) <= 3.0 * math.hypot(ea, eb) + stat_tol * scale

    def same(rep, r) -> bool:
        if rep.period_n != r.period_n or rep.motion_class != r.motion_class:
            return False
        if r.period_n > 0:
            if rep.states is None or r.states is None:
                return False
            return _cycle_distance(scaled(rep.states), scaled(r.states)) <= cluster_tol
        if not (agree(rep.qmin, 0, r.qmin, 0, qspread) and agree(rep.qmax, 0, r.qmax, 0, qspread)):
            return False
        a, b = _mesh_stats(rep, meshes), _mesh_stats(r, meshes)
        return all(agree(*a[g][k], *b[g][k], spread[g][k]) for g in meshes for k in (0, 1))

    for r in ok:
        for att, members in found:
            if same(members[0], r):
                members.append(r)
                break
        else:
            found.append((Attractor(point, float(param), int(r.motion_class), int(r.period_n)),
                          [r]))
    out = []
    for att, members in found:
        att.members = [int(r.index) for r in members]
        att.n_ok = len(ok)
        q0 = np.array([r.qmin for r in members])
        q1 = np.array([r.qmax for r in members])
        att.qmin, att.qmax = float(q0.mean()), float(q1.mean())
        k = len(members)
        att.qmin_err = float(q0.std(ddof=1) / math.sqrt(k)) if k > 1 else 0.0
        att.qmax_err = float(q1.std(ddof=1) / math.sqrt(k)) if k > 1 else 0.0
        for g in meshes:
            st = [_mesh_stats(r, meshes)[g] for r in members]
            imp = np.array([s[0][0] for s in st])
            rat = np.array([s[1][0] for s in st])
            att.metrics[g] = {"impacts": float(np.mean(imp)), "rattle": float(np.mean(rat)),
                              "impacts_err": float(max(max(s[0][1] for s in st),
                                                       imp.std(ddof=1) / math.sqrt(k)
                                                       if k > 1 else 0.0))}
        att.u0 = np.array(members[0].u_end, dtype=float)
        if att.period_n > 0 and members[0].states is not None:
            att.cycle = np.array(members[0].states, dtype=float)
        out.append(att)
    out.sort(key=lambda a: -a.count)
    return out, len(ok), len(recs) - len(ok)


def interval_widths(attractors) -> float:
    """The widest basin interval among ``attractors`` (1 when there are none)."""
    return max((a.ci[1] - a.ci[0] for a in attractors), default=1.0)


