"""Names of a package re-exported from its modules on first use.

A package's ``__init__`` names what it offers without importing the modules that define it,
so that importing one helper of a wing (or ``import vibrogear``) stays cheap::

    __all__ = ["StatesResult", "run"]
    __getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(__all__, "states"))

``names`` maps each public name to the module (relative to the package) that defines it.
"""
from __future__ import annotations

from importlib import import_module
from typing import Callable, Mapping


def lazy_exports(package: str, names: Mapping[str, str]
                 ) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """The module-level ``__getattr__`` and ``__dir__`` of ``package`` (PEP 562)."""
    names = dict(names)

    def __getattr__(name: str):
        if name in names:
            return getattr(import_module(f"{package}.{names[name]}"), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__():
        return sorted(set(vars(import_module(package))) | set(names))

    return __getattr__, __dir__
