"""The description of a study of a reduced model: what every analysis verb (time response,
sweep, continuation, ...) needs, and the only thing that differs between an impact pair and a
gearbox.

A :class:`Study` holds the :class:`~vibrogear.models.reduced.ReducedModel`, how to get its
start state at a parameter value (the static equilibrium under the mean load, paper eq. (9)),
the parameter's name and unit (``Omega`` for the impact pair, ``rpm`` for gearboxes), the
monitored quantity with its display unit, the model's time and force units, and a
fingerprint of its physics (for resuming).  The verbs are written once against it.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from ..config.options import IntegrationOptions, Parameter
from ..models.reduced import ReducedModel
from ..pipeline.outcome import NumericalFailure
from ..pipeline.resume import fingerprint

__all__ = ["Study", "Monitor", "build_study", "integration_options", "start_state",
           "within_limit", "lowest_param",
           "tolerances_for", "rtol_given", "ACCURACY_RULE", "ATOL_PER_RTOL",
           "ATOL_PER_RTOL_BY_MODEL", "atol_for"]


@dataclass(frozen=True)
class Monitor:
    """The monitored quantity: contact ``contact``'s deformation delta = c.x - e(t), shown
    as ``scale * delta`` in ``unit``; ``lines``: reference values in display units (zero line,
    clearance bounds)."""
    contact: int
    label: str
    unit: str
    scale: float = 1.0
    lines: tuple[float, ...] = ()
    zero_line: bool = False
    name: str = ""              # the contact's name (a gearbox mesh: "G1")

    def axis_label(self, prefix: str = "") -> str:
        text = f"{prefix} {self.label}".strip()
        return f"{text} [{self.unit}]" if self.unit else text


@dataclass(frozen=True, eq=False)
class Study:
    model: ReducedModel
    title: str
    parameter: Parameter                 # the model's declaration: Omega | rpm
    monitor: Monitor
    length_unit: str = ""                # unit of the model's displacements ("" nondimensional)
    time_unit_s: float = 1.0             # one model time unit in seconds
    force_unit_n: float = 1.0            # one model force unit in N
    rate_unit: float = 1.0               # one model deformation rate unit in display units/s
    contact_groups: dict = field(default_factory=dict)   # "mesh"/"bearing:<name>" -> indices
    balance_arclength: bool = False      # scale the parameter by range/|u| in the arclength
    strict_start: bool = True            # no static equilibrium is a failure (else start at 0)
    gearbox: object = None               # GearboxModel of a gearbox study
    #: LoadPath of a gearbox study (:mod:`vibrogear.analyses.static_load`): summary "load_path"
    load_path: object = None
    #: what the run changed and why (tightened tolerances): summary.json "notes"
    notes: list = field(default_factory=list, compare=False)
    #: (param, requested rtol) -> RtolLimit, measured once per study (:func:`within_limit`)
    rtol_limits: dict = field(default_factory=dict, compare=False)

    @property
    def energy_unit(self) -> str:
        """Unit of the contact metrics' impact energies (``rattle_<mesh>``)."""
        return "J" if self.length_unit == "m" else "model units"

    @property
    def param_name(self) -> str:
        return self.parameter.name

    @property
    def param_unit(self) -> str:
        return self.parameter.unit

    @property
    def param_label(self) -> str:
        return self.parameter.label

    @property
    def physics(self) -> str:
        """Content hash of everything in the reduced model (for resume signatures)."""
        return fingerprint(self.model)

    def start(self, param: float) -> np.ndarray:
        return start_state(self.model, param, strict=self.strict_start)


def start_state(model: ReducedModel, param: float, *, strict: bool = True) -> np.ndarray:
    """The static equilibrium [x, 0] at ``param`` (velocities zero, mean load)."""
    from ..solvers.static import static_equilibrium

    st = static_equilibrium(model, param)
    if st.converged:
        return st.u0
    if not strict:
        return np.zeros(model.n_states)
    raise NumericalFailure(f"static equilibrium at {model.param_name} = {param:g}: {st.message} "
                           f"(residual {st.residual:.3g} after {st.iterations} iterations)")


