"""On-disk cache of expensive, immutable artifacts keyed by content hash + package version.

An entry is a folder ``<cache_dir>/<kind>-<20 hex digits>`` (the key, :func:`cache_key`).
It is built in a temporary folder ``.<key>.<random>`` next to it; :func:`publish_entry`
writes the manifest ``vibrogear-entry.json`` (key, version, SHA-256 of every file) *last*,
fsynced, and renames the folder into place atomically.  :func:`open_entry` returns an entry
only if its manifest matches its files; a corrupted, truncated, tampered or half-written
entry is removed with a warning and the caller rebuilds it.  :func:`clear_cache` deletes
only folders that look like its own entries (key pattern and manifest, or its temporary
folders); anything else in the cache folder is left alone.
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any

from .version import __version__
from .config.base import ConfigError

__all__ = ["cache_dir", "cache_key", "entry_dir", "clear_cache", "cache_info", "publish_entry",
           "open_entry", "discard_entry", "new_workspace", "MANIFEST", "KEY_RE"]

log = logging.getLogger(__name__)

#: the file written last into every entry: key, version and a checksum per file
MANIFEST = "vibrogear-entry.json"
#: an entry folder's name: ``<kind>-<20 hex digits>``
KEY_RE = re.compile(r"[a-z][a-z0-9]*(?:-[a-z0-9]+)*-[0-9a-f]{20}")
_TMP_RE = re.compile(r"\.(" + KEY_RE.pattern + r")\.[A-Za-z0-9_]+")


def cache_dir() -> Path:
    """The cache folder (``$VIBROGEAR_CACHE_DIR``, default ``~/.cache/vibrogear``); a
    ConfigError when that path exists and is not a folder."""
    d = Path(os.environ.get("VIBROGEAR_CACHE_DIR", Path.home() / ".cache" / "vibrogear"))
    if d.exists() and not d.is_dir():
        raise ConfigError("VIBROGEAR_CACHE_DIR", f"the cache folder {d} exists and is not a "
                          "folder: remove it or point VIBROGEAR_CACHE_DIR elsewhere")
    return d


def cache_key(kind: str, config: Any) -> str:
    """``<kind>-<hash>``: the hash covers ``config`` (JSON-serialisable, e.g.
    dataclasses.asdict) and the package version; entries of different kinds built from one
    config share the hash."""
    payload = json.dumps({"version": __version__, "config": config}, sort_keys=True, default=repr)
    return f"{kind}-{hashlib.sha256(payload.encode()).hexdigest()[:20]}"


def entry_dir(key: str) -> Path:
    """Folder of one cache entry (its parent created; the entry itself is published by
    :func:`publish_entry`)."""
    d = cache_dir()
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError("VIBROGEAR_CACHE_DIR", f"cannot create the cache folder {d}: "
                          f"{exc.strerror or exc}") from None
    return d / key


def new_workspace(key: str) -> Path:
    """A fresh temporary folder in the cache folder to build entry ``key`` in."""
    return Path(tempfile.mkdtemp(prefix=f".{key}.", dir=entry_dir(key).parent))


def _digest(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _files(folder: Path) -> dict[str, Path]:
    return {p.relative_to(folder).as_posix(): p for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name != MANIFEST}


def publish_entry(tmp: Path, key: str) -> Path:
    """Write the manifest of the finished entry in ``tmp`` (last, fsynced) and rename it into
    place; a concurrent winner is kept.  Returns the entry folder."""
    manifest = {"key": key, "version": __version__,
                "files": {name: _digest(p) for name, p in _files(tmp).items()}}
    fd = os.open(tmp / MANIFEST, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    with os.fdopen(fd, "w") as fh:
        json.dump(manifest, fh, indent=1)
        fh.flush()
        os.fsync(fh.fileno())
    final = entry_dir(key)
    try:
        os.rename(tmp, final)
    except OSError:
        if open_entry(key) is None:            # a broken entry in the way: replace it
            try:
                os.rename(tmp, final)
                return final
            except OSError:
                pass
        shutil.rmtree(tmp, ignore_errors=True)
    return final


def _problem(folder: Path, key: str) -> str | None:
    """Why ``folder`` is not a valid entry ``key``, or None."""
    try:
        manifest = json.loads((folder / MANIFEST).read_text())
    except FileNotFoundError:
        return "no manifest (unfinished or written by an older version)"
    except (OSError, ValueError) as exc:
        return f"unreadable manifest ({exc})"
    if not isinstance(manifest, dict) or manifest.get("key") != key \
            or not isinstance(manifest.get("files"), dict):
        return "manifest of another entry or malformed"
    files = _files(folder)
    if set(files) != set(manifest["files"]):
        missing = sorted(set(manifest["files"]) - set(files))
        extra = sorted(set(files) - set(manifest["files"]))
        return f"files missing {missing} or unexpected {extra}"
    for name, p in files.items():
        if _digest(p) != manifest["files"][name]:
            return f"checksum mismatch in {name} (truncated or modified)"
    return None


def discard_entry(key: str, why: str) -> None:
    """Remove entry ``key`` with a warning saying why (it is rebuilt by the caller)."""
    folder = entry_dir(key)
    log.warning("cache entry %s is invalid (%s); removing it and rebuilding", folder, why)
    trash = folder.with_name(f".{key}.discarded{os.getpid()}")
    try:
        os.rename(folder, trash)
    except OSError:
        trash = folder
    shutil.rmtree(trash, ignore_errors=True)
    if trash.exists() or folder.exists():
        raise ConfigError("VIBROGEAR_CACHE_DIR", f"cannot remove the invalid cache entry {folder}")


def open_entry(key: str) -> Path | None:
    """The folder of entry ``key`` if it exists and its files match its manifest; None if
    there is no entry or it was invalid (then it is removed with a warning)."""
    folder = entry_dir(key)
    if not folder.exists() and not folder.is_symlink():
        return None
    why = "not a folder" if not folder.is_dir() else _problem(folder, key)
    if why is None:
        return folder
    if not folder.is_dir():
        log.warning("cache entry %s is invalid (%s); removing it and rebuilding", folder, why)
        folder.unlink(missing_ok=True)
        return None
    discard_entry(key, why)
    return None


def _own(child: Path) -> bool:
    """Whether ``child`` of the cache folder is one of this module's entries or workspaces."""
    if _TMP_RE.fullmatch(child.name):
        return child.is_dir() and not child.is_symlink()
    if not KEY_RE.fullmatch(child.name) or not child.is_dir() or child.is_symlink():
        return False
    names = {p.name for p in child.iterdir()}
    # entries of earlier versions carry meta.json or mesh.json and no manifest
    return bool(names & {MANIFEST, "meta.json", "mesh.json"})


def clear_cache() -> tuple[int, int]:
    """Delete this package's entries (and unfinished workspaces) from the cache folder;
    returns (entries removed, other files and folders left alone)."""
    d = cache_dir()
    if not d.is_dir():
        return 0, 0
    n = kept = 0
    for child in sorted(d.iterdir()):
        if _own(child):
            shutil.rmtree(child, ignore_errors=True)
            n += 1
        else:
            kept += 1
    return n, kept


def cache_info() -> dict:
    """Number of this package's entries in the cache folder and their size in bytes."""
    d = cache_dir()
    entries = [c for c in d.iterdir() if _own(c)] if d.is_dir() else []
    size = sum(p.stat().st_size for c in entries for p in c.rglob("*") if p.is_file())
    return {"folder": str(d), "entries": len(entries), "bytes": size}
