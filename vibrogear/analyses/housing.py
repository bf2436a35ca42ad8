"""Runner glue for housing scenes: ``modes`` (master modes + coupling values + outputs).

Under ``mpirun`` every rank computes, only rank 0 writes files.
"""
from __future__ import annotations

import csv
import os
import resource
import shutil
from pathlib import Path

import numpy as np

from ..pipeline.outcome import NumericalFailure

__all__ = ["run_modes", "is_root", "compute_modes", "modes_summary", "write_modes_outputs"]


def is_root() -> bool:
    return os.environ.get("OMPI_COMM_WORLD_RANK", os.environ.get("PMI_RANK", "0")) == "0"


def compute_modes(cfg, *, cache: bool = True):
    """housing_modes with geometry/solver failures turned into NumericalFailure (exit 1)."""
    from ..geometry.housing import MeshingError
    from ..models.housing import HousingSolveError
    from ..models.housing_run import housing_modes

    try:
        return housing_modes(cfg, cache=cache)
    except (MeshingError, HousingSolveError) as exc:
        raise NumericalFailure(f"housing: {exc}") from None


def _dominant(res) -> list[str]:
    v = res.preview_values
    out = []
    for i in range(res.n_modes):
        if v.ndim == 3 and i < v.shape[-1] and len(v):
            out.append("xyz"[int(np.argmax(np.sqrt((v[:, :, i] ** 2).mean(axis=0))))])
        else:
            out.append("")
    return out


def write_modes_outputs(res, out: Path, *, plot: bool = True) -> dict[str, str]:
    """modes.csv, housing_modes.npz (coupling data), shapes XDMF, PNG of the first modes."""
    out.mkdir(parents=True, exist_ok=True)
    files = {}
    dom = _dominant(res)
    with (out / "modes.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["index", "frequency_hz", "damping_ratio", "residual", "dominant_direction"])
        for i, f in enumerate(res.freqs_hz):
            w.writerow([i + 1, f"{f:.8g}", f"{res.damping_ratios[i]:.6g}", f"{res.residuals[i]:.3e}", dom[i]])
    files["modes"] = "modes.csv"
    np.savez(out / "housing_modes.npz", freqs_hz=res.freqs_hz, bore_values=res.bore_values,
             bore_points=res.bore_points, bore_centers=res.bore_centers, bore_axes=res.bore_axes,
             bore_center_values=res.bore_center_values, bore_n_points=np.array(res.bore_n_points),
             bore_names=np.array(res.bore_names), beta=res.beta, n_dofs=res.n_dofs)
    files["coupling"] = "housing_modes.npz"
    if res.shapes_path is not None and Path(res.shapes_path).is_file():
        src = Path(res.shapes_path)
        for ext in (".xdmf", ".h5"):
            s = src.with_suffix(ext)
            if s.is_file():
                shutil.copyfile(s, out / f"mode_shapes{ext}")
        files["shapes"] = "mode_shapes.xdmf"
    if plot and res.n_modes and len(res.preview_points):
        from ..report.housing_plots import plot_mode_previews
        plot_mode_previews(res, out / "housing_modes.png")
        files["plot"] = "housing_modes.png"
    return files


def _expected_mass(res, cfg) -> float | None:
    """Independent mass: closed-form volume (parametric) or OCC's solid volume (STEP) x rho; a
    mesh file's tetrahedron volumes (same mesh, so only a consistency check); none for modes."""
    from ..geometry.housing import housing_volume

    if cfg.source == "parametric":
        return housing_volume(cfg) * cfg.material.rho
    vol = (res.source_info or {}).get("volume_m3")
    return vol * cfg.material.rho if vol else None


def modes_summary(res, cfg) -> dict:
    expected = _expected_mass(res, cfg)
    return {
        "source": dict(res.source_info or {"source": cfg.source}),
        "status": res.status if res.status != "ok" else "ok",
        "message": res.message,
        "n_dofs": res.n_dofs,
        "degree": res.degree,
        "n_modes": res.n_modes,
        "n_processes": res.n_processes,
        "frequencies_hz": [float(f) for f in res.freqs_hz],
        "timings_s": dict(res.timings),
        "error_estimates": {
            "max_eigen_residual": float(res.residuals.max()) if res.n_modes else None,
            "mass_orthonormality_error": res.orthogonality_error,
            "mass_vs_closed_form_rel": (abs(res.mass_kg - expected) / expected
                                        if expected and np.isfinite(res.mass_kg) else None),
            "converged_reason": res.converged_reason,
            "n_converged": res.n_converged,
            "coupling_points_by_fallback": res.n_fallback_points,
        },
        "mass_kg": res.mass_kg,
        "peak_memory_mb": res.peak_memory_mb,
        "peak_memory_mb_this_process": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "cached": res.cached,
        "cache_key": res.cache_key,
        "bores": [{"name": n, "n_points": k, "center": [float(c) for c in res.bore_centers[i]]}
                  for i, (n, k) in enumerate(zip(res.bore_names, res.bore_n_points))],
    }


def run_modes(scene, ctx) -> dict:
    """``modes`` analysis of a housing scene."""
    cfg = scene.housing
    res = compute_modes(cfg, cache=True)
    summary = modes_summary(res, cfg)
    if is_root():
        summary["files"] = write_modes_outputs(res, ctx.out)
    return summary
