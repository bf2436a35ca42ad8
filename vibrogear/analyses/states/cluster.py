"""The settled motions of one parameter value grouped into attractors, with their basins
(the rule, its reasons and the evidence behind it: docs/states.md).

* **Periodic** motions (the sweep point's period n > 0) are one attractor when they have the
  same n and their last n stroboscopic states (the cycle) agree after a cyclic shift: the
  largest difference, each block (positions, velocities) divided by its largest |value| over
  all cycles at this parameter value (as the period test scales), at most ``cluster_tol``;
  a motion joins the first such attractor.
* **Non-periodic** motions (quasi-periodic, chaotic, aperiodic and "not settled" by the
  budget alone: one family, since a short record of one chaotic attractor is classed any of
  these ways by chance; "not settled" with an exponent below 0 only with its own kind) are
  one attractor when every test of :func:`non_periodic_score` passes:
  exponents within 3 combined standard errors; stroboscopic clouds not told apart by the
  two-sample Kolmogorov-Smirnov test at :data:`CLOUD_ALPHA`; ranges [qmin, qmax] sharing
  :data:`RANGE_OVERLAP` of their union; impacts and rattle per mesh within the Welch t
  quantile of :data:`LEVEL` times their batch-means errors plus ``stat_tol`` of the largest
  value here.  A motion joins the closest attractor it agrees with (smallest score).  A
  group is then split where its qmin or qmax fall into two clumps (:func:`split_by_extrema`:
  distinct tori whose other statistics agree within their errors).  Its extrema are the
  envelope of its members', its exponent their mean, its class :func:`group_class`.

Grouping runs in start order: the result does not depend on how the starts were split over
workers.  The basin fraction of an attractor is k / N_ok (k starts end there, N_ok starts
settled without an integrator failure) with its Wilson 95 % score interval
(``scipy.stats.binomtest``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import binomtest, ks_2samp, norm
from scipy.stats import t as student_t

from ...solvers.sequential.motion import (APERIODIC, CHAOTIC, MOTION_LEGEND, NOT_SETTLED,
    QUASI_PERIODIC)
from ...solvers.sequential.record_metrics import batch_blocks
from .gaps import split_by_extrema

__all__ = ["Attractor", "cluster_point", "wilson", "mesh_keys", "interval_widths",
           "non_periodic_score", "shared_range", "group_class"]

#: two-sided level of one statistic's comparison: 3 standard deviations of a normal law
LEVEL = float(2.0 * norm.sf(3.0))
#: two stroboscopic clouds differ when the two-sample KS test rejects at this level (low:
#: correlated samples of a chaotic record make the test's p-values too small)
CLOUD_ALPHA = 1e-3
#: ... tested only where both records have at least this many samples
CLOUD_MIN = 8
#: two deformation ranges [qmin, qmax] must overlap over at least this fraction of their union
RANGE_OVERLAP = 0.5
#: the classes one non-periodic attractor's short records fall into (and :func:`_in_family`)
_FAMILY = frozenset((QUASI_PERIODIC, CHAOTIC, APERIODIC))
_Z95 = float(norm.isf(0.025))
#: a torus's record is classed chaotic (95 % interval above 0) at most this often
CHAOTIC_BY_CHANCE = 0.025
#: a group is chaotic when its chaotic members are this unlikely for a torus
CLASS_LEVEL = 0.01


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
    lyapunov: float = math.nan     # non-periodic: members' mean exponent, its 95 % interval
    lyapunov_ci: tuple = (math.nan, math.nan)
    member_classes: dict = field(default_factory=dict)   # class name: members (non-periodic)

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
                "seen_by_sweep": self.seen_by_sweep, "lyapunov": _num(self.lyapunov),
                "lyapunov_ci_95": [_num(c) for c in self.lyapunov_ci],
                "member_classes": dict(self.member_classes)}


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


def _blocks(r) -> int:
    """Batch-means blocks behind a record's ``_err`` values (its window: len(poincare))."""
    return batch_blocks(len(r.poincare))[1] if r.poincare is not None else 0


