"""The one registry of verbs: name -> option section, model kinds, analysis, report writer, files.

Scene validation (:mod:`.scene`: which section a verb needs, which models support it), the
list of analyses a scene may name (:mod:`.sections.common`), the runner's table of analyses
and report writers, the CLI's single-analysis commands and help, and the README's verb table
(:func:`verb_table_markdown`; a test keeps the README equal to it) all read this table.

Adding a verb is one analysis module (``analyses/<name>.py``, or a wing ``analyses/<name>/``
whose ``__init__`` names its public functions) returning an ``AnalysisOutcome``, one report
writer of the same name (``report/writers/<name>.py``) writing its files and one entry here; an
option section also needs its dataclass under :mod:`.sections.common` and a field of the scene
(``docs/architecture.md``, "Adding a verb").

Targets are ``"module:function"`` strings relative to ``vibrogear.analyses`` and
``vibrogear.report``: this module imports nothing above the config layer, and an analysis's
modules are imported only when a scene runs it.
"""
from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["Run", "Verb", "VERBS", "MODEL_KINDS", "verb_table_markdown"]

#: model sections a scene may have (exactly one)
MODEL_KINDS = ("impact_pair", "gearbox", "rotor", "housing")


@dataclass(frozen=True)
class Run:
    """How one model kind runs a verb."""
    analysis: str                 # "module:function" under vibrogear.analyses
    report: str                   # "module:function" under vibrogear.report
    outputs: tuple[str, ...]      # the main files it writes (besides summary.json, report.html)
    study: bool = False           # takes the scene's reduced-model Study (analyses/study.py)


@dataclass(frozen=True)
class Verb:
    name: str                     # as listed in [scene] analyses
    help: str                     # one line, for the CLI and the README
    section: str | None           # the option section it needs (None: none)
    runs: dict[str, Run] = field(default_factory=dict)   # model kind -> Run
    command: str | None = None    # ``vibrogear COMMAND SCENE`` runs this verb alone
    #: verbs whose saved result it reads when they did not run in this run: the runner loads
    #: their main file from the output folder into ``previous`` (e.g. ``vibrogear continue``
    #: after ``vibrogear sweep`` into the same folder)
    reads_saved: tuple[str, ...] = ()
    #: verbs whose outcome it needs: where one is not in this run before it, that verb's
    #: analysis runs first for it alone (its outcome goes to ``previous``; no files, no
    #: summary entry), so that no analysis calls another (analyses/invoke.py)
    needs: tuple[str, ...] = ()

    @property
    def models(self) -> tuple[str, ...]:
        return tuple(self.runs)


def _both(analysis: str, report: str, outputs: tuple[str, ...]) -> dict[str, Run]:
    """The same analysis for the impact pair and a gearbox (both reduced models with a Study)."""
    run = Run(analysis, report, outputs, study=True)
    return {"impact_pair": run, "gearbox": run}


