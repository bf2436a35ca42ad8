"""Dotted keys and ``--set`` overrides of scene data: ``gearbox.gears[0].teeth=30`` (or
``gears.0``) parsed into its keys and a TOML value (:func:`parse_key`,
:func:`parse_override`), and a value set at such a path in the plain data read from a
scene file, creating tables on the way (:func:`set_path`); errors name the path as the
tool prints it.
"""
from __future__ import annotations

import re
from typing import Any

from .errors import ConfigError

__all__ = ["parse_key", "parse_override", "set_path"]


_KEY_PART = re.compile(r"([A-Za-z0-9_-]+)((?:\[\d+\])*)")


def parse_key(key: str, text: str | None = None, what: str = "--set") -> list[str]:
    """The keys of a dotted path as the tool prints it, ``gearbox.gears[0].teeth`` (or
    ``gears.0``): ``["gearbox", "gears", "0", "teeth"]``; ``text``: the whole override, for
    the message; ``what``: where the key was given (the error's path)."""
    keys: list[str] = []
    for part in key.strip().split("."):
        m = _KEY_PART.fullmatch(part.strip())
        if m is None:
            raise ConfigError(what, f"bad key {key.strip()!r} in {text or key!r}: expected "
                              "dotted names with optional list indices, e.g. "
                              "gearbox.gears[0].teeth")
        keys.append(m.group(1))
        keys += re.findall(r"\d+", m.group(2))
    return keys


def parse_override(text: str) -> tuple[list[str], Any]:
    """Parse ``section.key=value`` (value in TOML syntax, bare words as strings); list
    entries as the tool prints them, ``gearbox.gears[0].teeth=30`` (or ``gears.0``)."""
    import tomllib

    if "=" not in text:
        raise ConfigError("--set", f"expected section.key=value, got {text!r}")
    key, raw = text.split("=", 1)
    keys = parse_key(key, text)
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except (tomllib.TOMLDecodeError, RecursionError):
        value = raw.strip()
    return keys, value


def _show(keys: list[str]) -> str:
    """Keys as the tool prints paths: ``gearbox.gears[0].teeth``."""
    out = ""
    for k in keys:
        out += f"[{k}]" if k.isdigit() else (f".{k}" if out else k)
    return out


def set_path(data: dict, keys: list[str], value: Any) -> None:
    """Set ``data[k0][k1]...`` creating tables on the way; list items by index."""
    node: Any = data
    for i, k in enumerate(keys):
        here = _show(keys[:i + 1])
        last = i == len(keys) - 1
        if isinstance(node, list):
            if not k.isdigit() or int(k) >= len(node):
                raise ConfigError(here, f"no such list entry: the list has {len(node)} "
                                  f"entries, indices 0..{len(node) - 1}")
            if last:
                node[int(k)] = value
                return
            node = node[int(k)]
        else:
            if k.isdigit():
                raise ConfigError(here, "is not a list")
            if last:
                node[k] = value
                return
            nxt = node.get(k)
            if nxt is None:
                nxt = node[k] = {}
            node = nxt
        if not isinstance(node, (dict, list)):
            raise ConfigError(here, "is a value, not a table")
