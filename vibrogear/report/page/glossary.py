"""The words of the report in plain terms, the section titles and the method's citation
(one place; the README's glossary says the same)."""
from __future__ import annotations

__all__ = ["GLOSSARY", "PAPER", "SECTION_TITLES"]

#: the method paper
PAPER = ("M. Byrtus, \"Dynamic Analysis of Reduced Order Large Rotating Vibro-Impact "
         "Systems\", University of West Bohemia, Pilsen; World Academy of Science, Engineering "
         "and Technology, International Journal of Mechanical and Mechatronics Engineering "
         "(2014). The housing, shafts and couplings joined by modal synthesis, the sweep "
         "(its Fig. 2) and the continuation of periodic responses (its Figs 4-8) follow it.")

#: analysis -> section title of the report
SECTION_TITLES = {
    "modes": "Natural frequencies and resonance speeds",
    "time_response": "Time response at one speed",
    "sweep": "Speed sweep up and down (bifurcation diagram)",
    "continuation": "Periodic responses and their stability (continuation)",
    "nvh": "Noise and vibration: spectra and radiated power",
    "map": "Speed × load operating map",
    "runup": "Run-up and run-down",
    "reduction_accuracy": "Reduction accuracy: how many master modes are enough",
    "nnm": "Nonlinear normal modes (backbones)",
    "optimize": "Design optimisation",
    "states": "Coexisting states and their basins",
    "report": "Work-precision: error against run time",
    "critical_damping": "Critical damping of the primary resonance",
    "campbell": "Campbell diagram",
    "housing_sweep": "Housing geometry sweep",
    "housing_convergence": "Housing mesh convergence",
}

#: (term, meaning), in the order a reader meets them
GLOSSARY = (
    ("avoid / caution / fine", "The severity of a speed band by the rules of [findings] "
     "(docs/findings.md): avoid = do not operate there; caution = acceptable only with a "
     "reason, read the evidence; fine = reported, not flagged."),
    ("contact loss", "A gear mesh whose teeth separate for part of the time (its deformation "
     "enters the backlash); they re-impact on the drive flank."),
    ("rattle", "Impacts on the back flank of a mesh: the gear crosses its backlash (typical "
     "of a free, unloaded gear)."),
    ("mesh period", "The time between two tooth engagements: 60 / (speed in rpm x teeth). "
     "Impacts are counted per mesh period of the first mesh."),
    ("motion classes", "Claims at engineering resolution: periodic (every mesh deformation "
     "and force repeats every n excitation periods within 1e-3 of its range or 1 nm / 1 N: "
     "period-n; n >= 2 is a subharmonic), multi-frequency forced (the response follows a "
     "forcing of several mesh frequencies), quasi-periodic (no period; the largest Lyapunov "
     "exponent's 95 % interval reaches 0), chaotic (no period; that interval lies above 0, "
     "also on the record integrated ten times tighter), not settled (no verdict within the "
     "transient budget)."),
    ("loaded / idle mesh", "From the static load path: a loaded mesh carries the torque from "
     "motor to load and is judged by its dynamic factor kv (largest tooth force / static "
     "tooth force) and contact loss; an idle mesh drives a free gear held only by its drag "
     "and is judged by its rattle level (impact power in dB re 1 pW); its rattle threshold "
     "ratio, the inertia torque the gear needs to follow the mesh over its drag torque "
     "(linearised model), says why: above 1 the drag cannot hold it on its drive flank."),
    ("sweep up / down (sequential continuation)", "Each speed starts from the settled state "
     "of the previous speed, going up and then down; where the two differ, two responses "
     "coexist (hysteresis) and the response jumps."),
    ("continuation", "Tracing periodic responses over speed by shooting, stable and "
     "unstable ones, with their stability from the Floquet multipliers."),
    ("Floquet multiplier", "How a small disturbance of a periodic response grows per period; "
     "the response is stable when every multiplier lies inside the unit circle."),
    ("LP (fold)", "Limit point: the branch turns back; beyond it the response jumps to "
     "another branch."),
    ("PD (period doubling)", "A multiplier crosses -1: a period-2 response branches off "
     "(often the road to chaos)."),
    ("NS (Neimark-Sacker)", "A complex pair of multipliers crosses the unit circle: a torus "
     "(quasi-periodic motion) branches off."),
    ("grazing", "A contact just touches at one instant of the period: the onset of contact "
     "loss or impacts."),
    ("master modes, m = a+b+c", "The reduced model keeps m master modes: a and b of the "
     "shafts (or rotors) and c of the housing, chosen by the frequency criterion; m counts "
     "them all."),
    ("ERP", "Equivalent radiated power of the housing surface, rho c sum(v_n^2 A), in dB re "
     "1 pW."),
)
