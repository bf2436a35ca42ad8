"""On-disk cache of expensive, immutable artifacts keyed by content hash + package version."""
from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path
from typing import Any

from . import __version__

__all__ = ["cache_dir", "cache_key", "entry_dir", "clear_cache"]


def cache_dir() -> Path:
    return Path(os.environ.get("VIBROGEAR_CACHE_DIR", Path.home() / ".cache" / "vibrogear"))


def cache_key(kind: str, config: Any) -> str:
    """Hash of ``config`` (JSON-serialisable, e.g. dataclasses.asdict) + kind + version."""
    payload = json.dumps({"kind": kind, "version": __version__, "config": config},
                         sort_keys=True, default=repr)
    return f"{kind}-{hashlib.sha256(payload.encode()).hexdigest()[:20]}"


def entry_dir(key: str) -> Path:
    """Folder of one cache entry (created); write into a temp name and rename to publish."""
    d = cache_dir() / key
    d.parent.mkdir(parents=True, exist_ok=True)
    return d


def clear_cache() -> int:
    d = cache_dir()
    if not d.is_dir():
        return 0
    n = 0
    for child in d.iterdir():
        if child.is_dir():
            shutil.rmtree(child, ignore_errors=True)
        else:
            child.unlink(missing_ok=True)
        n += 1
    return n
