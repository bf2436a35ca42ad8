"""Files of a sweep: ``sweep.npz``, ``sweep.csv`` and the append-as-you-go partial file.

* ``sweep.npz`` (DESIGN.md): ``param``, ``direction`` ("up"/"down"), ``qmin``, ``qmax``,
  ``poincare`` (points x samples), ``period_n`` (0 = not periodic), ``impacts`` (contact
  losses per excitation period), plus ``index``, ``status``, ``ok``, ``defect``,
  ``clusters``, ``u_end`` and the scalar error estimates.  No NaN/inf is ever written:
  failed points carry 0 placeholders and ``ok = False`` / ``status < 0``.
* ``sweep.csv`` repeats the per-point scalars; missing values are empty cells.
* ``sweep.partial.jsonl``: one JSON line per finished point (first line: a header with
  the sweep's signature), flushed and fsynced as each point completes, so that a killed
  sweep resumes with :func:`read_partial` -> ``sweep(..., done=...)`` and loses nothing.
  With parallel units only the coordinating process (rank 0 under MPI) writes it, in
  the order the points arrive.  Floats are written with ``repr`` precision (exact round trip); NaN is written as null.

All final files are written atomically (temporary file in the same folder + rename).
"""
from __future__ import annotations

import csv
import io
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from ..pipeline.executors import is_root
from ..solvers.sweep import PointRecord, SweepResult, sweep

__all__ = ["write_sweep", "sweep_arrays", "read_sweep_npz", "PartialWriter", "read_partial",
           "sweep_signature", "atomic_write_bytes", "PARTIAL_NAME", "resumable_sweep"]

PARTIAL_NAME = "sweep.partial.jsonl"
#: bumped when the meaning of a sweep's points changes (2: independent units, each
#: starting from u0), so that an older partial file is never resumed
SWEEP_SEMANTICS = 2
#: sweep keywords that do not change the results (left out of the signature)
NOT_IN_SIGNATURE = ("options", "u0", "workers")
CSV_COLUMNS = ("direction", "index", "param", "qmin", "qmax", "period_n", "impacts",
               "clusters", "defect", "status", "message", "wall_time")


def atomic_write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file and an atomic rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def _finite(a, fill=0.0) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    return np.where(np.isfinite(a), a, fill)


def _cell(x) -> str:
    if isinstance(x, (float, np.floating)):
        return repr(float(x)) if math.isfinite(x) else ""
    return str(x)


def sweep_arrays(result: SweepResult) -> dict:
    """The arrays that ``sweep.npz`` holds (NaN/inf replaced), as a plain dict."""
    ok = result.status == 0
    return dict(
        param=_finite(result.param), direction=np.asarray(result.direction, dtype="<U4"),
        qmin=_finite(result.qmin), qmax=_finite(result.qmax),
        poincare=_finite(result.poincare), period_n=np.asarray(result.period_n, np.int64),
        impacts=_finite(result.impacts), index=np.asarray(result.index, np.int64),
        status=np.asarray(result.status, np.int64), ok=ok,
        defect=_finite(result.defect), clusters=np.asarray(result.clusters, np.int64),
        u_end=_finite(result.u_end), point_wall=_finite(result.point_wall),
        message=np.asarray(result.message, dtype=str) if result.message else np.zeros(0, "<U1"),
        rtol=np.asarray(result.rtol, np.float64), atol=np.asarray(result.atol, np.float64),
        period_tol=np.asarray(result.period_tol, np.float64),
        param_name=np.asarray(result.param_name),
    )


def write_sweep(result: SweepResult, out_dir, *, stem: str = "sweep") -> dict:
    """Write ``stem.npz`` and ``stem.csv`` into ``out_dir``; returns {kind: path}."""
    out_dir = Path(out_dir)
    arrays = sweep_arrays(result)
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    npz = atomic_write_bytes(out_dir / f"{stem}.npz", buf.getvalue())
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    for k in range(result.param.size):
        w.writerow([_cell(v) for v in (
            str(result.direction[k]), int(result.index[k]), float(result.param[k]),
            float(result.qmin[k]), float(result.qmax[k]), int(result.period_n[k]),
            float(result.impacts[k]), int(result.clusters[k]), float(result.defect[k]),
            int(result.status[k]), result.message[k], float(result.point_wall[k]))])
    csv_path = atomic_write_bytes(out_dir / f"{stem}.csv", text.getvalue().encode())
    return {"npz": npz, "csv": csv_path}


def read_sweep_npz(path) -> dict:
    """The arrays of a written ``sweep.npz`` as a plain dict."""
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


# ---------------------------------------------------------------- partial (resume) file

def sweep_signature(model, params, **settings) -> dict:
    """What must match for a partial file to be resumed: the model's name, the grid and
    the sweep settings (the caller decides which; they must be JSON-serialisable; leave
    out ``workers``, which does not change the results)."""
    p = np.asarray(params, dtype=float).ravel()
    return {"semantics": SWEEP_SEMANTICS, "model": getattr(model, "name", str(model)),
            "n_states": int(model.n_states),
            "params": [repr(float(x)) for x in p],
            "settings": {k: _jsonable(v) for k, v in sorted(settings.items())}}


def _jsonable(v):
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, (np.floating, float)):
        return repr(float(v))
    if isinstance(v, (np.integer,)):
        return int(v)
    return v


