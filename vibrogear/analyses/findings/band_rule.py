"""How one rule of the findings becomes speed bands: the band record (:class:`Band`), the
rule's test per grid point and direction on the arrays of ``sweep.npz`` (:func:`test_mask`,
:func:`grid_masks`), the runs of points that pass (:func:`segments`), split into both
directions or one, with their evidence text (:func:`stat_text`) and how far past the
threshold they lie (:func:`margin_of`).  :mod:`.bands` states the rules (contact loss,
rattle, bearings, motion, hysteresis) and evaluates each through :func:`rule_bands`.
"""
from __future__ import annotations

import operator
from dataclasses import dataclass, field

import numpy as np

from ...config.numbers import fmt

__all__ = ["Band", "OPS", "test_mask", "grid_masks", "segments", "band_points", "stat_text",
           "margin_of", "rule_bands"]

#: the comparison operators a band may state
OPS = {">": operator.gt, ">=": operator.ge, "<": operator.lt, "<=": operator.le,
       "==": operator.eq}


@dataclass(frozen=True)
class Band:
    quantity: str
    where: str
    direction: str
    start: float
    stop: float
    severity: str
    metric: str
    op: str
    threshold: float
    evidence: str
    source: str = "sweep.npz"
    edge_err: float = 0.0
    points: int = 0
    extra: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {"quantity": self.quantity, "where": self.where, "direction": self.direction,
                "from": self.start, "to": self.stop, "severity": self.severity,
                "metric": self.metric, "op": self.op, "threshold": self.threshold,
                "evidence": self.evidence, "source": self.source, "edge_err": self.edge_err,
                "points": self.points, **self.extra}


def test_mask(values, op: str, threshold: float) -> np.ndarray:
    return OPS[op](np.asarray(values, float), float(threshold))


def grid_masks(arrays: dict, metric: str, op: str, threshold: float):
    """(grid, {direction: mask on the grid}) of ``metric op threshold`` per direction."""
    param = np.asarray(arrays["param"], float)
    direction = np.asarray(arrays.get("direction", np.full(param.size, "up")), str)
    ok = np.asarray(arrays.get("ok", np.ones(param.size, bool)), bool)
    grid = np.unique(param)
    passed = test_mask(arrays[metric], op, threshold) & ok
    masks = {}
    for d in ("up", "down"):
        sel = direction == d
        if not np.any(sel):
            continue
        m = np.zeros(grid.size, bool)
        m[np.searchsorted(grid, param[sel])] = passed[sel]
        masks[d] = m
    return grid, masks


def segments(mask) -> list[tuple[int, int]]:
    """(first, last) index of each run of True in ``mask``."""
    m = np.concatenate(([False], np.asarray(mask, bool), [False])).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1) - 1))


def _split_directions(masks: dict) -> dict[str, np.ndarray]:
    if len(masks) == 1:
        return dict(masks)
    up, down = masks["up"], masks["down"]
    return {"both": up & down, "up": up & ~down, "down": down & ~up}


def band_points(arrays, grid, direction: str, i0: int, i1: int) -> np.ndarray:
    """Indices into the file's points of the band [grid[i0], grid[i1]] in ``direction``."""
    param = np.asarray(arrays["param"], float)
    d = np.asarray(arrays.get("direction", np.full(param.size, "up")), str)
    sel = (param >= grid[i0]) & (param <= grid[i1]) & \
        np.asarray(arrays.get("ok", np.ones(param.size, bool)), bool)
    if direction in ("up", "down"):
        sel &= d == direction
    return np.flatnonzero(sel)


def stat_text(arrays, key, idx, digits=2, scale=1.0, unit="") -> str:
    """'lo–hi unit (± err)' of ``key`` over ``idx`` with its batch-means error."""
    v = np.asarray(arrays[key], float)[idx] * scale
    err = arrays.get(f"{key}_err")
    e = f" (± {fmt(float(np.max(np.asarray(err, float)[idx])) * scale, 1)})" \
        if err is not None and np.any(np.asarray(err, float)[idx] > 0) else ""
    u = f" {unit}" if unit else ""
    lo, hi = float(v.min()), float(v.max())
    txt = fmt(lo, digits) if np.isclose(lo, hi) else f"{fmt(lo, digits)}–{fmt(hi, digits)}"
    return f"{txt}{u}{e}"


def margin_of(values, op: str, threshold: float, kind: str = "relative") -> float:
    """How far the worst of ``values`` lies past ``threshold``: relative to the threshold
    (``(worst - t) / |t|`` for > and >=, ``(t - worst) / |t|`` for < and <=), or the plain
    difference for ``kind = "dB"`` (and a zero threshold); 0 for ==."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if v.size == 0 or op == "==":
        return 0.0
    d = float(np.max(v)) - threshold if op in (">", ">=") else threshold - float(np.min(v))
    return d if kind == "dB" or threshold == 0 else d / abs(threshold)


def rule_bands(arrays, rule: dict, evidence, *, param_unit: str) -> list[Band]:
    """The bands of one rule: ``rule`` has quantity, where, metric, op, threshold,
    severity (and optionally ``margin``: "relative" or "dB"); ``evidence(idx) -> str``
    describes the file's points ``idx`` of a band.  Each band carries its ``margin``
    (:func:`margin_of`) over its points."""
    if rule["metric"] not in arrays:
        return []
    grid, masks = grid_masks(arrays, rule["metric"], rule["op"], rule["threshold"])
    step = float(np.min(np.diff(grid))) if grid.size > 1 else 0.0
    kind = rule.get("margin", "relative")
    out = []
    for direction, mask in _split_directions(masks).items():
        for i0, i1 in segments(mask):
            idx = band_points(arrays, grid, direction, i0, i1)
            # a class or a period has no distance past its threshold: no margin
            extra = {} if rule["metric"].startswith(("period_n", "motion_class")) else {
                "margin": margin_of(np.asarray(arrays[rule["metric"]], float)[idx],
                                    rule["op"], float(rule["threshold"]), kind),
                "margin_unit": "dB" if kind == "dB" else "relative"}
            out.append(Band(rule["quantity"], rule["where"], direction, float(grid[i0]),
                            float(grid[i1]), rule["severity"], rule["metric"], rule["op"],
                            float(rule["threshold"]), evidence(idx), edge_err=step,
                            points=int(i1 - i0 + 1), extra={**extra, **rule.get("extra", {})}))
    return out