_VERBS = (
    Verb("time_response", "time response from the initial state", "time_response",
         _both("time_response:run", "writers.time_response:write",
               ("time_response.npz", "time_response.csv", "time_response.png")), command="time"),
    Verb("sweep", "sequential continuation (brute-force bifurcation diagram) up and down in the "
         "parameter", "sweep",
         _both("sweep:run", "writers.sweep:write", ("sweep.npz", "sweep.csv", "bifurcation.png")),
         command="sweep"),
    Verb("continuation", "shooting + pseudo-arclength continuation of periodic orbits with Floquet "
         "stability", "continuation",
         _both("continuation:run", "writers.continuation:write",
               ("branch.npz", "branch.csv", "branch_max.png", "branch_min.png")), command="continue",
         reads_saved=("sweep",)),
    Verb("nnm", "nonlinear normal modes: backbones of the conservative model by continuation",
         "nnm", _both("nnm:run", "writers.nnm:write",
                      ("nnm.npz", "nnm.csv", "nnm_fep.png", "nnm_backbone.png")),
         command="nnm"),
    Verb("report", "work-precision study: integrator tolerance and shooting residual against run "
         "time", "report",
         {"impact_pair": Run("precision:run_report", "writers.precision:write",
                             ("work_precision.csv", "work_precision.png", "shooting_precision.csv",
                              "shooting_precision.png"))}, command="report"),
    Verb("critical_damping", "bisection in zeta for the damping where the primary-resonance folds "
         "meet", "critical_damping",
         {"impact_pair": Run("critical_damping:run_critical_damping", "writers.critical_damping:write",
                             ("critical_damping.json", "critical_damping.png"))}),
    Verb("modes", "modal analysis (gearbox, rotor or housing)", None,
         {"gearbox": Run("gearbox_modes:run", "writers.gearbox_modes:write",
                         ("modes.csv", "resonance_map.png"), study=True),
          "rotor": Run("rotor:run_modes", "writers.rotor:write_modes",
                       ("modes.csv", "master_modes.npz", "master_modes.csv")),
          "housing": Run("housing.modes:run_modes", "writers.housing:write_modes",
                         ("housing_modes.npz", "modes.csv", "housing_modes.png"))}, command="modes"),
    Verb("campbell", "Campbell diagram of a rotor", None,
         {"rotor": Run("rotor:run_campbell", "writers.rotor:write_campbell",
                       ("campbell.csv", "critical_speeds.csv"))}, command="campbell"),
    Verb("housing_sweep", "housing geometry sweep: first frequencies against one housing parameter",
         "housing_sweep",
         {"housing": Run("housing.sweep:run_sweep", "writers.housing:write_sweep",
                         ("housing_sweep.csv", "housing_sweep.png"))}),
    Verb("housing_convergence", "housing mesh convergence: frequency error vs DOF vs wall time, P1 "
         "and P2", "housing_convergence",
         {"housing": Run("housing.convergence:run_convergence", "writers.housing:write_convergence",
                         ("housing_convergence.csv", "housing_error_vs_time.png"))}),
    Verb("reduction_accuracy", "gearbox reduction level: frequency error, MAC and response error vs "
         "run time", "reduction_accuracy",
         {"gearbox": Run("reduction_accuracy:run_reduction_accuracy", "writers.reduction_accuracy:write",
                         ("reduction_levels.csv", "reduction_levels.json", "reduction_accuracy.png"),
                         study=True)}),
    Verb("nvh", "spectra of mesh deformations and forces, bearing forces; housing ERP and surface "
         "velocity", "nvh",
         {"gearbox": Run("nvh:run", "writers.nvh:write", ("spectra.npz", "erp.csv", "erp.png"),
                         study=True)}, command="nvh", needs=("modes",)),
    Verb("map", "speed x load operating map (sweeps over speed at each load) with LP/PD curves", "map",
         {"gearbox": Run("map:run", "writers.map:write",
                         ("map.npz", "map.csv", "map_curves.csv", "map_class.png"), study=True)},
         command="map"),
    Verb("runup", "run-up / run-down transient: envelopes, contact losses, order tracks, waterfall",
         "runup",
         {"gearbox": Run("runup:run", "writers.runup:write",
                         ("runup.npz", "runup.csv", "runup_envelope.png", "runup_waterfall.png"),
                         study=True)}, command="runup"),
    Verb("states", "every operating state at every speed: coexisting attractors from random "
         "starts, their basins with Wilson intervals, branches from each, the danger map", "states",
         _both("states:run", "writers.states:write", ("states.npz", "states.csv", "states.png")),
         command="states", reads_saved=("sweep", "continuation")),
    Verb("optimize", "design optimisation: the variables (any --set key) that minimise or "
         "maximise an analysis's metric under constraints", "optimize",
         {kind: Run("optimize:run", "writers.optimize:write",
                    ("optimize.csv", "optimize.json", "best_scene.toml",
                     "optimize_convergence.png")) for kind in MODEL_KINDS}, command="optimize"),
)

#: verb name -> Verb, in the order the README and the CLI help list them
VERBS: dict[str, Verb] = {v.name: v for v in _VERBS}


def verb_table_markdown() -> str:
    """The README's verb table (kept equal to this registry by a test)."""
    rows = ["| verb | command | models | option section | what it does | main files |",
            "| --- | --- | --- | --- | --- | --- |"]
    for v in VERBS.values():
        files = list(dict.fromkeys(f for r in v.runs.values() for f in r.outputs))
        rows.append(f"| `{v.name}` | {f'`vibrogear {v.command}`' if v.command else '-'} | "
                    f"{', '.join(v.models)} | {f'`[{v.section}]`' if v.section else '-'} | {v.help} | "
                    f"{', '.join(f'`{f}`' for f in files)} |")
    return "\n".join(rows) + "\n"
