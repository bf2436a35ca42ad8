"""The random starts of ``vibrogear states``: their scales and their reproducible draw.

Scaled starts (any reduced model; ``docs/states.md``), at parameter value p with static
equilibrium [x_s, 0]:

1. each modal coordinate x_i = x_s,i + a U(-1, 1) |x_s,i|, a = ``deformation_scale``;
2. each two-sided contact j (a gear mesh; the impact pair's clearance) is then put at a
   deformation drawn uniformly from [g_lo - a P_j, g_hi + a P_j]: anywhere in its backlash,
   or on either flank up to a times its static penetration P_j beyond the nearer gap (0 for
   a free gear that floats in its backlash); the smallest change of x that does it (least
   squares over the two-sided contacts' coupling vectors) is added;
3. each modal velocity v_i = b U(-1, 1) V_i, b = ``velocity_scale``, V_i the amplitude of
   mode i's velocity in the forced response linearised about the static state (the tangent
   stiffness and damping there, every harmonic of the load and of the transmission errors,
   amplitudes summed over harmonics).

Box starts (impact pair, ``q_range`` and ``v_range``): q and dq/dtau uniform in the box.

Start k at grid point i draws from ``numpy.random.default_rng((seed, i, k))``: the starts do
not depend on how the work is split, on the number of workers or on a resume.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..models.contact_law import evaluate_set
from ..solvers.integrator.contact_eval import contact_kinematics
from ..solvers.linear import tangent_matrices

__all__ = ["StartScales", "start_scales", "draw_start", "forced_velocity_amplitude"]


@dataclass(frozen=True, eq=False)
class StartScales:
    """What the starts at one parameter value are drawn from."""
    u_static: np.ndarray          # (2m,) the static equilibrium
    x_scale: np.ndarray           # (m,) a |x_s,i|
    v_scale: np.ndarray           # (m,) b V_i
    mesh_rows: np.ndarray         # two-sided contacts
    mesh_lo: np.ndarray           # their target interval
    mesh_hi: np.ndarray
    mesh_e0: np.ndarray           # their transmission error at t = 0
    box: tuple | None = None      # ((q_lo, q_hi), (v_lo, v_hi)) of the impact pair


def forced_velocity_amplitude(model, x_static, param: float) -> np.ndarray:
    """(m,) amplitude of each modal velocity in the forced response linearised about the
    static state: sum over harmonics h of h W |X_h|, (K_t - (h W)^2 + i h W D_t) X_h = F_h,
    F_h the load harmonics plus the transmission errors through the contacts' stiffness."""
    m = model.n_modes
    K, D = tangent_matrices(model, x_static, param)
    W = model.excitation_frequency(param)
    ct, fc = model.contacts, model.forcing
    H = max(fc.Fc.shape[0], ct.error_cos.shape[1] if ct.count else 0)
    k = evaluate_set(ct, ct.directions @ x_static[:m]).stiffness if ct.count else np.zeros(0)
    amp = np.zeros(m)
    for h in range(1, H + 1):
        F = np.zeros(m, dtype=complex)
        if h <= fc.Fc.shape[0]:
            F += fc.Fc[h - 1] - 1j * fc.Fs[h - 1]
        if ct.count and h <= ct.error_cos.shape[1]:
            E = ct.error_cos[:, h - 1] - 1j * ct.error_sin[:, h - 1]
            F += ct.directions.T @ (k * E)
        if not np.any(F):
            continue
        w = h * W
        try:
            X = np.linalg.solve(K - w * w * np.eye(m) + 1j * w * D, F)
        except np.linalg.LinAlgError:
            continue
        amp += w * np.abs(X)
    return amp


def start_scales(model, param: float, u_static, *, deformation_scale: float,
                 velocity_scale: float, box=None) -> StartScales:
    """The scales of the starts at ``param`` (module docstring)."""
    u_static = np.array(u_static, dtype=float)
    m = model.n_modes
    ct = model.contacts
    rows = np.flatnonzero(np.isfinite(ct.gap_lo)) if ct.count else np.zeros(0, int)
    a = float(deformation_scale)
    if rows.size:
        d, _, _ = contact_kinematics(model, param, [0.0], u_static[None, :], rows=rows)
        d = d[:, 0]
        hi, lo = ct.gap_hi[rows], ct.gap_lo[rows]
        pen = np.maximum(np.maximum(d - hi, lo - d), 0.0)
        e0 = ct.directions[rows] @ u_static[:m] - d
        mesh_lo, mesh_hi = lo - a * pen, hi + a * pen
    else:
        e0 = mesh_lo = mesh_hi = np.zeros(0)
    V = forced_velocity_amplitude(model, u_static[:m], param) if velocity_scale > 0 \
        else np.zeros(m)
    return StartScales(u_static, a * np.abs(u_static[:m]), float(velocity_scale) * V, rows,
                       mesh_lo, mesh_hi, e0, box)


def draw_start(scales: StartScales, model, seed: int, point: int, start: int) -> np.ndarray:
    """Start ``start`` at grid point ``point``: a state (2m,) (module docstring)."""
    rng = np.random.default_rng((int(seed), int(point), int(start)))
    m = model.n_modes
    if scales.box is not None:
        (q0, q1), (v0, v1) = scales.box
        q, v = rng.uniform(q0, q1), rng.uniform(v0, v1)
        # the smallest modal state whose monitored deformation and rate are (q, v) at t = 0
        # (the impact pair: x = q, x' = v; it has no transmission error)
        c = model.contacts.directions[model.monitor]
        cc = float(c @ c)
        return np.concatenate([c * q / cc, c * v / cc])
    u = scales.u_static.copy()
    x = u[:m] + scales.x_scale * rng.uniform(-1.0, 1.0, m)
    rows = scales.mesh_rows
    if rows.size:
        target = rng.uniform(scales.mesh_lo, scales.mesh_hi)
        C = model.contacts.directions[rows]
        now = C @ x - scales.mesh_e0
        x = x + np.linalg.lstsq(C, target - now, rcond=None)[0]
    v = scales.v_scale * rng.uniform(-1.0, 1.0, m)
    return np.concatenate([x, v])
