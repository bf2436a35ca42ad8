"""``nnm``: nonlinear normal modes of a reduced model (impact pair or gearbox) by shooting and
pseudo-arclength continuation in energy (:mod:`vibrogear.solvers.periodic.nnm`).

The conservative model (damping and harmonic excitation removed, the static load kept:
:func:`~vibrogear.solvers.periodic.nnm_problem.conservative_model`) is linearised at its
static equilibrium; the start mode comes from ``[nnm]`` (:mod:`vibrogear.config.sections.nnm`);
its contact-switch ("onset") energy is the energy of the linear mode whose excursion first
brings a contact to a gap, E_on = omega^2 a_on^2 / 2 with a_on = min_j |delta_j,s - g_j| /
|c_j . phi|.  The result holds the backbone(s) in display units: the frequency (Hz for a
gearbox, the unit of Omega for the impact pair), the energy (J / model units), the monitored
contact's extrema in display units, stability and labels, and the orbits at
``shape_energies`` (one period sampled: modal coordinates and the monitored deformation).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..solvers.linear import contact_slopes
from ..config.base import ConfigError
from ..pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ..solvers.integrator.integrate import integrate
from ..solvers.periodic.nnm import nnm_branch
from ..solvers.periodic.nnm_problem import (conservative_model, linear_modes_at,
                                            onset_amplitude)
from ..solvers.static import static_equilibrium
from ..status import Outcome, Status
from .study import integration_options

__all__ = ["NnmStudyResult", "run", "start_mode"]


@dataclass(frozen=True, eq=False)
class NnmStudyResult:
    """What :mod:`vibrogear.report.writers.nnm` writes."""
    study: object
    branches: tuple                 # NnmBranch per start mode
    freq_scale: float               # display frequency = freq_scale * omega (model units)
    freq_key: str                   # "frequency_hz" (gearbox) or "omega" (impact pair)
    freq_label: str
    energy_scale: float             # display energy = energy_scale * model energy
    energy_unit: str
    onset_energy: tuple             # per branch, display units (inf: no contact switch)
    linear_frequencies: np.ndarray  # every elastic mode, display frequency
    delta_static: float             # monitored deformation at the static state (model)
    shapes: tuple = field(default=())   # dicts: branch, energy, t, x, delta
    conservative: object = None     # the conservative ReducedModel


def _mesh_shares(model, x_s, omega, phi, contact: int) -> np.ndarray:
    """Strain-energy share k' (c . phi)^2 / omega^2 of contact ``contact`` per mode (k' the
    contact law's slope at the static state, :func:`~..solvers.linear.contact_slopes`)."""
    k = float(contact_slopes(model, x_s)[0][contact])
    return k * (model.contacts.directions[contact] @ phi) ** 2 / omega ** 2


def start_mode(cfg, study, model, x_s, omega, phi, freq_scale) -> int:
    """The elastic-mode index [nnm] asks for (module docstring of the section).  The scene's
    validation (:meth:`~vibrogear.config.sections.nnm.NnmConfig.check_model`) has checked
    what the config decides: ``mesh`` names a mesh, the impact pair's one mode; a gearbox's
    number of elastic modes is known only here, after the reduction."""
    if cfg.mode is not None:
        if cfg.mode >= omega.size:          # needs the model: its elastic-mode count
            raise ConfigError("nnm.mode", f"expected an elastic-mode index 0 .. "
                              f"{omega.size - 1}, got {cfg.mode}")
        return int(cfg.mode)
    if cfg.frequency is not None:
        return int(np.argmin(np.abs(omega * freq_scale - cfg.frequency)))
    if omega.size == 1 or not model.contacts.count:
        return 0
    contact = model.monitor
    if cfg.mesh is not None:         # a mesh of [gearbox.meshes] (checked with the config)
        names = tuple(model.contacts.names)
        mesh_rows = study.contact_groups.get("mesh", ())
        contact = int(next(j for j in mesh_rows if names[j] == cfg.mesh))
    return int(np.argmax(_mesh_shares(model, x_s, omega, phi, contact)))


def _units(study, model):
    if model.length_unit == "m":
        return (1.0 / (2 * np.pi * model.time_unit_s), "frequency_hz", "frequency [Hz]",
                model.force_unit_n, "J")
    return 1.0, "omega", f"{study.param_name} (circular frequency)", 1.0, "model units"