#: err = coefficient * rtol ** exponent: the error of the monitored mesh deformation over a
#: record window, max |delta - delta_ref| / (max delta_ref - min delta_ref), measured on nine
#: settled, non-chaotic points of gear_pair (4600-7000 rpm) and single_stage (2500-5500 rpm)
#: at rtol 1e-3 ... 1e-8 against rtol = 1e-10 from the same static state (least-squares fit
#: of benchmarks/calibrate_tolerance.py: err = 0.238 rtol^0.991, worst point 6.8x above the
#: fit, results/calibrate_tolerance.json).  The safety factor 10 divides the accuracy asked
#: for: it covers that worst point with a margin of 1.5.  (two_stage rattles chaotically over
#: its whole speed range: its error stays 0.3-0.7 at every rtol, so no rule exists for it.)
ACCURACY_RULE = {"coefficient": 0.238, "exponent": 0.991, "safety": 10.0}
#: atol / rtol by model kind, the one rule for every analysis that sets an rtol: the size of
#: the model's states (a gearbox's modal coordinates ~1e-6, the gearbox scenes' 1e-12 / 1e-6;
#: the impact pair's nondimensional ones ~1e-2, its scenes' 1e-10 / 1e-8)
ATOL_PER_RTOL_BY_MODEL = {"gearbox": 1e-6, "impact_pair": 1e-2}
#: the gearbox's (the accuracy rule's)
ATOL_PER_RTOL = ATOL_PER_RTOL_BY_MODEL["gearbox"]


def atol_for(model_kind: str, rtol: float) -> float:
    """atol that goes with ``rtol`` on a model of this kind (:data:`ATOL_PER_RTOL_BY_MODEL`)."""
    return ATOL_PER_RTOL_BY_MODEL.get(model_kind, ATOL_PER_RTOL) * rtol
#: the rule's rtol is kept inside this range
RTOL_RANGE = (1e-10, 1e-3)


def tolerances_for(accuracy: float) -> tuple[float, float]:
    """(rtol, atol) that deliver ``accuracy``: the loosest rtol whose fitted error
    (:data:`ACCURACY_RULE`) times the safety factor is ``accuracy``, within
    :data:`RTOL_RANGE`."""
    c, p, s = (ACCURACY_RULE[k] for k in ("coefficient", "exponent", "safety"))
    rtol = (accuracy / (s * c)) ** (1.0 / p)
    rtol = float(min(max(rtol, RTOL_RANGE[0]), RTOL_RANGE[1]))
    return rtol, ATOL_PER_RTOL * rtol


def rtol_given(scene) -> bool:
    """Whether the scene sets [integration] rtol: a value other than the built-in default
    (the scene object does not keep which keys were written, so an rtol equal to the
    default, 1e-9, counts as not given)."""
    return scene.integration.rtol != IntegrationOptions.__dataclass_fields__["rtol"].default


def integration_options(scene, *, record: bool = False, period_tol: float | None = None,
                        section=None, study: "Study | None" = None) -> IntegrationOptions:
    """The integrator's options of one analysis: the one rule, in this order.

    1. ``section.rtol`` where the analysis's own section has one and it is set ([continuation],
       [reduction_accuracy], [map], [runup], [nnm]): that rtol, atol = :func:`atol_for`.
    2. ``record=True`` (sweep, map, run-up, time response, spectra: results read from recorded
       motion) on a gearbox scene whose [integration] rtol is not given (:func:`rtol_given`):
       rtol and atol from the accuracy asked for (``section.accuracy`` where the section has
       one, else ``[sweep] accuracy``, default 1e-3: the error of the monitored mesh
       deformation relative to its range over the record window) by :func:`tolerances_for`,
       no looser than ``period_tol`` where given (the Poincare-sample tolerance: integration
       error alone must not make a periodic point look not periodic).
    3. Otherwise the [integration] section as written (shooting and continuation without
       their own rtol; an explicit [integration] rtol wins over the accuracy rule).

    With ``study``, the rtol so chosen is then held to the loosest the model can use
    (:func:`within_limit`: measured, tightened with a note in summary.json)."""
    opts = _requested_options(scene, record, period_tol, section)
    return opts if study is None else within_limit(study, scene, opts)


def _requested_options(scene, record, period_tol, section) -> IntegrationOptions:
    opts = scene.integration
    own = getattr(section, "rtol", None)
    if own is not None:
        return dataclasses.replace(opts, rtol=own, atol=atol_for(scene.model_kind, own))
    if not record or scene.gearbox is None or rtol_given(scene):
        return opts
    from ..config.options import SweepOptions

    acc = getattr(section, "accuracy", None) or getattr(scene.sweep, "accuracy", None) or \
        SweepOptions.__dataclass_fields__["accuracy"].default
    rtol, _ = tolerances_for(acc)
    rtol = rtol if period_tol is None else min(rtol, period_tol)
    return dataclasses.replace(opts, rtol=rtol, atol=ATOL_PER_RTOL * rtol)


