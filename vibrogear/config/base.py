"""Generic TOML -> frozen dataclass loading with validation.

A config section is a frozen dataclass whose fields carry their allowed range in
``field(metadata=...)``, built with :func:`spec`. :func:`build` turns a plain dict
(read from TOML) into the dataclass, checking unknown keys, missing keys, types,
finiteness and ranges, and naming the field path in every error.  Cross-field
checks live in a ``validate(self, path)`` method of the dataclass.
"""
from __future__ import annotations

import dataclasses
import difflib
import errno
import math
import os
import re
import stat
import types
import typing
from pathlib import Path
from typing import Any

from .errors import ConfigError, ErrorList

__all__ = ["ConfigError", "ErrorList", "spec", "build", "check", "as_data", "check_name",
           "read_toml_file", "expected_text", "NAME_MAX_LEN"]

#: longest name used as a file or folder name (scene.name)
NAME_MAX_LEN = 100
_NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9._+-]*")
#: largest scene file read (a scene is a few kB)
MAX_SCENE_BYTES = 10 * 2**20


_MISSING = dataclasses.MISSING


def spec(default: Any = _MISSING, *, gt: float | None = None, ge: float | None = None,
         lt: float | None = None, le: float | None = None, choices: tuple | None = None,
         min_len: int | None = None, max_len: int | None = None, doc: str = "") -> Any:
    """A dataclass field with an allowed range (gt/ge/lt/le), choices or length bounds."""
    meta = {"gt": gt, "ge": ge, "lt": lt, "le": le, "choices": choices,
            "min_len": min_len, "max_len": max_len, "doc": doc}
    if default is _MISSING:
        return dataclasses.field(metadata=meta)
    if isinstance(default, (list, dict, set)):
        raise TypeError("use tuples for defaults")
    return dataclasses.field(default=default, metadata=meta)


def _range_text(meta: dict) -> str:
    parts = []
    if meta.get("gt") is not None:
        parts.append(f"> {meta['gt']:g}")
    if meta.get("ge") is not None:
        parts.append(f">= {meta['ge']:g}")
    if meta.get("lt") is not None:
        parts.append(f"< {meta['lt']:g}")
    if meta.get("le") is not None:
        parts.append(f"<= {meta['le']:g}")
    return " and ".join(parts)


def check(value: float, meta: dict, path: str, shown: Any = None) -> None:
    """Raise ConfigError if a number lies outside the range in ``meta``."""
    ok = True
    if meta.get("gt") is not None and not value > meta["gt"]:
        ok = False
    if meta.get("ge") is not None and not value >= meta["ge"]:
        ok = False
    if meta.get("lt") is not None and not value < meta["lt"]:
        ok = False
    if meta.get("le") is not None and not value <= meta["le"]:
        ok = False
    if not ok:
        raise ConfigError(path, f"value {value if shown is None else shown!r} out of range: "
                          f"must be {_range_text(meta)}")


def _type_name(tp: Any) -> str:
    return getattr(tp, "__name__", str(tp))


def expected_text(tp: Any, meta: dict) -> str:
    """What a field accepts, in words: its type, range and choices ("a number > 0")."""
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        return " or ".join(expected_text(a, meta) for a in args if a is not type(None))
    if origin is tuple:
        item = expected_text(args[0], meta) if args else "values"
        lo, hi = meta.get("min_len"), meta.get("max_len")
        size = (f" of {lo} to {hi} entries" if lo is not None and hi is not None else
                f" of at least {lo} entries" if lo is not None else
                f" of at most {hi} entries" if hi is not None else "")
        return f"a list{size} of ({item})"
    if dataclasses.is_dataclass(tp):
        return f"a table (keys: {', '.join(f.name for f in dataclasses.fields(tp))})"
    rng = _range_text(meta)
    choices = meta.get("choices")
    base = {bool: "true or false", int: "an integer", float: "a number", str: "a string"}.get(
        tp, _type_name(tp))
    if choices:
        return f"one of {', '.join(map(repr, choices))}"
    return f"{base} {rng}" if rng else base


def _got(value: Any) -> str:
    kind = {str: "a string", bool: "a boolean", int: "an integer", float: "a number",
            list: "a list", dict: "a table"}.get(type(value), type(value).__name__)
    text = repr(value)
    return f"{kind} {text if len(text) <= 60 else text[:57] + '...'}"


def _type_error(path: str, tp: Any, meta: dict, value: Any) -> "ConfigError":
    return ConfigError(path, f"expected {expected_text(tp, meta)}, got {_got(value)}")


