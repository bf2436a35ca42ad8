"""A sweep point (:class:`~.sweep_point.PointRecord`) as JSON and back: the lines of a
resumable run's partial file (``sweep.partial.jsonl``, the operating map's and others').

Floats are kept exact (``repr`` round trip through JSON), NaN and infinities as null;
fields added after a file was written take their defaults when it is read back.
"""
from __future__ import annotations

import math

import numpy as np

from ...pipeline.files import finite_json
from .sweep_point import PointRecord

__all__ = ["record_to_json", "record_from_json", "json_number"]


def json_number(x):
    """A float for JSON: finite as it is, NaN and infinities as None."""
    return finite_json(float(x))


def _arr(a):
    return None if a is None else [json_number(v) for v in np.asarray(a, dtype=float).ravel()]


def _f(x) -> float:
    return math.nan if x is None else float(x)


def _a(x) -> np.ndarray:
    return np.array([_f(v) for v in x], dtype=float)


def record_to_json(r: PointRecord) -> dict:
    """A sweep point as JSON (floats exact, NaN as null)."""
    d = {"direction": r.direction, "index": int(r.index), "param": json_number(r.param),
         "qmin": json_number(r.qmin), "qmax": json_number(r.qmax),
         "poincare": _arr(r.poincare), "period_n": int(r.period_n),
         "impacts": json_number(r.impacts), "defect": json_number(r.defect),
         "clusters": int(r.clusters), "status": int(r.status), "message": r.message,
         "u_end": _arr(r.u_end), "steps": int(r.steps), "rejected": int(r.rejected),
         "rhs_calls": int(r.rhs_calls), "events": int(r.events),
         "wall_time": json_number(r.wall_time), "motion_class": int(r.motion_class),
         "lyapunov": json_number(r.lyapunov), "lyapunov_ci": _arr(r.lyapunov_ci),
         "transient_used": int(r.transient_used), "settled_by": r.settled_by,
         "metrics": {k: json_number(v) for k, v in r.metrics.items()},
         "timings": {k: json_number(v) for k, v in r.timings.items()},
         "u_end_t": json_number(r.u_end_t)}
    if r.states is not None:
        d["states_shape"] = list(np.shape(r.states))
        d["states"] = _arr(r.states)
    return d


def record_from_json(d: dict) -> PointRecord:
    states = None
    if d.get("states") is not None:
        states = _a(d["states"]).reshape(d["states_shape"])
    return PointRecord(
        direction=d["direction"], index=int(d["index"]), param=_f(d["param"]),
        qmin=_f(d["qmin"]), qmax=_f(d["qmax"]), poincare=_a(d["poincare"]),
        period_n=int(d["period_n"]), impacts=_f(d["impacts"]), defect=_f(d["defect"]),
        clusters=int(d["clusters"]), status=int(d["status"]), message=d["message"],
        u_end=_a(d["u_end"]), steps=int(d["steps"]), rejected=int(d["rejected"]),
        rhs_calls=int(d["rhs_calls"]), events=int(d["events"]),
        wall_time=_f(d["wall_time"]), states=states,
        motion_class=int(d.get("motion_class", 0)), lyapunov=_f(d.get("lyapunov")),
        lyapunov_ci=tuple(_a(d.get("lyapunov_ci") or [None, None])),
        transient_used=int(d.get("transient_used", 0)), settled_by=d.get("settled_by", ""),
        metrics={k: (int(v) if k.startswith(("period_n_", "motion_class_")) and v is not None
                     else _f(v)) for k, v in (d.get("metrics") or {}).items()},
        timings={k: _f(v) for k, v in (d.get("timings") or {}).items()},
        u_end_t=_f(d.get("u_end_t", 0.0)))