#: requested rtols at or below this are used as asked (no probe): the probe's ladder and the
#: checks after every run (solvers/integrator/trust.py) cover them
RTOL_PROBE_FROM = 1e-5
_SECTIONS = ("time_response", "sweep", "continuation", "map", "runup", "nvh",
             "reduction_accuracy")
_PARAM_KEYS = ("param_min", "param", "rpm_start", "rpm_end")


def lowest_param(scene) -> float | None:
    """The lowest parameter value any of the scene's sections asks for (the most demanding
    for the integrator: the excitation lies lowest under the fastest master mode)."""
    values = []
    for name in _SECTIONS:
        sec = getattr(scene, name, None)
        for key in _PARAM_KEYS:
            v = getattr(sec, key, None) if sec is not None else None
            if isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0:
                values.append(float(v))
    return min(values) if values else None


def within_limit(study: "Study", scene, opts: IntegrationOptions) -> IntegrationOptions:
    """``opts`` with rtol no looser than the loosest this model can use (measured once per
    study by :func:`vibrogear.solvers.integrator.rtol_limit.loosest_rtol` at the scene's lowest
    parameter); a tightened rtol is noted in ``study.notes`` (summary.json "notes")."""
    if opts.rtol <= RTOL_PROBE_FROM:
        return opts
    param = lowest_param(scene)
    if param is None:
        return opts
    from ..solvers.integrator.rtol_limit import loosest_rtol

    key = (param, opts.rtol)
    limit = study.rtol_limits.get(key)
    if limit is None and any(k[0] == param and v.rtol is not None and v.rtol >= opts.rtol
                             for k, v in study.rtol_limits.items()):
        return opts     # a probe up to a looser rtol passed every rung down to this one
    if limit is None:
        limit = study.rtol_limits[key] = loosest_rtol(study.model, param, study.start(param),
                                                      up_to=opts.rtol, options=opts)
    if limit.rtol is None or limit.rtol >= opts.rtol:
        return opts
    note = (f"rtol {opts.rtol:g} tightened to {limit.rtol:g}: "
            f"{limit.describe(study.param_name)}")
    if note not in study.notes:
        study.notes.append(note)
    return dataclasses.replace(opts, rtol=limit.rtol, atol=opts.atol * limit.rtol / opts.rtol)


def build_study(scene, source: str | None = None) -> Study:
    """The study of a scene's reduced model (impact pair or gearbox); ``source``: the scene
    file (its mapping report's assumptions go with the load path)."""
    if scene.impact_pair is not None:
        return _impact_pair_study(scene)
    if scene.gearbox is not None:
        return _gearbox_study(scene, source)
    raise NotImplementedError(f"no reduced model for a {scene.model_kind} scene")


def _impact_pair_study(scene) -> Study:
    from ..models.impact_pair import impact_pair_from_config

    c = scene.impact_pair
    title = (f"{scene.scene.name}: zeta={c.zeta:g}, kappa={c.kappa:g}, f_m={c.f_m:g}, "
             f"f_p={c.f_p:g}, b_r={c.b_r:g}")
    return Study(model=impact_pair_from_config(c), title=title, parameter=scene.parameter,
                 strict_start=False,
                 monitor=Monitor(contact=0, label="q", unit="", lines=(-c.b_r, c.b_r)),
                 contact_groups={"clearance": np.array([0])})


def _gearbox_study(scene, source=None) -> Study:
    from .static_load import static_load

    # the load carried checked and met before any dynamics (ConfigError: exit 2)
    loaded = static_load(scene, source=source)
    gm = loaded.model
    r = gm.reduced
    mesh = gm.contact_indices("mesh")
    groups = {"mesh": mesh}
    for j, c in enumerate(gm.contacts):
        if c.kind == "bearing":
            groups.setdefault(f"bearing:{c.group}", []).append(j)
    groups = {k: np.asarray(v, dtype=int) for k, v in groups.items()}
    back = scene.gearbox.meshes[0].backlash if scene.gearbox.meshes else 0.0
    parts = "+".join(str(s.n_modes) for s in gm.subsystems)
    name = gm.contacts[r.monitor].name if gm.contacts else "mesh"
    return Study(model=r, title=f"{scene.scene.name}: m = {r.n_modes} ({parts})",
                 parameter=scene.parameter,
                 monitor=Monitor(contact=r.monitor, label=f"{name} mesh deformation", unit="um",
                                 scale=1e6, lines=(-back * 1e6,), zero_line=True, name=name),
                 length_unit=r.length_unit, time_unit_s=r.time_unit_s,
                 force_unit_n=r.force_unit_n,
                 rate_unit=gm.omega_ref, contact_groups=groups, balance_arclength=True,
                 strict_start=True, gearbox=gm, load_path=loaded.load_path)
