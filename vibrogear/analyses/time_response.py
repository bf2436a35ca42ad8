"""Time response of a study's reduced model from its static equilibrium (paper eq. (9)).

Written once for every model: the study supplies the model, the start state, the
parameter's name and the units.  The result holds the sampled states and, for every
contact, its deformation, deformation rate and force in physical units (m, m/s, N for a
gearbox; nondimensional for the impact pair).

The summary counts, per mesh (or the impact pair's clearance), the contact losses over
the second half of the run: the times its working (upper) flank leaves contact, read
from the recorded samples (:func:`working_flank_losses`); a loss that closes again
between two samples is not seen, so ``samples_per_period`` sets the resolution.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..models.contact_law import flank
from ..solvers.integrator.contact_eval import contact_history
from ..pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ..solvers.integrator.integrate import integrate
from ..solvers.integrator.rtol_limit import loosest_rtol
from ..status import Status
from .study import Study, integration_options

__all__ = ["TimeResponseResult", "run", "working_flank_losses", "STATES_IN_NPZ"]


#: the states go into time_response.npz when the model has at most this many
STATES_IN_NPZ = 64


@dataclass(frozen=True, eq=False)
class TimeResponseResult:
    """The time response of a study's reduced model from its static equilibrium.

    n samples, nc contacts (gear meshes, bearing elements; the impact pair's clearance),
    2m states.  Units: a gearbox's lengths in m, forces in N, times in s (its model time
    unit is 1 s); the impact pair's are nondimensional.

    Fields:

    - ``study``: the :class:`~vibrogear.analyses.study.Study` (model, parameter, units).
    - ``param``: the parameter value (driving-shaft speed in rpm, or Omega).
    - ``t``: (n,) [model time units] sample times; ``t_s`` (property): (n,) [s].
    - ``u``: (n, 2m) [model units: modal coordinates and their rates] the states.
    - ``delta``: (nc, n) [m] each contact's deformation (a mesh: the tooth deflection along
      the line of action; below 0 the working flank has lost contact).
    - ``delta_dot``: (nc, n) [m/s] its rate.
    - ``force``: (nc, n) [N] each contact's force.
    - ``period``: [model time units] the excitation (mesh) period.

    :meth:`arrays`: the arrays of ``time_response.npz`` (``t``, ``t_s``, ``delta``,
    ``delta_dot``, ``force``, ``names`` (nc,) of the contacts, and ``u`` with
    ``state_names`` for a model of at most 64 states); :meth:`plot`: its figure."""
    study: Study
    param: float
    t: np.ndarray              # (n,) model time
    u: np.ndarray              # (n, 2m) states
    delta: np.ndarray          # (nc, n) contact deformations [model length unit]
    delta_dot: np.ndarray      # (nc, n) rates [length unit / s]
    force: np.ndarray          # (nc, n) forces [N, or model units]
    period: float              # excitation period [model time]

    @property
    def t_s(self) -> np.ndarray:
        """(n,) [s] the sample times in seconds."""
        return self.t * self.study.time_unit_s

    @property
    def names(self) -> list[str]:
        """(nc,) the contacts' names (``G1``, a bearing element's, ``c0`` ...)."""
        ct = self.study.model.contacts
        return list(ct.names) or [f"c{j}" for j in range(ct.count)]

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays of ``time_response.npz``, by the same names (see the class docstring)."""
        model = self.study.model
        out = dict(t=self.t, t_s=self.t_s, delta=self.delta, delta_dot=self.delta_dot,
                   force=self.force, names=np.array(self.names, dtype=str))
        if model.n_states <= STATES_IN_NPZ:
            out.update(u=self.u, state_names=np.array(model.state_names, dtype=str))
        return out

    def plot(self):
        """The report's figure of this time response (``time_response.png``) as a
        matplotlib Figure: a gearbox's mesh deformations, phase trajectories, mesh and
        bearing forces; the impact pair's deformation and phase trajectory."""
        from ..report.plots.time_response import time_response_figure
        return time_response_figure(self)


def working_flank_losses(delta, gap_hi: float, gap_lo: float) -> int:
    """Times the working flank leaves contact in the sampled deformation ``delta`` (n,):
    the samples where the flank mode (:func:`~vibrogear.models.contact_law.flank`) goes
    from +1 (working flank in contact) to 0 or -1 at the next sample."""
    on = flank(np.asarray(delta, dtype=float), gap_hi, gap_lo) > 0
    return int(np.count_nonzero(on[:-1] & ~on[1:]))


def run(study: Study, scene, ctx: RunContext) -> AnalysisOutcome:
    cfg = scene.time_response
    model = study.model
    param = float(cfg.param if hasattr(cfg, "param") else cfg.omega)
    T = model.base_period(param)     # periods count mesh periods, also with torque orders
    n = int(round(cfg.periods * cfg.samples_per_period))
    t_eval = np.linspace(0.0, cfg.periods * T, n + 1)
    opts = integration_options(scene, record=True, study=study)
    tr = integrate(model, param, study.start(param), 0.0, cfg.periods * T, t_eval=t_eval,
                   options=opts)
    if not tr.ok:
        hint = ""
        if tr.status in (Status.DIVERGED, Status.INACCURATE):
            lim = loosest_rtol(model, param, study.start(param), up_to=opts.rtol, options=opts)
            hint = f"; {lim.describe(study.param_name)}"
        raise NumericalFailure(f"time response at {study.param_name} = {param:g}: "
                               f"{tr.message}{hint}")
    delta, ddot, force = contact_history(model, param, tr.t, tr.u)
    result = TimeResponseResult(study=study, param=param, t=tr.t, u=tr.u, delta=delta,
                                delta_dot=ddot * study.rate_unit,
                                force=force * study.force_unit_n, period=T)
    names = model.contacts.names or tuple(f"c{j}" for j in range(model.contacts.count))
    half = tr.t >= 0.5 * tr.t[-1]
    primary = study.contact_groups.get("mesh", study.contact_groups.get("clearance", []))
    ct = model.contacts
    losses = {names[j]: working_flank_losses(delta[j, half], ct.gap_hi[j], ct.gap_lo[j])
              for j in primary}
    # status, message, counters, wall time and the integrator's error estimate: the runner's
    # spine, from tr.outcome; here the domain entries and the tolerances used
    summary = {
        study.param_name: param, "periods": cfg.periods,
        "excitation_frequency_hz": model.excitation_frequency(param) / (2 * np.pi)
        / study.time_unit_s,
        "deformation_unit": study.length_unit,
        "deformation_second_half": {names[j]: [float(delta[j, half].min()),
                                               float(delta[j, half].max())] for j in primary},
        "contact_losses_second_half": losses,
        "error_estimate": {"rtol": opts.rtol, "atol": opts.atol},
    }
    return AnalysisOutcome(summary=summary, result=result, solver=tr.outcome)
