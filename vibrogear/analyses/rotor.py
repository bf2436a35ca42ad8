"""Runner glue for rotor scenes: ``modes`` and ``campbell`` analyses.

``run_modes`` computes the supported rotor's modes at ``[rotor.modes].speed_rpm`` and the
free, non-rotating shaft's master modes (what modal synthesis uses); ``run_campbell`` the
Campbell diagram and critical speeds.  Their files (``modes.csv``, ``master_modes.csv/.npz``,
``mode_shapes.png/.svg``; ``campbell.csv``, ``critical_speeds.csv``, ``campbell.png/.svg``)
are written by :mod:`vibrogear.report.writers.rotor`.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..models.rotor.model import build_rotor_model, master_modes
from ..pipeline.outcome import AnalysisOutcome, NumericalFailure
from ..solvers.rotor.campbell import campbell_diagram
from ..solvers.rotor.modes import MODE_TYPES, modal_energy_share, rotor_modes

__all__ = ["run_modes", "run_campbell", "RotorModesResult", "RotorCampbellResult"]


@dataclass(frozen=True, eq=False)
class RotorModesResult:
    """The rotor model, its modes at ``speed_rpm`` (``modes``), the master modes and their
    types by modal energy share (``master_types``: lateral / axial / torsional), and the
    figure title."""
    model: Any
    modes: Any
    master: Any
    master_types: tuple[str, ...]
    title: str


@dataclass(frozen=True, eq=False)
class RotorCampbellResult:
    """The Campbell diagram (``campbell``) and the figure title."""
    campbell: Any
    title: str


def run_modes(scene, ctx) -> AnalysisOutcome:
    cfg = scene.rotor
    t0 = time.perf_counter()
    model = build_rotor_model(cfg)
    t_build = time.perf_counter() - t0
    mc = cfg.modes
    count = None if mc.cutoff_hz is not None else mc.count
    res = rotor_modes(model, mc.speed_rpm, count=count, cutoff_hz=mc.cutoff_hz)
    if res.status == "failed":
        raise NumericalFailure(f"rotor modes at {mc.speed_rpm:g} rpm: {res.message}")
    mcount = None if mc.master_cutoff_hz is not None else mc.master_count
    t1 = time.perf_counter()
    master = master_modes(model, count=mcount, cutoff_hz=mc.master_cutoff_hz)
    t_master = time.perf_counter() - t1
    result = RotorModesResult(model=model, modes=res, master=master,
                              master_types=tuple(MODE_TYPES[i] for i in np.argmax(
                                  modal_energy_share(model, master.vectors), axis=1)),
                              title=f"{scene.scene.name}: mode shapes at {mc.speed_rpm:g} rpm")
    summary = {
        "n_dofs": model.n_dofs,
        "n_elements": int(model.element_nodes.shape[0]), "speed_rpm": mc.speed_rpm,
        "frequencies_hz": res.natural_frequencies_hz.tolist(),
        "damped_frequencies_hz": res.frequencies_hz.tolist(), "whirl": list(res.whirl),
        "mode_type": list(res.mode_type), "damping_ratios": res.damping_ratios.tolist(),
        "n_rigid_supported": res.n_rigid, "method": res.method, "n_basis": res.n_basis,
        "master_modes": {"count": int(master.frequencies_hz.size), "n_rigid": master.n_rigid,
                         "max_frequency_hz": float(master.frequencies_hz.max())},
        "error_estimates": {"max_modal_residual": float(res.residuals.max(initial=0.0)),
                            "reduction_relative_eigenvalue_error": res.error_estimate},
        "timings_s": {"build": t_build, **res.timings, "master_modes": t_master},
    }
    return AnalysisOutcome(summary=summary, result=result, solver=res.outcome)


def run_campbell(scene, ctx) -> AnalysisOutcome:
    cfg = scene.rotor
    cc = cfg.campbell
    if cc is None:
        from ..config.base import ConfigError
        raise ConfigError("rotor.campbell", "missing section: the campbell analysis needs "
                          "[rotor.campbell] with rpm_max")
    t0 = time.perf_counter()
    model = build_rotor_model(cfg)
    t_build = time.perf_counter() - t0
    speeds = np.linspace(cc.rpm_min, cc.rpm_max, cc.n_speeds)
    with ctx.progress(cc.n_speeds, "campbell") as bar:
        res = campbell_diagram(model, speeds, n_modes=cc.n_modes, orders=cc.orders,
                               callback=lambda i, rpm: bar.update(1))
    if res.status == "failed":
        raise NumericalFailure(f"rotor Campbell diagram: {res.message}")
    result = RotorCampbellResult(campbell=res,
                                 title=f"{scene.scene.name}: Campbell diagram")
    summary = {
        "n_speeds": int(speeds.size),
        "orders": list(res.orders), "n_basis": res.n_basis,
        "critical_speeds": [{"order": c.order, "speed_rpm": c.speed_rpm, "frequency_hz":
                             c.frequency_hz, "whirl": c.whirl, "mode_type": c.mode_type}
                            for c in res.critical_speeds],
        "error_estimates": {"max_modal_residual": res.max_residual,
                            "reduction_relative_eigenvalue_error": res.error_estimate},
        "timings_s": {"build": t_build, **res.timings},
    }
    return AnalysisOutcome(summary=summary, result=result, solver=res.outcome)