def _convert(value: Any, tp: Any, meta: dict, path: str) -> Any:
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        non_none = [a for a in args if a is not type(None)]
        if value is None and len(non_none) < len(args):
            return None
        if len(non_none) == 1:
            return _convert(value, non_none[0], meta, path)
        errors = []
        for a in non_none:
            try:
                return _convert(value, a, meta, path)
            except ConfigError as exc:
                errors.append(str(exc))
        raise ConfigError(path, "; ".join(errors))
    if origin is tuple:
        if not isinstance(value, (list, tuple)):
            raise _type_error(path, tp, meta, value)
        n = len(value)
        if meta.get("min_len") is not None and n < meta["min_len"]:
            raise ConfigError(path, f"needs at least {meta['min_len']} entries, got {n}")
        if meta.get("max_len") is not None and n > meta["max_len"]:
            raise ConfigError(path, f"allows at most {meta['max_len']} entries, got {n}")
        item_tp = args[0] if args else Any
        if len(args) == 2 and args[1] is Ellipsis or len(args) == 1:
            item_meta = {k: meta.get(k) for k in ("gt", "ge", "lt", "le", "choices")}
            errs, items = ErrorList(), []
            for i, v in enumerate(value):
                with errs.catch():
                    items.append(_convert(v, item_tp, item_meta, f"{path}[{i}]"))
            errs.raise_if()
            return tuple(items)
        if len(args) != n:
            raise ConfigError(path, f"expected exactly {len(args)} entries, got {n}")
        return tuple(_convert(v, a, {}, f"{path}[{i}]") for i, (v, a) in enumerate(zip(value, args)))
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, dict):
            raise _type_error(path, tp, meta, value)
        return build(tp, value, path)
    if tp is bool:
        if not isinstance(value, bool):
            raise _type_error(path, tp, meta, value)
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise _type_error(path, tp, meta, value)
        check(value, meta, path)
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise _type_error(path, tp, meta, value)
        written, value = value, float(value)
        if not math.isfinite(value):
            raise ConfigError(path, f"must be a finite number, got {value!r}")
        check(value, meta, path, written)
        return value
    if tp is str:
        if not isinstance(value, str):
            raise _type_error(path, tp, meta, value)
        choices = meta.get("choices")
        if choices and value not in choices:
            raise ConfigError(path, f"{value!r} is not one of {', '.join(map(repr, choices))}")
        return value
    if tp is Any:
        return value
    raise TypeError(f"unsupported config type {_type_name(tp)} at {path}")


def build(cls: type, data: dict, path: str = "") -> Any:
    """Build the frozen dataclass ``cls`` from ``data``; errors name ``path.field``."""
    if not isinstance(data, dict):
        raise ConfigError(path, f"expected a table, got {type(data).__name__}")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    errs = ErrorList()              # every field's problem, reported together
    for key in sorted(set(data) - set(fields)):
        errs.add(ConfigError(f"{path}.{key}" if path else key,
                             f"unknown key{_did_you_mean(key, fields)}; allowed keys: "
                             f"{', '.join(sorted(fields))}"))
    kwargs = {}
    for name, f in fields.items():
        fpath = f"{path}.{name}" if path else name
        if name not in data:
            if f.default is _MISSING and f.default_factory is _MISSING:
                required = [n for n, g in fields.items() if g.default is _MISSING
                            and g.default_factory is _MISSING]
                doc = f.metadata.get("doc")
                errs.add(ConfigError(fpath, f"missing required key: expected "
                                     f"{expected_text(hints[name], dict(f.metadata))}"
                                     f"{f' ({doc})' if doc else ''}; required keys here: "
                                     f"{', '.join(required)}"))
            continue
        with errs.catch():
            kwargs[name] = _convert(data[name], hints[name], dict(f.metadata), fpath)
    errs.raise_if()
    try:
        obj = cls(**kwargs)
    except ConfigError as exc:   # a check in __post_init__ names a field of this section
        raise ConfigError(f"{path}.{exc.path}" if path and exc.path else path or exc.path,
                          exc.message) from None
    validate = getattr(obj, "validate", None)
    if validate is not None:
        validate(path)
    return obj


