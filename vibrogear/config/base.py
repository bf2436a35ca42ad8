"""Generic TOML -> frozen dataclass loading with validation.

A config section is a frozen dataclass whose fields carry their allowed range in
``field(metadata=...)``, built with :func:`spec`. :func:`build` turns a plain dict
(read from TOML) into the dataclass, checking unknown keys, missing keys, types,
finiteness and ranges, and naming the field path in every error.  Cross-field
checks live in a ``validate(self, path)`` method of the dataclass.
"""
from __future__ import annotations

import dataclasses
import math
import types
import typing
from typing import Any

__all__ = ["ConfigError", "spec", "build", "check", "set_path", "parse_override", "as_data"]


class ConfigError(ValueError):
    """Invalid input: names the field path and the allowed range."""

    def __init__(self, path: str, message: str):
        self.path = path
        super().__init__(f"{path}: {message}" if path else message)


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


def check(value: float, meta: dict, path: str) -> None:
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
        raise ConfigError(path, f"value {value!r} out of range: must be {_range_text(meta)}")


def _type_name(tp: Any) -> str:
    return getattr(tp, "__name__", str(tp))


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
            raise ConfigError(path, f"expected a list, got {type(value).__name__}")
        n = len(value)
        if meta.get("min_len") is not None and n < meta["min_len"]:
            raise ConfigError(path, f"needs at least {meta['min_len']} entries, got {n}")
        if meta.get("max_len") is not None and n > meta["max_len"]:
            raise ConfigError(path, f"allows at most {meta['max_len']} entries, got {n}")
        item_tp = args[0] if args else Any
        if len(args) == 2 and args[1] is Ellipsis or len(args) == 1:
            item_meta = {k: meta.get(k) for k in ("gt", "ge", "lt", "le", "choices")}
            return tuple(_convert(v, item_tp, item_meta, f"{path}[{i}]") for i, v in enumerate(value))
        if len(args) != n:
            raise ConfigError(path, f"expected exactly {len(args)} entries, got {n}")
        return tuple(_convert(v, a, {}, f"{path}[{i}]") for i, (v, a) in enumerate(zip(value, args)))
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, dict):
            raise ConfigError(path, f"expected a table, got {type(value).__name__}")
        return build(tp, value, path)
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(path, f"expected true/false, got {value!r}")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(path, f"expected an integer, got {value!r}")
        check(value, meta, path)
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(path, f"expected a number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            raise ConfigError(path, f"must be a finite number, got {value!r}")
        check(value, meta, path)
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(path, f"expected a string, got {value!r}")
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
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ConfigError(f"{path}.{unknown[0]}" if path else unknown[0],
                          f"unknown key; allowed keys: {', '.join(sorted(fields))}")
    kwargs = {}
    for name, f in fields.items():
        fpath = f"{path}.{name}" if path else name
        if name not in data:
            if f.default is _MISSING and f.default_factory is _MISSING:
                raise ConfigError(fpath, "missing required key")
            continue
        kwargs[name] = _convert(data[name], hints[name], dict(f.metadata), fpath)
    obj = cls(**kwargs)
    validate = getattr(obj, "validate", None)
    if validate is not None:
        validate(path)
    return obj


def parse_override(text: str) -> tuple[list[str], Any]:
    """Parse ``section.key=value`` (value in TOML syntax, bare words as strings)."""
    import tomllib

    if "=" not in text:
        raise ConfigError("--set", f"expected section.key=value, got {text!r}")
    key, raw = text.split("=", 1)
    key = key.strip()
    if not key or any(not part for part in key.split(".")):
        raise ConfigError("--set", f"bad key in {text!r}")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return key.split("."), value


def set_path(data: dict, keys: list[str], value: Any) -> None:
    """Set ``data[k0][k1]...`` creating tables on the way; list items by index."""
    node: Any = data
    for i, k in enumerate(keys[:-1]):
        if isinstance(node, list):
            try:
                node = node[int(k)]
            except (ValueError, IndexError):
                raise ConfigError(".".join(keys[:i + 1]), "no such list entry") from None
            continue
        nxt = node.get(k)
        if nxt is None:
            nxt = node[k] = {}
        if not isinstance(nxt, (dict, list)):
            raise ConfigError(".".join(keys[:i + 1]), "is a value, not a table")
        node = nxt
    last = keys[-1]
    if isinstance(node, list):
        try:
            node[int(last)] = value
        except (ValueError, IndexError):
            raise ConfigError(".".join(keys), "no such list entry") from None
    else:
        node[last] = value


def as_data(config: Any) -> Any:
    """A config dataclass back as plain TOML-like data (tables, lists; None left out)."""
    def strip(obj):
        if isinstance(obj, dict):
            return {k: strip(v) for k, v in obj.items() if v is not None}
        if isinstance(obj, (list, tuple)):
            return [strip(v) for v in obj]
        return obj
    return strip(dataclasses.asdict(config) if dataclasses.is_dataclass(config) else config)