def _num(x):
    x = float(x)
    return x if math.isfinite(x) else None


def _arr(a) -> list | None:
    if a is None:
        return None
    return [_num(v) for v in np.asarray(a, dtype=float).ravel()]


def _record_to_json(r: PointRecord) -> dict:
    d = {"direction": r.direction, "index": int(r.index), "param": _num(r.param),
         "qmin": _num(r.qmin), "qmax": _num(r.qmax), "poincare": _arr(r.poincare),
         "period_n": int(r.period_n), "impacts": _num(r.impacts), "defect": _num(r.defect),
         "clusters": int(r.clusters), "status": int(r.status), "message": r.message,
         "u_end": _arr(r.u_end), "steps": int(r.steps), "rejected": int(r.rejected),
         "rhs_calls": int(r.rhs_calls), "events": int(r.events),
         "wall_time": _num(r.wall_time)}
    if r.states is not None:
        d["states_shape"] = list(np.shape(r.states))
        d["states"] = _arr(r.states)
    return d


def _f(x) -> float:
    return math.nan if x is None else float(x)


def _a(x) -> np.ndarray:
    return np.array([_f(v) for v in x], dtype=float)


def _record_from_json(d: dict) -> PointRecord:
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
        wall_time=_f(d["wall_time"]), states=states)


class PartialWriter:
    """Append finished points to ``path`` (JSON lines); usable directly as the sweep
    callback: ``sweep(..., callback=PartialWriter(path, signature))``.

    A new file starts with a header line holding ``signature``; an existing file is
    appended to (its header must match, else ValueError).
    """

    def __init__(self, path, signature: dict | None = None):
        self.path = Path(path)
        self.signature = signature or {}
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if self.path.exists() and self.path.stat().st_size > 0:
            header, _ = _read_lines(self.path)
            if signature is not None and header.get("signature") != self.signature:
                raise ValueError(f"{self.path}: partial sweep file belongs to another sweep")
            _truncate_torn_tail(self.path)
        else:
            self._append({"kind": "header", "signature": self.signature})

    def _append(self, obj: dict) -> None:
        line = json.dumps(obj, allow_nan=False, separators=(",", ":")) + "\n"
        with open(self.path, "a", encoding="utf-8") as fh:
            fh.write(line)
            fh.flush()
            os.fsync(fh.fileno())

    def __call__(self, record: PointRecord) -> None:
        self._append({"kind": "point", **_record_to_json(record)})

    def remove(self) -> None:
        """Delete the partial file (after the final files are written)."""
        if self.path.exists():
            self.path.unlink()


def _truncate_torn_tail(path: Path) -> None:
    """Cut a last line left incomplete by a kill, so that appending stays valid."""
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        cut = data.rfind(b"\n") + 1
        with open(path, "r+b") as fh:
            fh.truncate(cut)


def _read_lines(path: Path) -> tuple[dict, list[dict]]:
    header: dict = {}
    points: list[dict] = []
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            if not line.endswith("\n"):
                break                      # torn last line of a killed run
            try:
                obj = json.loads(line)
            except json.JSONDecodeError:
                break
            if obj.get("kind") == "header":
                header = obj
            elif obj.get("kind") == "point":
                points.append(obj)
    return header, points


def read_partial(path, signature: dict | None = None) -> dict:
    """{(direction, index): PointRecord} from a partial file ({} if it does not exist).

    With ``signature``, a file written for another sweep raises ValueError.
    """
    path = Path(path)
    if not path.exists():
        return {}
    header, points = _read_lines(path)
    if signature is not None and header.get("signature") != signature:
        raise ValueError(f"{path}: partial sweep file belongs to another sweep")
    out = {}
    for d in points:
        r = _record_from_json(d)
        out[(r.direction, r.index)] = r
    return out


def resumable_sweep(model, params, out_dir, *, callback=None, keep_partial: bool = False,
                    **sweep_kw) -> tuple[SweepResult, dict]:
    """Run :func:`~vibrogear.solvers.sweep.sweep` (parallel units: ``segments``,
    ``workers``) writing each finished point to ``out_dir/sweep.partial.jsonl`` as it
    arrives, resuming from it if present (same signature; ``workers`` may differ), then
    write ``sweep.npz`` / ``sweep.csv`` and drop the partial file.  Returns
    (result, {kind: path}).  ``callback(record)`` is called after the point is saved.
    Under ``mpirun`` (collective) only rank 0 reads and writes files; every rank
    returns the same result.
    """
    opts = sweep_kw.get("options")
    settings = {k: v for k, v in sweep_kw.items() if k not in NOT_IN_SIGNATURE}
    if opts is not None:
        settings.update(rtol=opts.rtol, atol=opts.atol, max_steps=opts.max_steps)
    sig = sweep_signature(model, params, **settings)
    part = Path(out_dir) / PARTIAL_NAME
    root = is_root()
    done = read_partial(part, sig) if root else {}
    writer = PartialWriter(part, sig) if root else None

    def on_point(rec):
        writer(rec)
        return None if callback is None else callback(rec)

    result = sweep(model, params, callback=on_point, done=done, **sweep_kw)
    paths = {"npz": Path(out_dir) / "sweep.npz", "csv": Path(out_dir) / "sweep.csv"}
    if root:
        paths = write_sweep(result, out_dir)
        if not keep_partial and result.status_code != 2:
            writer.remove()
    return result, paths
