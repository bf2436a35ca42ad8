"""Period-n branches started from a sweep (``[continuation] from_sweep = true``).

A sweep point classified period-n carries the state of its settled orbit at phase 0
(``u_end``): shooting over n excitation periods converges onto that orbit at once, and
pseudo-arclength continuation traces its branch both ways from there until it ends
(leaves the range, a grazing, a rejoin, the point budget), each half with its reason.

Windows: per sweep direction, maximal runs of consecutive good points with the same
period n >= 1.  Two windows are one orbit family when they have the same n, overlap in the
parameter and their maxima agree within ``rel_tol`` at a common point (the up and the down
sweep on the same orbit); the window's middle point starts it.  A window whose orbit an
existing branch of the same n already passes through (:func:`on_branch`: its maximum
near the branch's, linearly interpolated at the same parameter) is not traced again.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Window", "period_windows", "branch_value_at", "on_branch"]


@dataclass(frozen=True, eq=False)
class Window:
    n: int                     # period (excitation periods)
    direction: str             # sweep direction it came from
    lo: float                  # parameter range of the window
    hi: float
    param: float               # its middle point: the start
    u0: np.ndarray             # the settled orbit's state at phase 0 there
    qmax: float                # the maximum of the monitored deformation there
    points: int                # sweep points in the window
    params: np.ndarray         # the window's points (param, qmax) for the overlap test
    qmaxs: np.ndarray


def _runs(ok_n: np.ndarray):
    """(start, stop) of maximal runs of equal positive values in ``ok_n``."""
    k = 0
    while k < ok_n.size:
        if ok_n[k] <= 0:
            k += 1
            continue
        j = k
        while j + 1 < ok_n.size and ok_n[j + 1] == ok_n[k]:
            j += 1
        yield k, j + 1
        k = j + 1


def _same_family(a: Window, b: Window, rel_tol: float) -> bool:
    if a.n != b.n or a.hi < b.lo or b.hi < a.lo:
        return False
    for p, q in zip(a.params, a.qmaxs):
        k = np.flatnonzero(np.isclose(b.params, p, rtol=0, atol=1e-9 * (1 + abs(p))))
        if k.size and abs(b.qmaxs[k[0]] - q) <= rel_tol * max(abs(q), abs(b.qmaxs[k[0]])):
            return True
    return False


def period_windows(data: dict, n_states: int, *, rel_tol: float = 1e-3,
                   min_points: int = 1) -> list[Window]:
    """The distinct period-n windows of sweep arrays ``data`` (``sweep.npz``'s, or
    :func:`~vibrogear.report.sweep_files.sweep_arrays`): see the module docstring."""
    param = np.asarray(data["param"], dtype=float)
    if param.size == 0 or np.asarray(data["u_end"]).shape[-1] != n_states:
        return []
    direction = np.asarray(data["direction"]).astype(str)
    status = np.asarray(data.get("status", np.zeros(param.size)), dtype=int)
    period_n = np.where(status == 0, np.asarray(data["period_n"], dtype=int), 0)
    qmax = np.asarray(data["qmax"], dtype=float)
    u_end = np.asarray(data["u_end"], dtype=float)
    found: list[Window] = []
    for d in ("down", "up"):
        idx = np.flatnonzero(direction == d)
        idx = idx[np.argsort(param[idx], kind="stable")]
        for a, b in _runs(period_n[idx]):
            if b - a < min_points:
                continue
            sel = idx[a:b]
            mid = sel[(b - a) // 2]
            w = Window(int(period_n[mid]), d, float(param[sel].min()), float(param[sel].max()),
                       float(param[mid]), u_end[mid].copy(), float(qmax[mid]), int(b - a),
                       param[sel].copy(), qmax[sel].copy())
            if not any(_same_family(w, v, rel_tol) for v in found):
                found.append(w)
    return found


def branch_value_at(branch, param: float, quantity: str = "qmax"
                    ) -> list[tuple[float, bool, float]]:
    """(value, stable, change) of ``branch`` at ``param``, linearly interpolated between
    each pair of consecutive points (labelled points included) that brackets it (a
    folded branch can pass a parameter several times); stable: both points of the pair
    are; change: |difference of the value| across the pair (the interpolation's scale)."""
    pts = branch.points
    out = []
    for a, b in zip(pts[:-1], pts[1:]):
        lo, hi = sorted((a.param, b.param))
        va, vb = getattr(a, quantity), getattr(b, quantity)
        if lo <= param <= hi and hi > lo:
            s = (param - a.param) / (b.param - a.param)
            out.append((float(va + s * (vb - va)), bool(a.stable and b.stable),
                        float(abs(vb - va))))
        elif a.param == param:
            out.append((float(va), bool(a.stable), 0.0))
    if pts and pts[-1].param == param:
        out.append((float(getattr(pts[-1], quantity)), bool(pts[-1].stable), 0.0))
    return out


def on_branch(branches, n: int, param: float, qmax: float, rel_tol: float) -> bool:
    """Whether a branch of period ``n`` passes through (param, qmax): within rel_tol of
    the value, or within a quarter of the value's change across the bracketing pair of
    points (linear interpolation between coarse points is no better than that)."""
    return any(abs(v - qmax) <= max(rel_tol * max(abs(v), abs(qmax)), 0.25 * dv)
               for br in branches if br.n_periods == n
               for v, _, dv in branch_value_at(br, param))
