"""The scene checks that need the model layer but no solve (gear-mesh geometry: shaft axes,
mesh planes, centre distances; ISO 6336 gear data).  The config layer checks every field
and every cross-section rule it can state alone (:mod:`vibrogear.config.model.layout`); this runs
after it, still before anything is written (``vibrogear check`` and ``run`` call it; so does
:func:`vibrogear.runner.run_scene`)."""
from __future__ import annotations

__all__ = ["validate_scene"]


def validate_scene(scene, *, files: bool = False):
    """Raise :class:`~vibrogear.config.base.ConfigError` naming the field; return the scene.
    ``files``: also open a STEP housing and select its bores and clamped faces as the mesher
    will (``vibrogear check``; a run does it when it meshes, and not at all from its cache)."""
    if getattr(scene, "gearbox", None) is not None:
        from .gearbox.model import check_layout
        check_layout(scene)
    housing = getattr(scene, "housing", None)
    if files and housing is not None and housing.source == "step":
        from ..geometry.housing_import import check_step_housing
        check_step_housing(housing)
    return scene
