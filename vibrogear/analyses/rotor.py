"""Runner glue for rotor scenes: ``modes`` and ``campbell`` analyses.

``run_modes`` writes ``modes.csv`` (supported rotor at ``[rotor.modes].speed_rpm``;
``frequency_hz`` is the natural frequency |lambda| / 2 pi, as in the gearbox's modes.csv,
``damped_frequency_hz`` Im(lambda) / 2 pi, both at full precision),
``master_modes.csv`` + ``master_modes.npz`` (free, non-rotating shaft: what modal synthesis
uses) and ``mode_shapes.png/.svg``; ``run_campbell`` writes ``campbell.csv``,
``critical_speeds.csv`` and ``campbell.png/.svg``.
"""
from __future__ import annotations

import csv
import time

import numpy as np

from ..models.rotor import build_rotor_model, master_modes
from ..pipeline.outcome import NumericalFailure
from ..solvers.rotor_campbell import campbell_diagram
from ..solvers.rotor_modes import MODE_TYPES, modal_energy_share, rotor_modes

__all__ = ["run_modes", "run_campbell"]


def _write_csv(path, header, rows):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(rows)


def run_modes(scene, ctx) -> dict:
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
    out = ctx.out
    _write_csv(out / "modes.csv",
               ["index", "frequency_hz", "damped_frequency_hz", "damping_ratio", "whirl",
                "whirl_ratio", "mode_type", "lateral_share", "axial_share", "torsional_share",
                "residual"],
               [[i + 1, repr(float(res.natural_frequencies_hz[i])),
                 repr(float(res.frequencies_hz[i])), f"{res.damping_ratios[i]:.6g}", res.whirl[i], f"{res.whirl_ratio[i]:.4f}",
                 res.mode_type[i], *(f"{v:.4f}" for v in res.energy_share[i]),
                 f"{res.residuals[i]:.2e}"] for i in range(res.frequencies_hz.size)])
    share = modal_energy_share(model, master.vectors)
    _write_csv(out / "master_modes.csv", ["index", "frequency_hz", "mode_type", "rigid_body"],
               [[i + 1, f"{f:.8g}", MODE_TYPES[int(np.argmax(share[i]))],
                 int(i < master.n_rigid)] for i, f in enumerate(master.frequencies_hz)])
    np.savez_compressed(out / "master_modes.npz", frequencies_hz=master.frequencies_hz,
                        vectors=master.vectors, node_z=model.node_z,
                        free_gear_dofs=np.array(model.free_gear_dofs, int),
                        n_rigid=master.n_rigid)
    plots = []
    if res.frequencies_hz.size:
        from ..report.rotor_plots import plot_mode_shapes
        plots = plot_mode_shapes(model, res, out / "mode_shapes", title=f"{scene.scene.name}: "
                                 f"mode shapes at {mc.speed_rpm:g} rpm")
    return {
        "status": res.status, "message": res.message, "n_dofs": model.n_dofs,
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
        "files": ["modes.csv", "master_modes.csv", "master_modes.npz",
                  *(p.name for p in plots)],
    }


def run_campbell(scene, ctx) -> dict:
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
    out = ctx.out
    n_lines = res.frequencies_hz.shape[1]
    header = ["speed_rpm"] + [f"{k}_{j + 1}" for j in range(n_lines)
                              for k in ("frequency_hz", "whirl", "mode_type", "damping_ratio")]
    rows = []
    for i, s in enumerate(res.speeds_rpm):
        row = [f"{s:.6g}"]
        for j in range(n_lines):
            row += [f"{res.frequencies_hz[i, j]:.8g}", res.whirl[i, j], res.mode_type[i, j],
                    f"{res.damping_ratios[i, j]:.6g}"]
        rows.append(row)
    _write_csv(out / "campbell.csv", header, rows)
    _write_csv(out / "critical_speeds.csv",
               ["order", "line", "speed_rpm", "frequency_hz", "whirl", "mode_type"],
               [[f"{c.order:g}", c.line + 1, f"{c.speed_rpm:.6g}", f"{c.frequency_hz:.6g}",
                 c.whirl, c.mode_type] for c in res.critical_speeds])
    from ..report.rotor_plots import plot_campbell
    plots = plot_campbell(res, out / "campbell", title=f"{scene.scene.name}: Campbell diagram")
    return {
        "status": res.status, "message": res.message, "n_speeds": int(speeds.size),
        "orders": list(res.orders), "n_basis": res.n_basis,
        "critical_speeds": [{"order": c.order, "speed_rpm": c.speed_rpm, "frequency_hz":
                             c.frequency_hz, "whirl": c.whirl, "mode_type": c.mode_type}
                            for c in res.critical_speeds],
        "error_estimates": {"max_modal_residual": res.max_residual,
                            "reduction_relative_eigenvalue_error": res.error_estimate},
        "timings_s": {"build": t_build, **res.timings},
        "files": ["campbell.csv", "critical_speeds.csv", *(p.name for p in plots)],
    }
