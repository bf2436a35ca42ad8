"""Campbell diagram of a rotor: the lowest modes over a range of spin speeds on one reduced
basis (:func:`~vibrogear.solvers.rotor.modes.reduce_rotor`), lines followed across crossings
by MAC, and the critical speeds where they cross the excitation-order lines.

Solvers return frozen results; they never print or plot.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.optimize import linear_sum_assignment

from ...models.rotor.model import RotorModel
from .modes import (MODE_TYPES, RPM, mode_residuals, solve_reduced, modes_status, rotor_outcome,
                          basis_error_estimate, classify_whirl, modal_energy_share, reduce_rotor)

__all__ = ["CampbellResult", "CriticalSpeed", "campbell_diagram"]


@dataclass(frozen=True)
class CriticalSpeed:
    order: float
    line: int
    speed_rpm: float
    frequency_hz: float
    whirl: str
    mode_type: str


@dataclass(frozen=True, eq=False)
class CampbellResult:
    speeds_rpm: np.ndarray             # (s,)
    frequencies_hz: np.ndarray         # (s, lines), lines tracked by MAC across speeds
    damping_ratios: np.ndarray
    whirl: np.ndarray                  # (s, lines) str
    mode_type: np.ndarray              # (s, lines) str
    orders: tuple[float, ...]
    critical_speeds: tuple[CriticalSpeed, ...]
    max_residual: float
    error_estimate: float              # at the highest speed, see basis_error_estimate
    n_basis: int
    status: str = "ok"
    message: str = ""
    timings: dict = field(default_factory=dict)

    @property
    def outcome(self):
        return rotor_outcome(self, {"speeds": self.speeds_rpm.size, "basis": self.n_basis},
                             {"reduction_error": self.error_estimate,
                              "max_residual": self.max_residual})


def _mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    num = np.abs(np.conj(a).T @ b) ** 2
    den = np.outer(np.sum(np.abs(a) ** 2, axis=0), np.sum(np.abs(b) ** 2, axis=0))
    return num / np.where(den > 0, den, 1.0)


def campbell_diagram(model: RotorModel, speeds_rpm, *, n_modes: int = 8,
                     orders: tuple[float, ...] = (1.0,), n_basis: int | None = None,
                     callback: Callable[[int, float], None] | None = None) -> CampbellResult:
    """Frequencies of the lowest ``n_modes`` oscillatory modes over ``speeds_rpm`` (lines
    followed across crossings by MAC), and the critical speeds where the lines cross the
    order lines ``f = order * rpm / 60`` (refined by the secant method)."""
    t0 = time.perf_counter()
    speeds = np.asarray(speeds_rpm, float)
    red = reduce_rotor(model, n_basis, count=n_modes)
    t_red = time.perf_counter() - t0
    extra = n_modes + 4
    freqs = np.full((speeds.size, n_modes), np.nan)
    zetas = np.full_like(freqs, np.nan)
    vecs_prev = None
    lams = []
    lines_q = []
    for i, rpm in enumerate(speeds):
        lam, q, _ = solve_reduced(red, rpm * RPM)
        lam, q = lam[:extra], q[:, :extra]
        if vecs_prev is None:
            pick = np.arange(min(n_modes, lam.size))
        else:
            cost = 1.0 - _mac(vecs_prev, q)
            # favour small frequency jumps when shapes are alike (degenerate pairs)
            df = np.abs(lam.imag[None, :] - lams[-1].imag[:, None]) / max(lam.imag.max(), 1.0)
            r, c = linear_sum_assignment(cost + 0.1 * df)
            pick = c[np.argsort(r)]
        lam_i, q_i = lam[pick], q[:, pick]
        k = lam_i.size
        freqs[i, :k] = lam_i.imag / (2 * np.pi)
        zetas[i, :k] = -lam_i.real / np.abs(lam_i)
        lams.append(lam_i)
        lines_q.append(q_i)
        vecs_prev = q_i
        if callback is not None:
            callback(i, float(rpm))
    t_sweep = time.perf_counter() - t0 - t_red
    whirl = np.empty(freqs.shape, dtype=object)
    types = np.empty(freqs.shape, dtype=object)
    max_res = 0.0
    for i, q_i in enumerate(lines_q):
        x = red.basis @ q_i
        share = modal_energy_share(model, x)
        ty = [MODE_TYPES[j] for j in np.argmax(share, axis=1)]
        wl, _ = classify_whirl(model, x)
        k = q_i.shape[1]
        types[i, :k] = ty
        whirl[i, :k] = [w if t == "lateral" else "-" for w, t in zip(wl, ty)]
        if i in (0, len(lines_q) - 1):
            max_res = max(max_res, float(mode_residuals(model, speeds[i] * RPM, lams[i], x).max()))
    est = basis_error_estimate(red, speeds[-1] * RPM, lams[-1], mode_residuals(
        model, speeds[-1] * RPM, lams[-1], red.basis @ lines_q[-1]))
    crit = _critical_speeds(red, speeds, freqs, lines_q, whirl, types, orders)
    timings = {"reduce_s": t_red, "sweep_s": t_sweep,
               "total_s": time.perf_counter() - t0}
    status, msg = modes_status(np.concatenate(lams), np.array([max_res]), est, red.basis.shape[1],
                          campbell=True)
    return CampbellResult(speeds, freqs, zetas, whirl, types, tuple(orders), tuple(crit), max_res,
                          est, red.basis.shape[1], status, msg, timings)


def _critical_speeds(red, speeds, freqs, lines_q, whirl, types, orders):
    out = []
    for order in orders:
        for line in range(freqs.shape[1]):
            g = freqs[:, line] - order * speeds / 60.0
            for i in np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0)[0]:
                rpm = _refine(red, speeds[i], speeds[i + 1], g[i], g[i + 1], lines_q[i][:, line],
                              order)
                j = i if abs(rpm - speeds[i]) <= abs(rpm - speeds[i + 1]) else i + 1
                out.append(CriticalSpeed(float(order), line, float(rpm), float(order * rpm / 60.0),
                                         str(whirl[j, line]), str(types[j, line])))
    out.sort(key=lambda c: c.speed_rpm)
    return out


def _line_freq(red, rpm, ref):
    lam, q, _ = solve_reduced(red, rpm * RPM)
    j = int(np.argmax(_mac(ref[:, None], q)[0]))
    return lam[j].imag / (2 * np.pi)


def _refine(red, s0, s1, g0, g1, ref, order, iters=6):
    """Secant/regula-falsi on g(rpm) = f_line(rpm) - order rpm / 60 within [s0, s1]."""
    a, b, ga, gb = s0, s1, g0, g1
    x = a - ga * (b - a) / (gb - ga)
    for _ in range(iters):
        gx = _line_freq(red, x, ref) - order * x / 60.0
        if abs(gx) < 1e-9 * max(1.0, order * x / 60.0):
            break
        if np.sign(gx) == np.sign(ga):
            a, ga = x, gx
        else:
            b, gb = x, gx
        x = a - ga * (b - a) / (gb - ga)
    return x
