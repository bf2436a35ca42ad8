"""The random starts of ``vibrogear states``: their scales and their reproducible draw.

Scaled starts (any reduced model; ``docs/states.md``), at parameter value p with static
equilibrium [x_s, 0]:

1. the static deflection scaled as a whole: x = s x_s, s drawn uniformly from [1 - a, 1 + a],
   a = ``deformation_scale`` (every bearing deflection and every loaded deformation moves
   together, up to a times its static value: independent modal disturbances would add up
   incoherently over many modes and load one rolling element tens of times its static
   deflection);
2. each two-sided contact j (a gear mesh; the impact pair's clearance) is then put at a
   deformation drawn uniformly from [g_lo - a P_j, g_hi + a P_j]: anywhere in its backlash,
   or on either flank up to a times its static penetration P_j beyond the nearer gap (0 for
   a free gear that floats in its backlash); the smallest change of x that does it (least
   squares over the two-sided contacts' coupling vectors) is added;
3. the velocities of the forced response linearised about the static state (the tangent
   stiffness and damping there, every harmonic of the load and of the transmission errors)
   at a random phase phi, times c: v = c Re(sum_h i h W X_h e^(i h phi)), phi uniform in
   [0, 2 pi), c uniform in [-b, b], b = ``velocity_scale``.

Box starts (impact pair, ``q_range`` and ``v_range``): q and dq/dtau uniform in the box.

Start k at grid point i draws from ``numpy.random.default_rng((seed, i, k))``: the starts do
not depend on how the work is split, on the number of workers or on a resume.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...models.contact_law import evaluate_set
from ...solvers.integrator.contact_eval import contact_kinematics
from ...solvers.linear import tangent_matrices

__all__ = ["StartScales", "start_scales", "draw_start", "forced_velocity"]


@dataclass(frozen=True, eq=False)
class StartScales:
    """What the starts at one parameter value are drawn from."""
    u_static: np.ndarray          # (2m,) the static equilibrium
    a: float                      # deformation_scale
    b: float                      # velocity_scale
    v_harmonics: np.ndarray       # (H, m) complex velocity harmonics of the forced response
    mesh_rows: np.ndarray         # two-sided contacts
    mesh_lo: np.ndarray           # their target interval
    mesh_hi: np.ndarray
    mesh_e0: np.ndarray           # their transmission error at t = 0
    box: tuple | None = None      # ((q_lo, q_hi), (v_lo, v_hi)) of the impact pair


def forced_velocity(model, x_static, param: float) -> np.ndarray:
    """(H, m) complex velocity harmonics i h W X_h of the forced response linearised about
    the static state: (K_t - (h W)^2 + i h W D_t) X_h = F_h, F_h the load harmonics plus the
    transmission errors through the contacts' stiffness (v(t) = Re sum_h V_h e^(i h W t))."""
    m = model.n_modes
    K, D = tangent_matrices(model, x_static, param)
    W = model.excitation_frequency(param)
    ct, fc = model.contacts, model.forcing
    H = max(fc.Fc.shape[0], ct.error_cos.shape[1] if ct.count else 0)
    k = evaluate_set(ct, ct.directions @ x_static[:m]).stiffness if ct.count else np.zeros(0)
    out = np.zeros((H, m), dtype=complex)
    for h in range(1, H + 1):
        F = np.zeros(m, dtype=complex)
        if h <= fc.Fc.shape[0]:
            F += fc.Fc[h - 1] - 1j * fc.Fs[h - 1]
        if ct.count and h <= ct.error_cos.shape[1]:
            E = ct.error_cos[:, h - 1] - 1j * ct.error_sin[:, h - 1]
            F += ct.directions.T @ (k * E)
        if not np.any(F):
            continue
        w = model.harmonic_orders[h - 1] * W
        try:
            out[h - 1] = 1j * w * np.linalg.solve(K - w * w * np.eye(m) + 1j * w * D, F)
        except np.linalg.LinAlgError:
            continue
    return out


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
    V = forced_velocity(model, u_static[:m], param) if velocity_scale > 0 and box is None \
        else np.zeros((0, m), dtype=complex)
    return StartScales(u_static, a, float(velocity_scale), V, rows, mesh_lo, mesh_hi, e0, box)


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
    x = scales.u_static[:m] * rng.uniform(1.0 - scales.a, 1.0 + scales.a)
    rows = scales.mesh_rows
    if rows.size:
        target = rng.uniform(scales.mesh_lo, scales.mesh_hi)
        C = model.contacts.directions[rows]
        now = C @ x - scales.mesh_e0
        x = x + np.linalg.lstsq(C, target - now, rcond=None)[0]
    phi = rng.uniform(0.0, 2.0 * np.pi * model.period_multiple)
    c = rng.uniform(-scales.b, scales.b)
    H = scales.v_harmonics.shape[0]
    v = c * np.real(np.exp(1j * phi * model.harmonic_orders[:H]) @ scales.v_harmonics) if H \
        else np.zeros(m)
    return np.concatenate([x, v])
