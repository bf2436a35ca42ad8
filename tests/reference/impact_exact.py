"""Thin re-export: the exact impact-pair reference now lives in
:mod:`vibrogear.verification.impact_exact` (the flow) and
:mod:`vibrogear.verification.impact_orbits` (periodic orbits), so the ``report`` analysis can
use it at run time.  Kept so that existing imports ``from tests.reference import
impact_exact`` work."""
from vibrogear.verification.impact_exact import *  # noqa: F401,F403
from vibrogear.verification.impact_exact import __all__ as _flow_names
from vibrogear.verification.impact_orbits import *  # noqa: F401,F403
from vibrogear.verification.impact_orbits import __all__ as _orbit_names

__all__ = [*_flow_names, *_orbit_names]
