"""vibrogear: nonlinear vibration analysis of gear drives."""

__version__ = "0.1.0"
__all__ = ["__version__"]
