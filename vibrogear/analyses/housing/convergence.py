"""Housing mesh convergence and frequency error against run time (``housing_convergence``).

P2 meshes at the configured size factors give a Richardson-extrapolated reference per mode
(observed order fitted from the three finest levels); P1 and P2 runs are then placed on an
error / DOF / wall-time chart, and the cheapest run within ``target_error`` is named.  The
files (``housing_convergence.csv``, ``housing_error_vs_time.png``) are written by
:mod:`vibrogear.report.writers.housing`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...pipeline.outcome import AnalysisOutcome
from ...status import Outcome
from .compute import compute_modes

__all__ = ["observed_order", "richardson", "run_convergence", "with_mesh",
           "HousingConvergenceResult"]


@dataclass(frozen=True, eq=False)
class HousingConvergenceResult:
    """One row (dict: degree, size, n_dofs, freqs, fe_seconds, rel_errors, max_rel_error,
    ...) per run, the number of frequencies compared and the target error."""
    rows: tuple
    n_freqs: int
    target_error: float


def observed_order(f: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Order p of f(h) = f0 + C h^p from three levels (rows of ``f``, coarse to fine).

    Solves (f1 - f2) / (f2 - f3) = (h1^p - h2^p) / (h2^p - h3^p) by bisection (any ratios);
    NaN where the differences change sign (not monotone).
    """
    f = np.asarray(f, dtype=float)
    h = np.asarray(h, dtype=float)
    d1, d2 = f[0] - f[1], f[1] - f[2]
    out = np.full(f.shape[1:], np.nan)
    for idx in np.ndindex(out.shape):
        a, b = d1[idx], d2[idx]
        if a == 0 or b == 0 or np.sign(a) != np.sign(b):
            continue
        target = a / b

        def g(p):
            return (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p) - target

        lo, hi = 1e-3, 20.0
        if g(lo) * g(hi) > 0:
            continue
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if g(lo) * g(mid) <= 0:
                hi = mid
            else:
                lo = mid
        out[idx] = 0.5 * (lo + hi)
    return out


def richardson(f: np.ndarray, h: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Extrapolated f0 from the two finest levels with order p."""
    f = np.asarray(f, dtype=float)
    r = h[-2] / h[-1]
    return f[-1] - (f[-2] - f[-1]) / (r ** np.asarray(p) - 1.0)


def with_mesh(cfg, *, size: float | None = None, degree: int | None = None, refine: int | None = None,
              count: int | None = None):
    """A copy of the housing config with other mesh settings (validated)."""
    from ...config.base import build
    from ...config.base import as_data
    from ...config.model.housing import HousingConfig

    d = as_data(cfg)
    if size is not None:
        d["mesh"]["size"] = size
        d["mesh"].pop("bore_size", None)
    if degree is not None:
        d["mesh"]["degree"] = degree
    if refine is not None:
        d["mesh"]["refine"] = refine
    if count is not None:
        d["modes"] = {**d["modes"], "count": count, "shapes": 0}
        d["modes"].pop("cutoff_hz", None)
    return build(HousingConfig, d, "housing")


def _fe_seconds(res) -> float:
    t = res.timings
    return sum(t.get(k, 0.0) for k in ("meshing", "mesh_read", "assembly", "eigensolve", "postprocess"))


def run_convergence(scene, ctx) -> AnalysisOutcome:
    """Error vs DOF vs wall time for P1 and P2; Richardson reference from P2."""
    opts = scene.housing_convergence
    cfg = scene.housing
    n = opts.n_freqs
    h0 = cfg.mesh_size
    runs = [(2, s) for s in sorted(opts.size_factors, reverse=True)] + \
           [(1, s) for s in sorted(opts.p1_size_factors, reverse=True)]
    rows, solves = [], []
    with ctx.progress(len(runs), "convergence") as bar:
        for degree, s in runs:
            res = compute_modes(with_mesh(cfg, size=s * h0, degree=degree, count=n))
            solves.append(res.outcome)
            rows.append({"degree": degree, "size": s * h0, "n_dofs": res.n_dofs, "freqs": res.freqs_hz[:n],
                         "fe_seconds": _fe_seconds(res), "compile_seconds": res.timings.get("form_compilation", 0.0),
                         "peak_memory_mb": res.peak_memory_mb})
            bar.update(1, f"P{degree} {res.n_dofs} DOF")
    p2 = [r for r in rows if r["degree"] == 2][-3:]
    h = np.array([r["n_dofs"] ** (-1.0 / 3.0) for r in p2])  # effective h of unstructured meshes
    F = np.array([r["freqs"] for r in p2])
    p = observed_order(F, h)
    # unstructured (non-nested) meshes make per-mode fits noisy: one common order for all modes
    fin = p[np.isfinite(p)]
    p_common = opts.order if opts.order is not None else \
        float(np.clip(np.median(fin), 1.0, 4.0)) if fin.size else 2.0
    ref = richardson(F, h, np.full(F.shape[1], p_common))
    for r in rows:
        r["rel_errors"] = np.abs(r["freqs"] - ref) / ref
        r["max_rel_error"] = float(r["rel_errors"].max())
    ok = [r for r in rows if r["max_rel_error"] <= opts.target_error]
    best = min(ok, key=lambda r: r["fe_seconds"]) if ok else None
    table = [{k: (float(v) if isinstance(v, (float, np.floating)) else v) for k, v in r.items()
              if k not in ("freqs", "rel_errors")} for r in rows]
    summary = {
        "observed_order_p2": [float(x) if math.isfinite(x) else None for x in p],
        "order_used": p_common,
        "reference_hz": [float(x) for x in ref],
        "richardson_error_finest_p2": [float(x) for x in np.abs(F[-1] - ref) / ref],
        "runs": table,
        "cheapest_within_target": None if best is None else
        {"degree": best["degree"], "size_m": best["size"], "n_dofs": best["n_dofs"],
         "fe_seconds": best["fe_seconds"], "max_rel_error": best["max_rel_error"]},
        "target_error": opts.target_error,
    }
    return AnalysisOutcome(summary=summary, result=HousingConvergenceResult(
        rows=tuple(rows), n_freqs=n, target_error=opts.target_error),
        solver=Outcome.combine(solves))
