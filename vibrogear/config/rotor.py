"""Rotor scene schema (placeholder: filled in by the rotor work)."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["RotorConfig"]


@dataclass(frozen=True)
class RotorConfig:
    pass
