"""Resumable runs: append-as-you-go partial files with ONE reuse rule.

A partial file (JSON lines: a header with the run's *signature*, then one line per finished
item, each flushed and fsynced) is reused only if its signature equals the new run's:
everything that affects the items (the model's physics as a content hash, the grid, the
analysis settings, the integrator options, the package version).  Otherwise it is set aside
(renamed ``<name>.stale-<n>``, never deleted) and the run starts clean, saying why in
:attr:`PartialStore.note` and in the log.  A torn last line of a killed run is dropped.
Under MPI only the root process touches the file (the caller decides who that is).
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import os
from pathlib import Path

import numpy as np

from ..version import __version__

__all__ = ["fingerprint", "PartialStore", "signature_difference", "read_items"]

log = logging.getLogger(__name__)


def _feed(h, obj) -> None:
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        h.update(type(obj).__name__.encode())
        for f in dataclasses.fields(obj):
            h.update(f.name.encode())
            _feed(h, getattr(obj, f.name))
    elif isinstance(obj, np.ndarray):
        a = np.ascontiguousarray(obj)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    elif isinstance(obj, dict):
        for k in sorted(obj, key=str):
            h.update(str(k).encode())
            _feed(h, obj[k])
    elif isinstance(obj, (list, tuple)):
        h.update(f"seq{len(obj)}".encode())
        for v in obj:
            _feed(h, v)
    elif isinstance(obj, float):
        h.update(repr(obj).encode())
    else:
        h.update(repr(obj).encode())


def fingerprint(obj) -> str:
    """SHA-256 of the content of ``obj`` (dataclasses, arrays, scalars, containers)."""
    h = hashlib.sha256()
    _feed(h, obj)
    return h.hexdigest()


def _jsonable(v):
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        return {f.name: _jsonable(getattr(v, f.name)) for f in dataclasses.fields(v)}
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in sorted(v.items(), key=lambda kv: str(kv[0]))}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [_jsonable(x) for x in v]
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, (np.integer,)):
        return int(v)
    return v


def signature_difference(old: dict, new: dict, prefix: str = "") -> list[str]:
    """Signature entries whose values differ (what changed since the partial run), one
    level into tables: e.g. ``["physics", "settings.record_periods"]``."""
    out = []
    for k in sorted(set(old) | set(new)):
        a, b = old.get(k), new.get(k)
        if a == b:
            continue
        if isinstance(a, dict) and isinstance(b, dict) and not prefix:
            out += signature_difference(a, b, f"{k}.") or [k]
        else:
            out.append(prefix + k)
    return out


class PartialStore:
    """``store = PartialStore(path, signature)``; ``store.items``: the items of a matching
    partial file (else []); ``store.append(item)`` writes one item (a JSON-able dict);
    ``store.note``: what happened to an existing file ("" when there was none)."""

    def __init__(self, path, signature: dict):
        self.path = Path(path)
        self.signature = _jsonable({**signature, "version": __version__})
        self.items: list[dict] = []
        self.note = ""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if self.path.exists() and self.path.stat().st_size > 0:
            header, items = _read_lines(self.path)
            old = header.get("signature", {})
            if old == self.signature:
                self.items = items
                _truncate_torn_tail(self.path)
                self.note = f"resumed {len(items)} finished points from {self.path.name}"
                log.info(self.note)
                return
            aside = self._set_aside()
            changed = ", ".join(signature_difference(old, self.signature)) or "format"
            self.note = (f"{self.path.name} was written for a different run ({changed} "
                         f"changed): set aside as {aside.name}; starting clean")
            log.warning(self.note)
        self.path.unlink(missing_ok=True)
        self._append({"kind": "header", "signature": self.signature})

    def _set_aside(self) -> Path:
        n = 1
        while (aside := self.path.with_name(f"{self.path.name}.stale-{n}")).exists():
            n += 1
        os.replace(self.path, aside)
        return aside

    def _append(self, obj: dict) -> None:
        line = json.dumps(obj, allow_nan=False, separators=(",", ":")) + "\n"
        try:
            with open(self.path, "a", encoding="utf-8") as fh:
                _write_line(fh, line)
        except OSError as exc:          # name the file (a full disk leaves a torn line: cut
            raise OSError(exc.errno, exc.strerror, str(self.path)) from exc   # on resume)

    def append(self, item: dict) -> None:
        self._append({"kind": "point", **item})


def _write_line(fh, line: str) -> None:
    """The one place a partial file grows (a test injects ENOSPC / EIO here)."""
    fh.write(line)
    fh.flush()
    os.fsync(fh.fileno())


def _truncate_torn_tail(path: Path) -> None:
    """Cut a last line left incomplete by a kill, so that appending stays valid."""
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with open(path, "r+b") as fh:
            fh.truncate(data.rfind(b"\n") + 1)


def _read_lines(path: Path) -> tuple[dict, list[dict]]:
    header: dict = {}
    points: list[dict] = []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            if not line.endswith("\n"):
                break                      # torn last line of a killed run
            try:
                obj = json.loads(line)
            except json.JSONDecodeError:
                break
            if not isinstance(obj, dict):
                break
            if obj.get("kind") == "header":
                header = obj
            elif obj.get("kind") == "point":
                points.append(obj)
    return header, points


def read_items(path) -> list[dict]:
    """The items of a partial file, whatever its signature ([] if there is none)."""
    path = Path(path)
    return _read_lines(path)[1] if path.exists() else []
