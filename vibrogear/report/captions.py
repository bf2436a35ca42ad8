"""Captions of the report's figures: what each shows and what to look at (by file name)."""
from __future__ import annotations

import re

__all__ = ["CAPTIONS", "caption_for"]

#: figure file name (or a regular expression of it) -> caption
CAPTIONS = {
    "findings.png": "Speed bands of the findings: where to avoid or watch the gearbox.",
    "gearbox.png": "The gearbox to scale, from the scene: shafts, gears, bearings, couplings "
                   "and the housing outline.",
    "resonance_map.png": "Mesh-order lines over speed against the natural frequencies: where "
                         "a line crosses a mode with a large mesh-energy share, the gearbox "
                         "resonates. Look for crossings inside the operating range.",
    "time_response.png": "The response at one speed after the transient: mesh deformations "
                         "below zero mean the teeth separate (contact loss).",
    "bifurcation.png": "The sweep up and down: the extreme deformation of each mesh per "
                       "speed, the motion class and the impacts. Where up and down differ, two "
                       "responses coexist and the gearbox jumps.",
    "branch_max.png": "Periodic responses traced over speed: solid stable, dashed unstable, "
                      "with folds (LP), period doublings (PD) and tori (NS) marked. A fold "
                      "pair bounds the speeds where the response can jump.",
    "branch_min.png": "The minimum deformation of the traced responses: below zero the teeth "
                      "separate.",
    "fig2.png": "The paper's Fig. 2 on its gearbox: sweep extremes, zero line, continuation "
                "branches and motion classes.",
    "erp.png": "Radiated power of the housing over speed: peaks are the speeds the housing is "
               "loudest.",
    r"nvh_waterfall_.*\.png": "Spectra over speed; identified lines (mesh orders, shaft "
                              "orders, modes) are marked. Look for lines that grow where "
                              "they cross a mode.",
    "map_class.png": "Motion class over speed and load: where in the operating map the "
                     "response stops being periodic.",
    r"map_.*\.png": "A metric over speed and load of the operating map.",
    "runup_envelope.png": "Envelope of the response while the speed ramps, over the steady "
                          "sweep: transient contact loss shows where the envelope crosses zero.",
    "runup_waterfall.png": "Spectra over the run-up: order lines and the resonances they "
                           "cross.",
    "reduction_accuracy.png": "Error of the reduced model against its size and run time: the "
                              "chosen master-mode count should sit where the error has "
                              "levelled off.",
    "nnm_backbone.png": "Backbones of the nonlinear normal modes over the forced response: "
                        "where a backbone bends, the resonance speed depends on amplitude.",
    "nnm_fep.png": "Frequency-energy plot of the nonlinear normal modes.",
    "optimize_convergence.png": "Best objective found against evaluations: a flat tail means "
                                "the budget was enough.",
    "states.png": "The danger map: every state found from random disturbances at each speed, "
                  "coloured by motion class, sized by how many disturbances end there.",
    "housing_modes.png": "Housing mode shapes: the surface deformed by each mode and coloured by "
                         "displacement, each panel labelled with the wall or bore that moves "
                         "most (share of the mode's kinetic energy).",
    r"housing_modes_\d+\.png": "More housing mode shapes.",
    "nvh_housing_modes.png": "The housing's first mode shapes in this gearbox: which wall moves "
                             "in each.",
    r"housing_mode_\d+_anim\.png": "The first housing mode, animated.",
    "housing_ods.png": "Operating deflection shape at the ERP peak: the housing surface coloured "
                       "by RMS normal velocity (dB re 1e-9 m/s); the coloured walls radiate "
                       "most.",
    "housing_ods_anim.png": "The operating deflection shape at the ERP peak, animated.",
    "work_precision.png": "Error against run time of the integrator for each tolerance.",
    "shooting_precision.png": "Error against run time of the shooting method.",
    "critical_damping.png": "The primary resonance's folds against damping: they meet at the "
                            "critical damping.",
}


def caption_for(rel: str) -> str:
    """The caption of the figure at relative path ``rel`` ('' if none)."""
    name = rel.rsplit("/", 1)[-1]
    if name in CAPTIONS:
        return CAPTIONS[name]
    for pattern, text in CAPTIONS.items():
        if any(c in pattern for c in "*\\") and re.fullmatch(pattern, name):
            return text
    return ""