def _in_family(r) -> bool:
    """Quasi-periodic, chaotic or aperiodic; or "not settled" because the budget ran out
    while the exponent's interval does not lie below 0 (one that does still converges)."""
    c = int(r.motion_class)
    return c in _FAMILY or (c == NOT_SETTLED and not float(r.lyapunov_ci[1]) < 0.0)


def _sigma(r) -> float:
    """Standard error of a record's exponent (95 % half-width / 1.96; NaN: none)."""
    lo, hi = (float(c) for c in r.lyapunov_ci)
    return (hi - lo) / (2.0 * _Z95) if math.isfinite(lo) and math.isfinite(hi) else math.nan


def _ratio(a, ea, na, b, eb, nb, floor) -> float:
    """|a - b| over its allowance: the Welch t quantile of :data:`LEVEL` times the combined
    error (errors ``ea``, ``eb`` from ``na``, ``nb`` batch-means blocks) plus ``floor``
    (<= 1: they agree; NaN on both sides agrees, on one side does not)."""
    if not (math.isfinite(a) and math.isfinite(b)):
        return 0.0 if (math.isnan(a) and math.isnan(b)) else math.inf
    s2 = ea * ea + eb * eb
    crit = float(norm.isf(LEVEL / 2))                 # 3
    terms = [(e, n) for e, n in ((ea, na), (eb, nb)) if e > 0]
    if terms and all(n >= 2 for _, n in terms):       # Welch-Satterthwaite dof
        crit = float(student_t.isf(LEVEL / 2, s2 * s2 / sum(e ** 4 / (n - 1)
                                                               for e, n in terms)))
    allow = crit * math.sqrt(s2) + floor
    d = abs(a - b)
    return d / allow if allow > 0 else (0.0 if d == 0 else math.inf)


def shared_range(lo1: float, hi1: float, lo2: float, hi2: float) -> float:
    """The share of the union of [lo1, hi1] and [lo2, hi2] that both cover (1 for two equal
    points; NaN for NaN ends)."""
    union = max(hi1, hi2) - min(lo1, lo2)
    if not union > 0:
        return 1.0 if union == 0 else math.nan
    return max(0.0, min(hi1, hi2) - max(lo1, lo2)) / union


def non_periodic_score(a, b, meshes, floors, stat_tol: float) -> float:
    """How far non-periodic records ``a`` and ``b`` are from one attractor: the largest
    ratio of a test's difference to what it allows (module docstring); <= 1: one attractor,
    inf: classes that cannot be one.  ``floors``: per mesh the largest (impacts, rattle)
    over the records of this parameter value."""
    if a.motion_class != b.motion_class and not (_in_family(a) and _in_family(b)):
        return math.inf
    worst = 0.0
    sa, sb = _sigma(a), _sigma(b)
    if math.isfinite(sa) and math.isfinite(sb):
        worst = _ratio(a.lyapunov, sa, 0, b.lyapunov, sb, 0, 0.0)
    shared = shared_range(a.qmin, a.qmax, b.qmin, b.qmax)
    if math.isnan(shared):                              # NaN extrema
        return math.inf
    worst = max(worst, (1.0 - shared) / (1.0 - RANGE_OVERLAP))
    pa, pb = (np.asarray(r.poincare, dtype=float) for r in (a, b))
    pa, pb = pa[np.isfinite(pa)], pb[np.isfinite(pb)]
    if min(pa.size, pb.size) >= CLOUD_MIN:
        pv = float(ks_2samp(pa, pb, method="auto" if pa.size * pb.size <= 10_000
                            else "asymp").pvalue)
        worst = max(worst, math.log(max(pv, 1e-300)) / math.log(CLOUD_ALPHA))
    na, nb = _blocks(a), _blocks(b)
    ma, mb = _mesh_stats(a, meshes), _mesh_stats(b, meshes)
    for g in meshes:
        for k in (0, 1):
            worst = max(worst, _ratio(*ma[g][k], na, *mb[g][k], nb, stat_tol * floors[g][k]))
    return worst