def run(study, scene, ctx: RunContext) -> AnalysisOutcome:
    cfg = scene.nnm
    cfg.check_model(scene.impact_pair, scene.gearbox, "nnm")   # as the scene's validation
    t0 = time.perf_counter()
    cm, skew = conservative_model(study.model)
    st = static_equilibrium(cm, 0.0)
    if not st.converged:
        if study.strict_start:
            raise NumericalFailure(f"nnm: static equilibrium of the conservative model: "
                                   f"{st.message}")
    us = st.u0 if st.converged else np.zeros(cm.n_states)
    m = cm.n_modes
    omega, phi, rigid = linear_modes_at(cm, us[:m])
    if omega.size == 0:
        raise NumericalFailure("nnm: the model has no elastic mode")
    fs, fkey, flabel, es, eunit = _units(study, cm)
    opts = integration_options(scene, section=cfg, study=study)
    first = start_mode(cfg, study, cm, us[:m], omega, phi, fs)
    modes = [first] + ([cfg.second_mode] if cfg.second_mode is not None
                       and cfg.second_mode != first else [])
    branches, onsets, notes, shapes = [], [], [], []
    mon = study.monitor
    d_s = float(cm.contacts.directions[cm.monitor] @ us[:m]) if cm.contacts.count else 0.0
    for b, j in enumerate(modes):
        if j >= omega.size:                 # needs the model: its elastic-mode count
            raise ConfigError("nnm.second_mode", f"expected an elastic-mode index 0 .. "
                              f"{omega.size - 1}, got {j}")
        a_on = onset_amplitude(cm, us[:m], phi[:, j])
        e_on = 0.5 * omega[j] ** 2 * a_on ** 2
        onsets.append(e_on * es)
        lo, hi, excursion_max = _energy_range(cfg, cm, phi[:, j], omega[j], e_on, es,
                                              mon.scale, us)
        _check_energy_floor(cfg, cm, us, lo, hi, es, eunit)
        method = cfg.method(energy_min=lo, energy_max=hi, integration=opts,
                            excursion_max=excursion_max, delta_static=d_s)
        with ctx.progress(cfg.max_points, f"nnm mode {j}") as bar:
            br = nnm_branch(cm, us, omega[j], phi[:, j], method, rigid=rigid, mode=j,
                            other_omegas=np.delete(omega, j),
                            callback=lambda p, bar=bar: bar.update(1, f"{p.omega * fs:.5g} "
                                                                      f"{fkey}"))
        if not br.points:
            raise NumericalFailure(f"nnm: mode {j}: {br.message}")
        branches.append(br)
        shapes += _shapes(cfg, cm, br, b, e_on, es, opts)
    wall = time.perf_counter() - t0
    if skew > 1e-12:
        notes.append(f"non-symmetric linear coupling stiffness (|skew| / |K| = {skew:.3g}) "
                     "symmetrised: the circulatory part is not conservative")
    result = NnmStudyResult(study=study, branches=tuple(branches), freq_scale=fs,
                            freq_key=fkey, freq_label=flabel, energy_scale=es,
                            energy_unit=eunit, onset_energy=tuple(onsets),
                            linear_frequencies=omega * fs, delta_static=d_s,
                            shapes=tuple(shapes), conservative=cm)
    return AnalysisOutcome(summary=_summary(result, wall, opts, cfg, rigid, notes),
                           result=result,
                           # a backbone that ends at its point budget or its range has ended
                           # well (each one's end is in branches[].status): the verb is ok
                           solver=Outcome.combine((b.outcome for b in branches), wall_s=wall,
                                                  status=Status.OK))


def _energy_range(cfg, cm, phi, om, e_on, es, mon_scale, us):
    """(energy_min, energy_max, excursion_max) in model units: an amplitude range ends at
    its excursion (energy_max unbounded), an energy range has no excursion bound (None)."""
    if cfg.amplitude_min is not None:
        if not cm.contacts.count:
            raise ConfigError("nnm.amplitude_min", "an amplitude range needs a monitored "
                              "contact; give energy_min / energy_max")
        c = cm.contacts.directions[cm.monitor]
        cphi = abs(float(c @ phi))
        if cphi == 0.0:
            raise ConfigError("nnm.amplitude_min", "the start mode does not move the "
                              "monitored contact; give an energy range")
        a = cfg.amplitude_min / mon_scale / cphi
        return 0.5 * om ** 2 * a ** 2, math.inf, cfg.amplitude_max / mon_scale
    if cfg.energy_unit == "onset":
        # needs the model: the config refuses the unloaded gearbox (every contact on its
        # switch, NnmConfig.check_model); a loaded model can still give 0 (a contact exactly
        # at its gap in the static state) or inf (a start mode that moves no contact)
        if not np.isfinite(e_on):
            raise ConfigError("nnm.energy_unit", "'onset': the start mode never makes a "
                              "contact switch (a linear model); give absolute energies")
        if not e_on > 0.0:
            raise ConfigError("nnm.energy_unit", "'onset': the static state sits on a "
                              "contact switch (a contact exactly at its gap, e.g. an unloaded "
                              "mesh), so the contact-switch energy is 0 and cannot scale the "
                              "range; give absolute energies")
        return cfg.energy_min * e_on, cfg.energy_max * e_on, None
    return cfg.energy_min / es, cfg.energy_max / es, None


