"""What to look at in each figure: captions by figure file name, for report.html.

:data:`CAPTIONS` maps a figure's file name (or a pattern with ``<mesh>``, ``<quantity>``) to
a caption in plain words that says what the figure answers and where to look.
:func:`caption` finds the caption of a written file and adds the reduced model's mode count
(``m = 146 (21+25+100)``), which the figures' titles leave out, where the study title has it.
"""
from __future__ import annotations

import re
from pathlib import Path

from ..figure import mode_count_note

__all__ = ["CAPTIONS", "caption"]

_MOTION = ("Motion classes: period 1 / 2 / 3+ (the motion repeats every 1, 2, 3 or more "
           "excitation periods, at engineering resolution), multi-frequency forced (follows "
           "several meshes' frequencies), quasi-periodic (two incommensurate frequencies, a "
           "torus; NS), chaotic (a positive Lyapunov exponent, reproduced ten times tighter).")
_POINTS = ("LP: a fold (limit point), where the response jumps; PD: period doubling; NS: "
           "Neimark-Sacker, the onset of quasi-periodic motion; each named with its speed.")

CAPTIONS: dict[str, str] = {
    "gearbox.png": (
        "The gearbox to scale, drawn from the scene file: side view along the shafts (shaft "
        "sections at their diameters, gears at their pitch diameter and face width, free "
        "gears hatched, bearings as crossed squares, couplings to motor and load) and end "
        "view (pitch circles, housing walls and bores). Check it against your drawing."),
    "bifurcation.png": (
        "The response at every speed of the sweep up (blue) and down (red). Top: the "
        "monitored mesh's deformation, its minima and maxima and one sample per mesh period; "
        "below zero its teeth lose contact. Where up and down differ the response jumps "
        "(hysteresis). Middle: the motion class at each speed, one row per direction. Then one "
        "panel per gear mesh: drive-flank impacts (filled), back-flank impacts (open: "
        "rattle) per mesh period and the share of the time out of contact (line). Last: the "
        "impact energy per period of each mesh that rattles. " + _MOTION),
    "bifurcation_branches.png": (
        "The sweep of bifurcation.png with the periodic orbits traced by continuation: stable "
        "solid (this motion can be observed), unstable dashed (it cannot). " + _POINTS),
    "fig2.png": (
        "The method paper's Fig. 2 for this gearbox: the sweep's minima and maxima of the "
        "monitored mesh deformation (below zero: contact lost), the continuation branches "
        "(stable solid, unstable dashed) and the motion class at each speed. " + _POINTS),
    "branch_max.png": (
        "The largest mesh deformation of the periodic orbits traced by continuation, against "
        "speed: stable solid, unstable dashed, sweep points for comparison. Where a branch "
        "folds (LP) the response jumps; the legend lists only what is drawn. " + _POINTS),
    "branch_min.png": (
        "The smallest mesh deformation of the traced orbits; below zero the teeth lose "
        "contact during the orbit. " + _POINTS),
    "resonance_map.png": (
        "The natural frequencies of the linearised gearbox (horizontal lines, darker = more "
        "strain energy in the gear meshes, scale at the right) against the 1x and 2x mesh "
        "frequency of every mesh. Circles mark the resonance speeds (modes with more than "
        "5 % mesh strain energy), written on the speed axis: speeds to avoid or to check."),
    "time_response.png": (
        "The time response at one speed: each mesh's deformation (below zero: contact lost; "
        "the dotted line is the back flank), its phase trajectory, the mesh forces (spikes "
        "are impacts) and the bearing loads."),
    "reduction_accuracy.png": (
        "How many master modes the reduced model needs: its natural frequencies and "
        "nonlinear response against the full model's, at each reduction level."),
    "nvh_waterfall_dte.png": (
        "Spectrum of the dynamic transmission error at each speed (colour: dB re 1 \u00b5m). "
        "Lines along the white diagonals are mesh orders; markers name the identified lines "
        "by source; the title states the share of the line power that no source explains."),
    "nvh_waterfall_mesh_force.png": (
        "Spectrum of the mesh force at each speed (dB re 1 N), mesh orders and identified "
        "lines marked; the title states the unidentified share."),
    "nvh_waterfall_bearing_force.png": (
        "Spectrum of the bearing forces at each speed (dB re 1 N), mesh orders and identified "
        "lines marked; the title states the unidentified share."),
    "nvh_waterfall_erp.png": (
        "Equivalent radiated power of the housing surface per frequency at each speed "
        "(dB re 1 pW): which orders make the noise, and at which speeds."),
    "nvh_waterfall_branch_dte.png": (
        "Spectrum of the transmission error along the traced periodic orbit (one orbit "
        "period per speed); speeds where that orbit is unstable are hatched at the left: "
        "there it is not what runs. Not drawn when the orbit is unstable at every speed."),
    "erp.png": (
        "Equivalent radiated power of the housing's outer surface against speed, in W and "
        "dB re 1 pW: the peak is the loudest speed."),
    "runup_envelope.png": (
        "The envelope of each mesh's deformation during a run-up and run-down at a finite "
        "rate, over the steady sweep: where the run-up lags or jumps the speed is passed "
        "through a hysteresis region."),
    "runup_orders.png": "Order tracks of the run-up: each mesh order's amplitude against speed.",
    "runup_waterfall.png": "Spectrum against speed during the run-up, mesh orders labelled.",
    "map_class.png": (
        "Motion class over speed and input torque: where the gearbox runs periodic (green), "
        "quasi-periodic (blue) or chaotic (red); LP curves bound the jump regions. " + _MOTION),
    "map_impacts_<mesh>.png": "Contact onsets per mesh period of the mesh over speed and torque.",
    "map_rattle_<mesh>.png": "Impact energy per period of the mesh over speed and torque (log).",
    "map_max_force_<mesh>.png": "Largest mesh force [N] over speed and torque.",
    "nnm_fep.png": (
        "Frequency-energy plot of a nonlinear normal mode: how the mode's frequency shifts "
        "with its energy (stable solid, unstable dashed)."),
    "nnm_backbone.png": (
        "The nonlinear mode's backbone over the forced response: the forced peaks lean along "
        "it."),
    "optimize_convergence.png": "The objective of each evaluation and the best so far.",
    "optimize_landscape.png": "The objective against each optimised variable.",
    "critical_damping.png": (
        "The folds of the primary resonance against damping: above the critical damping "
        "the response no longer jumps."),
    "work_precision.png": "Error against work of the integrator at each tolerance.",
    "shooting_precision.png": "Accuracy of the shooting method against work and tolerance.",
    "campbell.png": "Natural frequencies against speed, with the 1x line: critical speeds.",
    "mode_shapes.png": "The rotor's mode shapes.",
    "housing_modes.png": (
        "Housing mode shapes: the surface deformed by each mode and coloured by displacement, "
        "each panel labelled with the wall or bore that moves most (its share of the mode's "
        "kinetic energy); bores ringed and numbered, the supported faces hatched."),
    "housing_modes_<n>.png": "More housing mode shapes (as housing_modes.png).",
    "nvh_housing_modes.png": (
        "The housing's first mode shapes in this gearbox: which wall moves in each."),
    "housing_mode_<n>_anim.png": "The first housing mode shape, animated.",
    "housing_ods.png": (
        "Operating deflection shape at the ERP peak: the housing surface coloured by RMS "
        "normal velocity (dB re 1e-9 m/s, top 40 dB); the coloured walls radiate most."),
    "housing_ods_anim.png": "The operating deflection shape at the ERP peak, animated.",
    "findings.png": (
        "Where to avoid or watch the gearbox: one row per contact or kind of motion, a bar "
        "where its rule holds (red avoid, amber caution, hatched: one sweep direction only), "
        "events (jumps, folds, resonances, the ERP peak) on the last row."),
    "states.png": (
        "The danger map: every state found from random disturbances at each speed, coloured "
        "by motion class, sized by its basin (the share of disturbances that end there), "
        "with the continuation's branches over it."),
    "housing_sweep.png": "The housing response against frequency.",
    "housing_error_vs_time.png": "The housing eigen-solvers' accuracy against their time.",
}


def caption(file_name: str | Path, title: str = "") -> str:
    """The caption of the figure ``file_name`` (any folder; ``<mesh>`` / ``<quantity>``
    patterns matched), with the mode count of the study ``title`` where it has one; "" for
    a figure without a caption."""
    name = Path(file_name).name
    text = CAPTIONS.get(name)
    if text is None:
        for key, value in CAPTIONS.items():
            if "<" in key:
                pattern = re.escape(key).replace(re.escape("<mesh>"), r"[^/]+").replace(
                    re.escape("<quantity>"), r"[^/]+").replace(re.escape("<n>"), r"\d+")
                if re.fullmatch(pattern, name):
                    text = value
                    break
    if text is None:
        return ""
    note = mode_count_note(title)
    return f"{text} {note}" if note else text