def _pooled_exponent(members) -> tuple[float, tuple]:
    """The members' mean exponent and its 95 % interval from their standard errors (the
    sampling scatter only, not a bias of the finite-time estimate: the class is not read
    from it, :func:`group_class`)."""
    lam = np.array([r.lyapunov for r in members], float)
    sig = np.array([_sigma(r) for r in members], float)
    ok = np.isfinite(lam) & np.isfinite(sig)
    if not ok.any():
        return math.nan, (math.nan, math.nan)
    mean = float(lam[ok].mean())
    half = _Z95 * float(math.sqrt(np.sum(sig[ok] ** 2))) / int(ok.sum())
    return mean, (mean - half, mean + half)


def group_class(members) -> int:
    """The class of a group of non-periodic members: chaotic when more of them are classed
    chaotic than a quasi-periodic torus gives by chance (each record's 95 % interval lies
    above 0 at most :data:`CHAOTIC_BY_CHANCE` of the time; binomial test at
    :data:`CLASS_LEVEL`), else quasi-periodic when any member is; else the first's."""
    classes = [int(r.motion_class) for r in members]
    if not all(_in_family(r) for r in members):
        return classes[0]
    k = sum(c == CHAOTIC for c in classes)
    if k and binomtest(k, len(classes), CHAOTIC_BY_CHANCE,
                       alternative="greater").pvalue < CLASS_LEVEL:
        return CHAOTIC
    return QUASI_PERIODIC if any(c in (QUASI_PERIODIC, CHAOTIC) for c in classes) \
        else classes[0]


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
    stats = {r.index: _mesh_stats(r, meshes) for r in ok}    # per mesh (impacts, rattle)
    spread = {g: tuple(max(stats[r.index][g][k][0] for r in ok) for k in (0, 1))
              for g in meshes}
    found: list[tuple[Attractor, list]] = []        # (attractor, member records)

    def scaled(c):
        c = np.array(c, dtype=float)
        c[:, :m] /= sx
        c[:, m:] /= sv
        return c

    def same_cycle(rep, r) -> bool:
        if rep.period_n != r.period_n or rep.states is None or r.states is None:
            return False
        return _cycle_distance(scaled(rep.states), scaled(r.states)) <= cluster_tol

    for r in ok:
        if r.period_n > 0:
            home = next((members for _att, members in found if same_cycle(members[0], r)), None)
        else:                    # the closest attractor among those it agrees with
            scores = [(non_periodic_score(members[0], r, meshes, spread, stat_tol), j)
                      for j, (att, members) in enumerate(found) if att.period_n == 0]
            best = min(scores, default=(math.inf, -1))
            home = found[best[1]][1] if best[0] <= 1.0 else None
        if home is not None:
            home.append(r)
        else:
            found.append((Attractor(point, float(param), int(r.motion_class), int(r.period_n)),
                          [r]))
    parts = []
    for att, members in found:
        if att.period_n > 0:
            parts.append((att, members))
            continue
        for ms in split_by_extrema(members):
            parts.append((Attractor(point, float(param), int(ms[0].motion_class), 0), ms))
    out = []
    for att, members in parts:
        att.members = [int(r.index) for r in members]
        att.n_ok = len(ok)
        q0 = np.array([r.qmin for r in members])
        q1 = np.array([r.qmax for r in members])
        k = len(members)
        att.qmin, att.qmax = float(q0.mean()), float(q1.mean())
        if att.period_n == 0:           # the pooled record: envelope, exponent, class
            att.qmin, att.qmax = float(q0.min()), float(q1.max())
            att.lyapunov, att.lyapunov_ci = _pooled_exponent(members)
            att.motion_class = group_class(members)
            for r in members:
                name = MOTION_LEGEND[r.motion_class]
                att.member_classes[name] = att.member_classes.get(name, 0) + 1
        att.qmin_err = float(q0.std(ddof=1) / math.sqrt(k)) if k > 1 else 0.0
        att.qmax_err = float(q1.std(ddof=1) / math.sqrt(k)) if k > 1 else 0.0
        for g in meshes:
            st = [stats[r.index][g] for r in members]
            imp = np.array([s[0][0] for s in st])
            rat = np.array([s[1][0] for s in st])
            peaks = [r.metrics.get(f"max_force_{g}", math.nan) for r in members]
            att.metrics[g] = {"impacts": float(np.mean(imp)), "rattle": float(np.mean(rat)),
                              "max_force": float(np.nanmax(peaks)) if np.any(
                                  np.isfinite(peaks)) else math.nan,
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


