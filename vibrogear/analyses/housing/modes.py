"""Runner glue for housing scenes: ``modes`` (master modes + coupling values).

Under ``mpirun`` every rank computes; the files (:mod:`vibrogear.report.writers.housing`)
are written by rank 0 only.
"""
from __future__ import annotations

import resource

import numpy as np

from ...pipeline.outcome import AnalysisOutcome
from .compute import compute_modes

__all__ = ["run_modes", "modes_summary"]


def _expected_mass(res, cfg) -> float | None:
    """Independent mass: closed-form volume (parametric) or OCC's solid volume (STEP) x rho; a
    mesh file's tetrahedron volumes (same mesh, so only a consistency check); none for modes."""
    from ...geometry.housing import housing_volume

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


def run_modes(scene, ctx) -> AnalysisOutcome:
    """``modes`` analysis of a housing scene (its result: the housing modes)."""
    cfg = scene.housing
    res = compute_modes(cfg, cache=True)
    # one eigen-solve: its own outcome (the summary's status "truncated" and the solver's
    # message stay the housing's words)
    return AnalysisOutcome(summary=modes_summary(res, cfg), result=res, solver=res.outcome)
