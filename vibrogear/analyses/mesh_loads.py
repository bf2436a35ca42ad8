"""Per-speed judgement arrays of each gear mesh, added beside a sweep's contact metrics:

* ``static_force_<mesh>`` [N]: the mesh force at the static equilibrium under the mean load
  (mean mesh stiffness, no transmission error: :mod:`vibrogear.solvers.static`), the same
  state the load path's ``normal_force_N`` is read from;
* ``kv_<mesh>``: the dynamic factor, ``max_force_<mesh>`` (the largest |mesh force| over the
  record) / ``static_force_<mesh>``; NaN (written as 0) where the static force is below
  :data:`MIN_STATIC_N` (an idle mesh: its only load is a drag torque, and a ratio to it says
  nothing about the teeth);
* ``rattle_db_<mesh>``: the rattle power ``rattle_power_<mesh>`` [W] as a level in dB re
  1 pW, 10 log10(P / 1e-12 W); a mesh without impacts (P below 1 pW) is written as 0 dB.

These are what the findings judge a loaded mesh (``kv``) and an idle one (``rattle_db``)
by (docs/findings.md).
"""
from __future__ import annotations

import numpy as np

from ..models.contact_law import evaluate

__all__ = ["static_mesh_forces", "mesh_judgement_arrays", "P_REF_W", "MIN_STATIC_N",
           "level_db"]

#: the reference power of the rattle level (1 pW, as sound power)
P_REF_W = 1e-12
#: below this static mesh force [N] no dynamic factor is formed
MIN_STATIC_N = 1e-9


def level_db(power_w) -> np.ndarray:
    """10 log10(P / 1 pW), 0 dB for P <= 1 pW (no impacts)."""
    p = np.asarray(power_w, float)
    return 10.0 * np.log10(np.maximum(np.where(np.isfinite(p), p, 0.0), P_REF_W) / P_REF_W)


def static_mesh_forces(model, u0, groups: dict) -> dict[str, float]:
    """{mesh key: |force| [N]} of each two-sided contact (a gear mesh) at the static state
    ``u0`` ([x, v]): delta = c . x, mean stiffness, zero rate."""
    m = model.n_modes
    x = np.asarray(u0, float)[:m]
    ct = model.contacts
    out = {}
    for key, (kind, idx) in groups.items():
        if kind != "mesh":
            continue
        j = int(idx[0])
        delta = np.array([float(ct.directions[j] @ x)])
        f = evaluate(delta, 0.0, k_hi=ct.k_hi[j], k_lo=ct.k_lo[j], gap_hi=ct.gap_hi[j],
                     gap_lo=ct.gap_lo[j], exponent=ct.exponent[j], damping=ct.damping[j],
                     modulation=1.0).force
        out[key] = abs(float(f[0])) * model.force_unit_n
    return out


def mesh_judgement_arrays(metrics: dict, static: dict[str, float]) -> dict[str, np.ndarray]:
    """The arrays of the module docstring from a sweep's ``metrics`` ({name: (N,)}) and the
    static mesh forces; only for meshes whose ``max_force_`` / ``rattle_power_`` exist."""
    out = {}
    for key, f0 in static.items():
        peak = metrics.get(f"max_force_{key}")
        if peak is not None:
            peak = np.asarray(peak, float)
            out[f"static_force_{key}"] = np.full(peak.shape, float(f0))
            out[f"kv_{key}"] = peak / f0 if f0 > MIN_STATIC_N else np.full(peak.shape, np.nan)
        power = metrics.get(f"rattle_power_{key}")
        if power is not None:
            out[f"rattle_db_{key}"] = level_db(power)
    return out
