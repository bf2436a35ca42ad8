"""Housing scene schema (placeholder: filled in by the housing work)."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["HousingConfig"]


@dataclass(frozen=True)
class HousingConfig:
    pass
