"""Atomic file writes: every output file appears whole or not at all.

A file is written to a temporary file beside it and renamed over it.  The temporary file
is made by :func:`tempfile.mkstemp`, which creates it readable by its owner only (0600);
it is given the mode a plain ``open()`` would have given a new file, 0666 less the umask
(0644 under the usual umask 022), so colleagues and a web server can read the results."""
from __future__ import annotations

import csv
import errno
import io
import math
import os
import tempfile
from pathlib import Path
from typing import Any

from ..config.base import ConfigError

__all__ = ["listed_paths", "atomic_write_bytes", "atomic_write_text", "atomic_write_csv", "atomic_write_npz",
           "atomic_copy", "new_file_mode", "finite_json",
           "check_output_dir"]


def _write(fh, data: bytes) -> None:
    """The one place bytes reach an output file (a test injects ENOSPC / EIO here)."""
    fh.write(data)
    fh.flush()
    os.fsync(fh.fileno())


def new_file_mode() -> int:
    """The mode ``open()`` gives a new file: 0666 less the process's umask (read from
    /proc, so that no other thread sees a changed umask; else set and restored)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return 0o666 & ~int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


def _temporary_beside(path: Path) -> tuple[int, str]:
    """A new temporary file in ``path``'s folder, with the mode of a new file."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.fchmod(fd, new_file_mode())
    except BaseException:
        os.close(fd)
        os.unlink(tmp)
        raise
    return fd, tmp


def atomic_write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file, fsync and an atomic rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = _temporary_beside(path)
    try:
        with os.fdopen(fd, "wb") as fh:
            _write(fh, data)
        os.replace(tmp, path)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.unlink(tmp)
        if isinstance(exc, OSError) and exc.filename is None:
            raise OSError(exc.errno, exc.strerror, str(path)) from exc   # name the file
        raise
    return path


def atomic_copy(src, dst) -> Path:
    """Copy the file ``src`` to ``dst`` atomically (temporary file beside ``dst`` + rename),
    with the mode of a new file."""
    import shutil

    dst = Path(dst)
    fd, tmp = _temporary_beside(dst)
    os.close(fd)
    try:
        shutil.copyfile(src, tmp)
        os.replace(tmp, dst)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return dst


def atomic_write_text(path, text: str) -> Path:
    return atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_npz(path, arrays: dict, *, compressed: bool = True) -> Path:
    """``arrays`` as one ``.npz`` (compressed unless told otherwise), written atomically."""
    import io

    import numpy as np

    buf = io.BytesIO()
    (np.savez_compressed if compressed else np.savez)(buf, **arrays)
    return atomic_write_bytes(path, buf.getvalue())


def atomic_write_csv(path, header, rows) -> Path:
    """Write a CSV file (``csv`` module dialect, CRLF line ends) atomically: ``header`` is
    the first row (none when None), then ``rows``."""
    buf = io.StringIO()
    w = csv.writer(buf)
    if header is not None:
        w.writerow(header)
    w.writerows(rows)
    return atomic_write_text(path, buf.getvalue())


def finite_json(obj: Any) -> Any:
    """``obj`` made JSON-safe: non-finite floats become None (JSON has no NaN/inf), numpy
    scalars become Python numbers, tuples become lists and dict keys strings."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k): finite_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite_json(v) for v in obj]
    if hasattr(obj, "item") and hasattr(obj, "dtype"):
        return finite_json(obj.item())
    return obj


def check_output_dir(path, what: str = "--out") -> Path:
    """``path`` as an output folder that can be created and written, or a ConfigError naming
    ``what``; creates nothing (so ``vibrogear check`` can run it before any output exists)."""
    if path is None or str(path).strip() == "":
        raise ConfigError(what, "empty path: give an output folder")
    p = Path(path)
    try:
        name_max = os.pathconf(".", "PC_NAME_MAX")
        path_max = os.pathconf(".", "PC_PATH_MAX")
    except (OSError, ValueError):
        name_max, path_max = 255, 4096
    for part in p.parts:
        if len(os.fsencode(part)) > name_max:
            raise ConfigError(what, f"a path component is {len(os.fsencode(part))} bytes long; "
                              f"the file system allows at most {name_max}: {part[:40]}...")
    if len(os.fsencode(str(p.absolute()))) > path_max - 64:
        raise ConfigError(what, f"path too long (the file system allows {path_max} bytes)")
    probe = p
    while True:
        try:
            if probe.exists() or probe.is_symlink():
                break
        except OSError as exc:
            raise ConfigError(what, f"{probe}: {exc.strerror or exc}") from None
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        kind = "a broken link" if probe.is_symlink() and not probe.exists() else "a file"
        if probe == p:
            raise ConfigError(what, f"{p} exists and is {kind}, not a folder")
        raise ConfigError(what, f"{probe} is {kind}, so {p} cannot be a folder under it")
    try:                                  # a real probe (permissions alone mislead root)
        os.rmdir(tempfile.mkdtemp(prefix=".vibrogear-probe.", dir=probe))
    except OSError as exc:
        raise ConfigError(what, f"cannot create folders in {probe}: "
                          f"{exc.strerror or os.strerror(errno.EACCES)}") from None
    return p


def listed_paths(files):
    """The paths in an analysis's ``files`` entry of ``summary.json`` (any nesting of dicts
    and lists of strings or path-likes), in order."""
    if isinstance(files, (str, os.PathLike)):
        yield os.fspath(files)
    elif isinstance(files, dict):
        for v in files.values():
            yield from listed_paths(v)
    elif isinstance(files, (list, tuple)):
        for v in files:
            yield from listed_paths(v)