#: the energy above the static state is a difference of terms of the size of the static
#: state's energy: below this fraction of them it is round-off (measured: 1e-16 of them)
ENERGY_FLOOR = 1e-10


def _check_energy_floor(cfg, cm, us, lo, hi, es, eunit) -> None:
    """A ConfigError naming the range's start where the start energy ``lo`` (model units)
    is below what the energy above the static state resolves in double precision
    (:data:`ENERGY_FLOOR` times the size of the static state's energy terms): the backbone
    there would be round-off (energies of either sign reported as orbits)."""
    m = cm.n_modes
    x = us[:m]
    size = abs(float(cm.forcing.F0 @ x)) + 0.5 * abs(float(x @ (cm.omega2 * x)))
    floor = ENERGY_FLOOR * size
    key = "amplitude_min" if cfg.amplitude_min is not None else "energy_min"
    if not (np.isfinite(lo) and lo < hi):
        raise ConfigError(f"nnm.{key}", f"the start energy {lo * es:.3g} {eunit} is not "
                          f"below the end energy {hi * es:.3g} {eunit} (model units overflow); "
                          f"lower {key}")
    if lo > floor:
        return
    raise ConfigError(f"nnm.{key}", f"the start energy {lo * es:.3g} {eunit} is below the "
                      f"{floor * es:.3g} {eunit} that the energy above the static state "
                      f"resolves ({ENERGY_FLOOR:g} of the static state's energy terms, "
                      f"{size * es:.3g} {eunit}): the orbits there are round-off; raise "
                      f"{key}")


def _shapes(cfg, cm, br, b, e_on, es, opts) -> list[dict]:
    """The orbits nearest each of ``shape_energies`` (in energy_unit), one period sampled."""
    out = []
    if not cfg.shape_energies:
        return out
    energies = br.array("energy")
    for e in cfg.shape_energies:
        target = e * e_on if cfg.energy_unit == "onset" else e / es
        k = int(np.argmin(np.abs(np.log(np.maximum(energies, 1e-300) / target))))
        p = br.points[k]
        t = np.linspace(0.0, p.period, cfg.shape_samples + 1)
        tr = integrate(cm, p.omega, p.u0, 0.0, p.period, t_eval=t, options=opts)
        x = tr.u[:, :cm.n_modes]
        delta = x @ cm.contacts.directions[cm.monitor] if cm.contacts.count else np.zeros(t.size)
        out.append({"branch": b, "index": k, "energy": p.energy, "omega": p.omega, "t": t,
                    "x": x, "delta": delta})
    return out


def _summary(r: NnmStudyResult, wall, opts, cfg, rigid, notes) -> dict:
    brs = []
    for b, br in enumerate(r.branches):
        om = br.array("omega")
        e = br.array("energy")
        stable = br.array("stable")
        brs.append({
            "mode": br.mode, f"linear_{r.freq_key}": br.omega_linear * r.freq_scale,
            "points": len(br.points), "status": br.status.text, "message": br.message,
            f"{r.freq_key}_range": [float(om.min() * r.freq_scale),
                                    float(om.max() * r.freq_scale)],
            f"energy_range_{r.energy_unit.replace(' ', '_')}":
                [float(e.min() * r.energy_scale), float(e.max() * r.energy_scale)],
            f"onset_energy_{r.energy_unit.replace(' ', '_')}": r.onset_energy[b],
            "low_energy_relative_frequency_error": float(abs(om[0] - br.omega_linear)
                                                         / br.omega_linear),
            "stable_points": int(stable.sum()), "unstable_points": int((~stable).sum()),
            "labels": [{"label": p.label, r.freq_key: p.omega * r.freq_scale,
                        "energy": p.energy * r.energy_scale}
                       for p in br.points if p.label],
            **br.counters, "wall_s": br.wall_time,
            "error_estimate": br.error_estimate,
        })
    return {"branches": brs, "free_coordinates": int(rigid.shape[1]),
            "rtol": opts.rtol, "tol": cfg.tol, "solver_wall_s": wall, "notes": notes,
            "error_estimate": {"max_periodicity_residual": max(
                (b["error_estimate"]["max_periodicity_residual"] or 0.0) for b in brs),
                "rtol": opts.rtol}}
