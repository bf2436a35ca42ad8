"""One run per output folder at a time.

A run holds an exclusive ``flock`` on ``OUT/.vibrogear.lock`` for its whole length; the file
says who holds it (pid, host, command, start time).  The kernel releases the lock when the
holder ends in any way, ``kill -9`` included, so a lock left by a killed run is stale by
construction: the next run takes it over.  A second run into a held folder is refused with
the holder named (exit 2), or waits with ``--wait``.  Under ``mpirun`` only rank 0 locks.
"""
from __future__ import annotations

import fcntl
import json
import os
import socket
import sys
import time
from pathlib import Path

__all__ = ["FolderInUse", "RunLock", "LOCK_NAME"]

LOCK_NAME = ".vibrogear.lock"


class FolderInUse(RuntimeError):
    """Another live run holds the output folder."""


class RunLock:
    """``with RunLock(out, wait=False):`` the folder's lock for the block's length."""

    def __init__(self, out: Path, *, wait: bool = False, poll_s: float = 0.5,
                 enabled: bool = True):
        self.path = Path(out) / LOCK_NAME
        self.wait, self.poll_s, self.enabled = wait, poll_s, enabled
        self._fd: int | None = None
        self._created = False

    def __enter__(self) -> "RunLock":
        if not self.enabled:
            return self
        self._created = not self.path.parent.exists()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if not self.wait:
                    holder = _holder(self.path)
                    os.close(fd)
                    raise FolderInUse(
                        f"output folder {self.path.parent}/ is in use by another run ({holder}); "
                        "wait for it, give another --out, or add --wait") from None
                time.sleep(self.poll_s)
        info = {"pid": os.getpid(), "host": socket.gethostname(),
                "command": " ".join(sys.argv), "started": time.strftime("%Y-%m-%dT%H:%M:%S")}
        os.ftruncate(fd, 0)
        os.pwrite(fd, json.dumps(info).encode(), 0)
        self._fd = fd
        return self

    def __exit__(self, *exc) -> None:
        if self._fd is not None:
            os.ftruncate(self._fd, 0)            # released: the file says no one holds it
            fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = None
            # a run that wrote nothing (refused input) leaves no folder it created
            folder = self.path.parent
            if self._created and [p.name for p in folder.iterdir()] == [LOCK_NAME]:
                self.path.unlink(missing_ok=True)
                try:
                    folder.rmdir()
                except OSError:
                    pass


def _holder(path: Path) -> str:
    """Who holds the lock, from the file it wrote."""
    try:
        info = json.loads(path.read_text() or "{}")
    except (OSError, ValueError):
        info = {}
    if not info:
        return "holder unknown"
    return (f"pid {info.get('pid')} on {info.get('host')}, started {info.get('started')}: "
            f"{info.get('command')}")
