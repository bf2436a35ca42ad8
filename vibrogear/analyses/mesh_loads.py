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

* ``rattle_threshold_<mesh>``: the rattle threshold ratio, the largest drop of the mesh force
  below its static value over the excitation period, over the static force, in the model
  linearised about the static state with every contact held as it is there
  (:func:`rattle_threshold`).  For an idle mesh the static force is the drag torque over the
  free gear's base radius and the drop is the inertia torque the gear needs to follow the
  mesh, so the ratio is the gear's inertia torque over its drag torque: above 1 the drag
  cannot hold the teeth together and the gear rattles.  For a loaded mesh the same ratio above
  1 is the linear model's contact loss (the linear dynamic factor minus one).

These are what the findings judge a loaded mesh (``kv``) and an idle one (``rattle_db``,
``rattle_threshold``) by (docs/findings.md).
"""
from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla

from ..models.contact_law import evaluate, evaluate_set
from ..solvers.linear import tangent_matrices

__all__ = ["static_mesh_forces", "mesh_judgement_arrays", "rattle_threshold", "P_REF_W",
           "MIN_STATIC_N", "level_db"]

#: the reference power of the rattle level (1 pW, as sound power)
P_REF_W = 1e-12
#: below this static mesh force [N] no dynamic factor is formed
MIN_STATIC_N = 1e-9
#: the rattle threshold's time series: samples per period of its highest harmonic slot, and
#: the longest common period [base periods] sampled (beyond it: the sum of the harmonics'
#: amplitudes, an upper bound)
SAMPLES_PER_HARMONIC = 64
MAX_SAMPLED_PERIOD = 64


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


def rattle_threshold(model, u0, groups: dict, params) -> dict[str, np.ndarray]:
    """{``rattle_threshold_<mesh>``: (len(params),)} (module docstring) at each parameter
    value: the model linearised about the static state ``u0`` ([x, v]), every contact held in
    its static mode with its tangent stiffness and damping (the tangent matrices of
    :mod:`vibrogear.solvers.linear`), driven by every harmonic slot h of the excitation at
    n_h W: the external forcing, each mesh's stiffness variation (its static force x
    (a_h cos + b_h sin)) and transmission error.  One complex solve per slot gives the mesh
    force's harmonics dF_h; over the common period (sampled; beyond
    :data:`MAX_SAMPLED_PERIOD` base periods the sum of |dF_h|, an upper bound) the largest
    drop below the static force F0, max(-sign(F0) dF(t)), over |F0|.  inf where the static
    force is 0 (nothing holds the teeth together)."""
    m = model.n_modes
    x0 = np.asarray(u0, float)[:m]
    ct = model.contacts
    C = ct.directions
    meshes = {key: int(idx[0]) for key, (kind, idx) in groups.items() if kind == "mesh"}
    out = {f"rattle_threshold_{k}": np.full(len(params), np.nan) for k in meshes}
    if not meshes:
        return out
    law = evaluate_set(ct, C @ x0)
    F0, kt, dt = law.force, law.stiffness, law.damping
    A = ct.stiffness_cos - 1j * ct.stiffness_sin          # (nc, H): q = Re(Q e^{i w t})
    E = ct.error_cos - 1j * ct.error_sin
    Fx = model.forcing.Fc - 1j * model.forcing.Fs         # (H, m)
    orders = np.asarray(model.harmonic_orders, float)
    P = model.forcing_period_multiple
    sampled = P is not None and P <= MAX_SAMPLED_PERIOD
    if sampled:
        n = int(SAMPLES_PER_HARMONIC * P * max(1.0, float(np.max(orders))))
        phase = 2.0 * np.pi * P * np.arange(n) / n          # W t over the common period
    rows = np.array(list(meshes.values()))
    for ip, param in enumerate(np.asarray(params, float)):
        K, D = tangent_matrices(model, x0, float(param))
        W = model.excitation_frequency(float(param))
        dF = np.zeros((rows.size, orders.size), complex)
        for h, order in enumerate(orders):
            w = order * W
            rhs = Fx[h] - C.T @ (F0 * A[:, h] - (kt + 1j * w * dt) * E[:, h])
            if not np.any(rhs):
                continue
            X = sla.solve(K - w * w * np.eye(m) + 1j * w * D, rhs)
            dF[:, h] = (F0 * A[:, h] + (kt + 1j * w * dt) * (C @ X - E[:, h]))[rows]
        if sampled:
            series = (dF @ np.exp(1j * np.outer(orders, phase))).real      # (meshes, n)
            drop = np.max(-np.sign(F0[rows])[:, None] * series, axis=1)
        else:
            drop = np.sum(np.abs(dF), axis=1)
        for (key, j), d in zip(meshes.items(), drop):
            f0 = abs(float(F0[j]))
            out[f"rattle_threshold_{key}"][ip] = (max(float(d), 0.0) / f0 if f0 > 0.0
                                                  else math.inf)
    return out
