"""Which REXS component types the import covers: those it maps (:data:`MAPPED_TYPES`), those
that carry power in a way the scene cannot express and are refused by name
(:data:`UNSUPPORTED`, :func:`refuse_unsupported`), and those read only as data of others
or deliberately left out, each with the reason the mapping report gives
(:data:`KNOWN_IGNORED`).  :mod:`.mapping` maps the components.
"""
from __future__ import annotations

from ..base import ConfigError

__all__ = ["UNSUPPORTED", "KNOWN_IGNORED", "MAPPED_TYPES", "refuse_unsupported"]

#: component types that carry power in a way the scene cannot express: refused by name
UNSUPPORTED = ("planetary_stage", "planet_carrier", "planet_shaft", "planet_pin",
               "bevel_gear", "bevel_stage", "worm_gear", "worm_wheel", "worm_stage",
               "ring_gear", "coupling", "fixed_coupling", "switchable_coupling",
               "slide_bearing", "general_gear", "general_stage", "crossed_helical_stage",
               "hypoid_stage")
#: shaft-hub connections and shaft details: the hub is taken as rigidly fixed to its shaft
_RIGID_CONNECTIONS = ("cylindrical_interference_fit", "tapered_interference_fit",
                      "feather_key_connection", "involute_spline_connection",
                      "involute_spline_gear_hub", "involute_spline_gear_shaft",
                      "involute_spline_gear_flank", "involute_spline_stage_gear_data",
                      "shaft_shoulder", "shaft_shoulder_with_undercut", "rectangular_groove",
                      "round_groove", "v_notch", "transverse_bore", "notch_effect_shaft_hub_connection",
                      "fkm_evaluation_point")
#: read only as data of other components, or known and deliberately left out
KNOWN_IGNORED = {
    "gear_unit": "only its duration share per load case is read (load_duration_fraction, "
                 "REXS 1.6 operating_time_fraction): the load case taken is the longest "
                 "unless `--load-case N` names one",
    "gear_casing": "the casing is rigid ground: bearings in it are bearings to ground "
                   "(`vibrogear import --housing box` generates a box housing with "
                   "its walls at the casing bearings' planes; `--housing CASING.step "
                   "--fixed-region ...` takes the casing from CAD)",
    "lubricant": "oil data do not enter the dynamic model",
    "cylindrical_stage_gear_data": "read through the stage's gears",
    "cylindrical_gear_flank": "read as the gear's pressure angle and profile shift",
    "shaft_section": "read as the shaft's sections",
    "material": "read through the shafts that reference it",
    "rolling_bearing_row": "read as its bearing's element set",
    "rolling_element": "read as its bearing's element set",
    **{t: "a shaft-hub connection or shaft detail: the hub is taken as rigidly fixed, the "
          "shaft as its sections" for t in _RIGID_CONNECTIONS},
}
#: component types the importer maps to scene tables
MAPPED_TYPES = ("additional_mass", "shaft", "cylindrical_gear", "cylindrical_stage",
                "external_load", "rolling_bearing_with_catalog_geometry",
                "rolling_bearing_with_detailed_geometry", "concept_bearing")


def refuse_unsupported(model, errs) -> None:
    """Collect in ``errs`` a ConfigError for every component the scene cannot express: a
    type of :data:`UNSUPPORTED` (by name) and an internal cylindrical gear (negative
    number_of_teeth)."""
    for c in model.components.values():
        with errs.catch():
            if c.type in UNSUPPORTED:
                raise ConfigError(model.source, f"component {c.id} is a {c.type!r}"
                                  f"{' (' + repr(c.name) + ')' if c.name else ''}: not "
                                  "supported (vibrogear maps shafts, cylindrical gears and "
                                  "stages, rolling and concept bearings, external loads); fix: "
                                  "export the gearbox without it, or model it by hand")
            if c.type == "cylindrical_gear" and c.given("number_of_teeth") and \
                    c.number("number_of_teeth", model.source) < 0:
                raise ConfigError(model.source, f"component {c.id} is an internal "
                                  "'cylindrical_gear' (negative number_of_teeth): internal "
                                  "gears are not supported")
