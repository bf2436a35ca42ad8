"""``docs/scene-reference.md``, generated from the config specs: every section and key of a
scene with its type, allowed range, default and meaning.  A test keeps the file equal to
:func:`scene_reference_markdown`; regenerate it with
``python -m vibrogear.config.reference > docs/scene-reference.md``."""
from __future__ import annotations

import dataclasses
import types
import typing

from .base import expected_text
from .scene import GearboxScene, Scene

__all__ = ["scene_reference_markdown"]

_HEAD = """# Scene reference

Every key a scene TOML may hold, section by section: its type and allowed range, its
default ("required" where it has none) and what it means, with its unit in brackets.
Generated from the code's own specs (`python -m vibrogear.config.reference >
docs/scene-reference.md`); a test keeps this page equal to them.  Units are SI (m, kg, s, N,
Pa) unless a key says otherwise; angles in degrees, speeds in rpm.  A gearbox scene's
`[sweep]`, `[continuation]` and `[time_response]` take the driving speed (`rpm_min`,
`rpm_max`, `rpm`) where the impact pair takes `Omega`; both forms are listed.
"""


def _inner(tp):
    """The dataclass inside ``X | None`` or ``tuple[X, ...]``, and how it nests."""
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    if typing.get_origin(tp) in (typing.Union, types.UnionType) and len(args) == 1:
        tp = args[0]
    if typing.get_origin(tp) is tuple and typing.get_args(tp) and \
            dataclasses.is_dataclass(typing.get_args(tp)[0]):
        return typing.get_args(tp)[0], True
    return (tp, False) if dataclasses.is_dataclass(tp) else (None, False)


def _default(f) -> str:
    if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
        return "required"
    d = f.default if f.default is not dataclasses.MISSING else f.default_factory()
    if d is None:
        return "-"
    if dataclasses.is_dataclass(d):
        return "(table defaults)"
    if isinstance(d, tuple):
        return "[" + ", ".join(repr(x) for x in d) + "]"
    return f"`{d!r}`"


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _section(cls, name: str, seen: set, out: list, note: str = "") -> None:
    key = (cls, name)
    if key in seen:
        return
    seen.add(key)
    hints = typing.get_type_hints(cls)
    rows, nested = [], []
    for f in dataclasses.fields(cls):
        inner, is_list = _inner(hints[f.name])
        if inner is not None:
            nested.append((inner, f"{name}.{f.name}", is_list))
            rows.append(f"| `{f.name}` | {'[[' if is_list else '['}{name}.{f.name}"
                        f"{']]' if is_list else ']'} | {_default(f)} | "
                        f"{_cell(f.metadata.get('doc', ''))} |")
            continue
        rows.append(f"| `{f.name}` | {_cell(expected_text(hints[f.name], dict(f.metadata)))} | "
                    f"{_default(f)} | {_cell(f.metadata.get('doc', ''))} |")
    out += [f"## [{name}]{note}", "", "| key | type and range | default | meaning |",
            "| --- | --- | --- | --- |", *rows, ""]
    for inner, sub, _ in nested:
        _section(inner, sub, seen, out)


def scene_reference_markdown() -> str:
    out = [_HEAD]
    seen: set = set()
    hints = typing.get_type_hints(Scene)
    ghints = typing.get_type_hints(GearboxScene)
    for f in dataclasses.fields(Scene):
        plain, _ = _inner(hints[f.name])
        geared, _ = _inner(ghints[f.name])
        if plain is None:
            continue
        if geared is plain:
            _section(plain, f.name, seen, out)
        else:
            _section(plain, f.name, seen, out, " (impact pair: the parameter Omega)")
            _section(geared, f.name, seen, out, " (gearbox: the driving speed in rpm)")
    return "\n".join(out).rstrip() + "\n"


if __name__ == "__main__":
    import sys
    sys.stdout.write(scene_reference_markdown())
