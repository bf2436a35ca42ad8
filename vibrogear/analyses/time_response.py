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

__all__ = ["TimeResponseResult", "run", "working_flank_losses"]


@dataclass(frozen=True, eq=False)
class TimeResponseResult:
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
        return self.t * self.study.time_unit_s


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
