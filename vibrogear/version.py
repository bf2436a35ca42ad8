"""The package version (the ground floor: every layer may read it)."""

__version__ = "0.1.0"
__all__ = ["__version__"]