def _did_you_mean(name: str, allowed) -> str:
    close = difflib.get_close_matches(name, list(allowed), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def as_data(config: Any) -> Any:
    """A config dataclass back as plain TOML-like data (tables, lists; None left out)."""
    def strip(obj):
        if isinstance(obj, dict):
            return {k: strip(v) for k, v in obj.items() if v is not None}
        if isinstance(obj, (list, tuple)):
            return [strip(v) for v in obj]
        return obj
    return strip(dataclasses.asdict(config) if dataclasses.is_dataclass(config) else config)


def check_name(value: str, path: str) -> None:
    """A name used as a file or folder name: 1..NAME_MAX_LEN characters of letters, digits,
    ``. _ + -``, starting with a letter or digit (so no ``..``, ``/`` or hidden names)."""
    if not value:
        raise ConfigError(path, "must not be empty (it names the output folder)")
    if len(value) > NAME_MAX_LEN:
        raise ConfigError(path, f"at most {NAME_MAX_LEN} characters (it names the output "
                          f"folder), got {len(value)}")
    if not _NAME_RE.fullmatch(value):
        raise ConfigError(path, f"{value!r} is not a safe file name: use letters, digits and "
                          "'. _ + -', starting with a letter or digit (it names the output folder)")


def _file_error(path: Path) -> str | None:
    """Why ``path`` cannot be read as a scene file, or None."""
    try:
        st = path.stat()
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "symbolic link loop"
        if exc.errno == errno.ENAMETOOLONG:
            return "file name too long"
        if exc.errno == errno.ENOTDIR:
            return "no such file (a part of the path is not a folder)"
        if exc.errno == errno.EACCES:
            return "permission denied"
        return "no such file" if exc.errno == errno.ENOENT else exc.strerror or str(exc)
    if stat.S_ISDIR(st.st_mode):
        return "is a folder, not a scene file"
    if not stat.S_ISREG(st.st_mode):
        return "not a regular file (a FIFO, socket or device)"
    if st.st_size > MAX_SCENE_BYTES:
        return f"too large for a scene file ({st.st_size} bytes > {MAX_SCENE_BYTES})"
    if not os.access(path, os.R_OK):
        return "permission denied"
    return None


def _header_error(text: str, schema: type) -> ConfigError | None:
    """The first ``[table]`` / ``[[array]]`` header naming no table of ``schema``, with its
    line (so a typo in a table name is reported there, not where TOML later trips)."""
    for lineno, line in enumerate(text.splitlines(), 1):
        m = re.match(r"\s*\[\[?([^\[\]]+)\]\]?\s*(#.*)?$", line)
        if m is None:
            continue
        tp, path = schema, ""
        for key in (k.strip().strip("\"'") for k in m.group(1).split(".")):
            if not dataclasses.is_dataclass(tp):
                break
            fields = {f.name for f in dataclasses.fields(tp)}
            here = f"{path}.{key}" if path else key
            if key not in fields:
                return ConfigError(here, f"unknown table [{m.group(1).strip()}] at line {lineno}"
                                   f"{_did_you_mean(key, fields)}; allowed keys"
                                   f"{' of [' + path + ']' if path else ''}: "
                                   f"{', '.join(sorted(fields))}")
            tp = typing.get_type_hints(tp)[key]
            args = [a for a in typing.get_args(tp) if a is not type(None)]
            if typing.get_origin(tp) in (typing.Union, types.UnionType) and len(args) == 1:
                tp = args[0]
            if typing.get_origin(tp) is tuple and typing.get_args(tp):
                tp = typing.get_args(tp)[0]
            path = here
    return None


#: the first line of a draft scene (``vibrogear import`` when the mapping stopped): refused
DRAFT_MARKER = "# vibrogear DRAFT:"


def read_toml_file(path: str | Path, schema: type | None = None) -> dict[str, Any]:
    """Read a TOML file (UTF-8, an optional byte-order mark) into a dict; ConfigError naming
    the file for anything that is not a readable scene file, and the table of ``schema``
    where a table header is misspelt."""
    import tomllib

    p = Path(path)
    why = _file_error(p)
    if why is not None:
        raise ConfigError(str(path), why)
    try:
        text = p.read_bytes().decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(str(path), "not a valid TOML file: not UTF-8 text") from None
    except OSError as exc:
        raise ConfigError(str(path), f"cannot read: {exc.strerror or exc}") from None
    text = text.removeprefix("\ufeff")
    if text.startswith(DRAFT_MARKER):
        raise ConfigError(str(path), "is a draft scene that `vibrogear import` wrote because the "
                          "mapping stopped: fix the problems listed at its top, then delete its "
                          "first line")
    if schema is not None:
        bad = _header_error(text, schema)
        if bad is not None:
            raise bad
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(str(path), f"not a valid TOML file: {exc}") from None
    except RecursionError:
        raise ConfigError(str(path), "not a valid scene file: arrays or tables nested too "
                          "deeply") from None
