"""Complex modal analysis of a rotor at spin speed (the Campbell diagram, built on it, is in
:mod:`vibrogear.solvers.rotor.campbell`).

The equation of motion is paper eq. (2) with the rotor on its own bearings,
``M q'' + (B + W G) q' + (K + W C) q = 0`` (``W`` spin speed in rad/s).  Two methods:

- ``"reduced"`` (default): the speed-independent matrices are projected once onto the lowest
  undamped, non-rotating modes of the supported rotor (``n_basis`` of them, mass-normalised),
  and each speed solves the small ``2 n_basis`` state-space eigenproblem.  Every mode's
  relative residual in the full model is reported as its error estimate.
- ``"full"``: dense eigen-decomposition of the full ``2 n`` state matrix (small models, checks).

Solvers return frozen results; they never print or plot.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from ...models.rotor.model import RotorModel, dof_groups, lowest_modes
from ...models.rotor.elements import PHI, THETA, U, V
from ...status import Outcome, Status

__all__ = ["RotorModes", "ReducedRotor", "reduce_rotor", "rotor_modes", "classify_whirl",
           "modal_energy_share", "RPM", "basis_error_estimate", "MODE_TYPES", "ERROR_LIMIT"]

RPM = np.pi / 30.0          # rad/s per rpm
MODE_TYPES = ("lateral", "axial", "torsional")


@dataclass(frozen=True, eq=False)
class ReducedRotor:
    """Speed-independent matrices of the supported rotor in a modal basis.

    Lateral DOFs are the only ones the speed couples (G and C act on ``u, v, phi, theta``);
    they never couple structurally to the axial and torsional DOFs.  So the basis is built per
    group: ``lateral`` modes (projected K, B, G, C; one small eigenproblem per speed) and
    ``other`` (axial + torsional) modes whose complex modes do not depend on the speed and
    are solved once.
    """
    basis: np.ndarray          # (n, m_lat + m_other), mass-normalised undamped modes
    n_lateral: int
    K: np.ndarray              # lateral block, (m_lat, m_lat)
    B: np.ndarray
    G: np.ndarray
    C: np.ndarray
    other_lam: np.ndarray      # oscillatory eigenvalues of the axial/torsional block
    other_q: np.ndarray        # their eigenvectors in basis coordinates (m_lat + m_other, k)
    other_rigid: int
    basis_hz: np.ndarray
    lateral_complete: bool = False     # the lateral basis spans every lateral DOF (exact)
    other_lam_coarse: np.ndarray | None = None  # axial/torsional block, basis cut by a third
    other_limit: float = np.inf        # |lambda| up to which the cut block is trusted

    def truncated(self, fraction: float = 2.0 / 3.0) -> "ReducedRotor":
        """The same reduction with only the lowest ``fraction`` of the lateral basis."""
        k = max(1, int(round(fraction * self.n_lateral)))
        s = slice(0, k)
        keep = np.r_[np.arange(k), np.arange(self.n_lateral, self.basis.shape[1])]
        return ReducedRotor(self.basis[:, keep], k, self.K[s, s], self.B[s, s], self.G[s, s],
                            self.C[s, s], self.other_lam, self.other_q[keep], self.other_rigid,
                            self.basis_hz[keep], lateral_complete=False)

    def state_matrix(self, omega: float) -> np.ndarray:
        m = self.K.shape[0]
        a = np.zeros((2 * m, 2 * m))
        a[:m, m:] = np.eye(m)
        a[m:, :m] = -(self.K + omega * self.C)
        a[m:, m:] = -(self.B + omega * self.G)
        return a


def default_basis_size(n_dofs: int, count: int) -> int:
    return int(min(n_dofs, max(3 * count + 16, 40)))


def _block_modes(kk, bb, m_bb, idx, nb):
    """Undamped basis of the DOF subset ``idx`` embedded in the full space."""
    if idx.size == 0 or nb == 0:
        return np.zeros((m_bb.shape[0], 0)), np.zeros(0)
    sub = np.ix_(idx, idx)
    hz, v = lowest_modes(kk.tocsr()[sub], m_bb.tocsr()[sub], count=min(nb, idx.size))
    full = np.zeros((m_bb.shape[0], v.shape[1]))
    full[idx] = v
    return full, hz


def reduce_rotor(model: RotorModel, n_basis: int | None = None, *, count: int = 12) -> ReducedRotor:
    """Project the supported rotor on its lowest undamped non-rotating modes: ``n_basis``
    lateral ones and ``count + 8`` axial/torsional ones (those are solved once, exactly
    enough for any speed since the speed does not act on them)."""
    k_s, b_s = model.supported()
    groups = dof_groups(model)
    lat = np.nonzero(groups["lateral"])[0]
    oth = np.nonzero(~groups["lateral"])[0]
    nb = default_basis_size(lat.size, count) if n_basis is None else min(n_basis, lat.size)
    v_l, hz_l = _block_modes(k_s, b_s, model.M, lat, nb)
    v_o, hz_o = _block_modes(k_s, b_s, model.M, oth, min(count + 8, oth.size))
    ml, mo = v_l.shape[1], v_o.shape[1]
    # axial/torsional block: speed-independent complex modes, solved once
    scale = np.sqrt(max(hz_o.max() * 2 * np.pi, 1.0) ** 2) if mo else 1.0
    lam, q, n_rigid = _other_block(k_s, b_s, v_o, scale)
    q_full = np.zeros((ml + mo, q.shape[1]), complex)
    q_full[ml:] = q
    coarse, limit = None, np.inf
    if 0 < mo < oth.size:                 # truncated: the same block on 2/3 of its basis
        k = max(1, int(round(2.0 * mo / 3.0)))
        coarse = _other_block(k_s, b_s, v_o[:, :k], scale)[0]
        limit = 0.5 * 2 * np.pi * hz_o[k - 1]
    proj = lambda a, v: v.T @ (a @ v)  # noqa: E731
    return ReducedRotor(np.hstack([v_l, v_o]), ml, proj(k_s, v_l), proj(b_s, v_l),
                        proj(model.G, v_l), proj(model.C, v_l), lam, q_full, n_rigid,
                        np.concatenate([hz_l, hz_o]), lateral_complete=ml == lat.size,
                        other_lam_coarse=coarse, other_limit=limit)


def _other_block(k_s, b_s, v_o, scale):
    mo = v_o.shape[1]
    a = np.zeros((2 * mo, 2 * mo))
    a[:mo, mo:] = np.eye(mo)
    a[mo:, :mo] = -(v_o.T @ (k_s @ v_o))
    a[mo:, mo:] = -(v_o.T @ (b_s @ v_o))
    lam, q = sla.eig(a)
    return _select(lam, q[:mo], scale)


@dataclass(frozen=True, eq=False)
class RotorModes:
    """Oscillatory modes at one speed, sorted by damped frequency."""
    speed_rpm: float
    eigenvalues: np.ndarray            # lambda = -zeta w_n + i w_d, Im >= 0
    frequencies_hz: np.ndarray         # damped natural frequency Im(lambda) / 2 pi
    natural_frequencies_hz: np.ndarray  # |lambda| / 2 pi
    damping_ratios: np.ndarray         # -Re(lambda) / |lambda|
    whirl: tuple[str, ...]             # forward / backward / mixed / - (not lateral)
    whirl_ratio: np.ndarray            # (F - B) / (F + B) of the lateral orbit, in [-1, 1]
    mode_type: tuple[str, ...]         # lateral / axial / torsional by kinetic-energy share
    energy_share: np.ndarray           # (modes, 3) lateral, axial, torsional
    shapes: np.ndarray                 # (n_dofs, modes) complex, displacement part
    residuals: np.ndarray              # relative residual of each mode in the full model
    error_estimate: float              # relative eigenvalue change, basis cut by a third
    n_rigid: int                       # zero eigenvalues (free axial / torsional motion)
    method: str
    n_basis: int
    status: str = "ok"
    message: str = ""
    timings: dict = field(default_factory=dict)

    @property
    def outcome(self) -> Outcome:
        return rotor_outcome(self, {"modes": self.frequencies_hz.size, "basis": self.n_basis},
                             {"reduction_error": self.error_estimate,
                              "max_residual": float(np.max(self.residuals, initial=0.0))})


#: the rotor solvers' status words as the one Status
ROTOR_STATUS = {"ok": Status.OK, "inaccurate": Status.INACCURATE, "failed": Status.NONFINITE}


def rotor_outcome(res, counters: dict, error_estimate: dict) -> Outcome:
    """:class:`Outcome` of a rotor result (its status word mapped by :data:`ROTOR_STATUS`)."""
    st = ROTOR_STATUS[res.status]
    return Outcome(st, res.message or st.message, counters,
                   res.timings.get("total_s", 0.0), error_estimate)


def classify_whirl(model: RotorModel, shapes: np.ndarray, *, tol: float = 0.02):
    """Whirl direction of complex mode shapes (columns, for ``e^{i w t}``, w > 0).

    Each node's orbit ``(u, v)`` (and slope orbit ``(theta, -phi)``) splits into a forward
    circle ``|U + iV|/2`` and a backward one ``|U - iV|/2``; spin is about ``+z`` (x to y).
    Returns (labels, ratio) with ratio = (F - B)/(F + B) summed over nodes; a mode is forward
    (backward) when every node with a visible orbit whirls forward (backward), else mixed.
    """
    nn = model.n_nodes
    idx = 6 * np.arange(nn)
    pairs = [(shapes[idx + U], shapes[idx + V]), (shapes[idx + THETA], -shapes[idx + PHI])]
    labels, ratios = [], []
    for j in range(shapes.shape[1]):
        f_tot = b_tot = 0.0
        signs = []
        for a, b in pairs:
            f = np.abs(a[:, j] + 1j * b[:, j]) ** 2
            bk = np.abs(a[:, j] - 1j * b[:, j]) ** 2
            f_tot += f.sum()
            b_tot += bk.sum()
            amp = f + bk
            vis = amp > tol * amp.max() if amp.max() > 0 else np.zeros_like(amp, bool)
            diff = (f - bk)[vis] / amp[vis]
            signs.append(diff[np.abs(diff) > tol])
        s = np.concatenate(signs)
        ratio = (f_tot - b_tot) / (f_tot + b_tot) if f_tot + b_tot > 0 else 0.0
        if s.size and np.all(s > 0):
            labels.append("forward")
        elif s.size and np.all(s < 0):
            labels.append("backward")
        else:
            labels.append("mixed")
        ratios.append(ratio)
    return labels, np.array(ratios)


def modal_energy_share(model: RotorModel, shapes: np.ndarray) -> np.ndarray:
    """Kinetic-energy share (modes, 3) of the lateral, axial and torsional DOFs."""
    groups = dof_groups(model)
    mx = model.M @ shapes
    e = np.real(np.conj(shapes) * mx)
    share = np.stack([e[groups[g]].sum(axis=0) for g in MODE_TYPES], axis=1)
    tot = share.sum(axis=1, keepdims=True)
    return share / np.where(tot > 0, tot, 1.0)


def mode_residuals(model: RotorModel, omega: float, lam: np.ndarray, x: np.ndarray) -> np.ndarray:
    k_s, b_s = model.supported()
    d = b_s + omega * model.G
    kk = k_s + omega * model.C
    with np.errstate(all="ignore"):        # an overflowing model gives NaN: status "failed"
        mx, dx, kx = model.M @ x, d @ x, kk @ x
        r = lam ** 2 * mx + lam * dx + kx
        scale = (np.abs(lam) ** 2 * np.linalg.norm(mx, axis=0) + np.abs(lam)
                 * np.linalg.norm(dx, axis=0) + np.linalg.norm(kx, axis=0))
        return np.linalg.norm(r, axis=0) / np.where(scale > 0, scale, 1.0)


#: reduction error estimate (relative eigenvalue change, see :func:`basis_error_estimate`)
#: above which a reduced result is flagged "inaccurate"
ERROR_LIMIT = 1e-4

#: modes with a damping ratio above this are overdamped (not oscillatory) and left out
MAX_DAMPING_RATIO = 0.95


def _select(lam: np.ndarray, vec: np.ndarray, scale: float):
    """Oscillatory half (Im > 0, damping ratio below :data:`MAX_DAMPING_RATIO`) sorted by
    Im, and the number of (near-)zero eigenvalues."""
    tiny = 1e-7 * scale
    n_rigid = int(np.sum(np.abs(lam) < tiny))
    keep = (lam.imag > tiny) & (-lam.real < MAX_DAMPING_RATIO * np.abs(lam))
    lam, vec = lam[keep], vec[:, keep]
    order = np.argsort(lam.imag, kind="stable")
    return lam[order], vec[:, order], n_rigid


def basis_error_estimate(red: ReducedRotor, omega: float, lam: np.ndarray,
                         residuals: np.ndarray | None = None) -> float:
    """A-posteriori estimate of the reduction error of ``lam`` (largest relative eigenvalue
    change), per block: a complete lateral basis is exact (0); otherwise the modes that the
    basis cut by a third can still represent (``|lambda|`` below half its highest basis
    frequency) are compared with it.  The axial/torsional block likewise when its basis is
    truncated.  A mode neither comparison covers is estimated by its relative residual in
    the full model (``residuals``, aligned with ``lam``)."""
    if lam.size == 0:
        return 0.0
    other = np.isin(lam, red.other_lam)
    est = np.zeros(lam.size)
    covered = np.ones(lam.size, bool)
    lat = ~other
    if np.any(lat) and not red.lateral_complete:
        cut = red.truncated()
        coarse, _, _ = solve_reduced(cut, omega)
        coarse = coarse[~np.isin(coarse, cut.other_lam)]
        limit = 0.5 * 2 * np.pi * cut.basis_hz[cut.n_lateral - 1]
        ok = lat & (np.abs(lam) <= limit)
        covered[lat & ~ok] = False
        if np.any(ok):
            if coarse.size == 0:
                return float("inf")
            est[ok] = _nearest_change(lam[ok], coarse)
    if np.any(other) and red.other_lam_coarse is not None:
        ok = other & (np.abs(lam) <= red.other_limit)
        covered[other & ~ok] = False
        if np.any(ok):
            est[ok] = (_nearest_change(lam[ok], red.other_lam_coarse)
                       if red.other_lam_coarse.size else np.inf)
    if not np.all(covered):
        est[~covered] = np.inf if residuals is None else residuals[~covered]
    return float(np.max(est))


def _nearest_change(lam: np.ndarray, coarse: np.ndarray) -> np.ndarray:
    d = np.abs(lam[:, None] - coarse[None, :]).min(axis=1)
    return d / np.maximum(np.abs(lam), 1e-300)


def solve_reduced(red: ReducedRotor, omega: float):
    """Oscillatory modes at ``omega`` in basis coordinates, sorted by frequency."""
    m = red.n_lateral
    lam, vec = sla.eig(red.state_matrix(omega))
    scale = np.sqrt(max(np.max(np.diag(red.K)), 1.0)) if m else 1.0
    lam, vec, n_rigid = _select(lam, vec[:m], scale)
    q = np.zeros((red.basis.shape[1], lam.size), complex)
    q[:m] = vec
    lam = np.concatenate([lam, red.other_lam])
    q = np.hstack([q, red.other_q])
    order = np.argsort(lam.imag, kind="stable")
    return lam[order], q[:, order], n_rigid + red.other_rigid


def _solve_full(model: RotorModel, omega: float):
    k_s, b_s = model.supported()
    n = model.n_dofs
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -(k_s + omega * model.C).toarray()
    a[n:, n:] = -(b_s + omega * model.G).toarray()
    bm = np.eye(2 * n)
    bm[n:, n:] = model.M.toarray()
    lam, vec = sla.eig(a, bm)
    scale = np.sqrt(max(np.max(k_s.diagonal() / model.M.diagonal()), 1.0))
    return _select(lam, vec[:n], scale)


def _trim(lam, x, count, cutoff_hz):
    f = lam.imag / (2 * np.pi)
    keep = np.ones(f.size, bool) if cutoff_hz is None else f <= cutoff_hz
    if cutoff_hz is None or count is not None:
        keep &= np.arange(f.size) < (count if count is not None else f.size)
    return lam[keep], x[:, keep]


def rotor_modes(model: RotorModel, speed_rpm: float = 0.0, *, count: int | None = 12,
                cutoff_hz: float | None = None, method: str = "reduced",
                n_basis: int | None = None, reduced: ReducedRotor | None = None) -> RotorModes:
    """Complex modes of the supported rotor at ``speed_rpm``: the lowest ``count`` oscillatory
    modes (or all up to ``cutoff_hz``), with whirl, mode type and residual error estimates."""
    t0 = time.perf_counter()
    omega = speed_rpm * RPM
    timings = {}
    if method == "full":
        lam, x, n_rigid = _solve_full(model, omega)
        nb = model.n_dofs
    elif method == "reduced":
        want = count if count is not None else 12
        red = reduced if reduced is not None else reduce_rotor(model, n_basis, count=want)
        timings["reduce_s"] = time.perf_counter() - t0
        lam, q, n_rigid = solve_reduced(red, omega)
        lam, q = _trim(lam, q, count, cutoff_hz)
        x = red.basis @ q
        timings["error_estimate"] = basis_error_estimate(red, omega, lam,
                                                         mode_residuals(model, omega, lam, x))
        nb = red.basis.shape[1]
    else:
        raise ValueError(f"method must be 'reduced' or 'full', got {method!r}")
    lam, x = _trim(lam, x, count, cutoff_hz)
    timings["eigen_s"] = time.perf_counter() - t0 - timings.get("reduce_s", 0.0)
    # normalise shapes: largest component real and 1
    big = x[np.argmax(np.abs(x), axis=0), np.arange(x.shape[1])]
    x = x / np.where(big != 0, big, 1.0)
    share = modal_energy_share(model, x)
    types = tuple(MODE_TYPES[i] for i in np.argmax(share, axis=1))
    wl, ratio = classify_whirl(model, x)
    whirl = tuple(w if t == "lateral" else "-" for w, t in zip(wl, types))
    res = mode_residuals(model, omega, lam, x)
    timings["total_s"] = time.perf_counter() - t0
    wn = np.abs(lam)
    est = timings.pop("error_estimate", 0.0)
    status, msg = modes_status(lam, res, est if method == "reduced" else 0.0, nb)
    return RotorModes(speed_rpm=float(speed_rpm), eigenvalues=lam, frequencies_hz=lam.imag / (2 * np.pi),
                      natural_frequencies_hz=wn / (2 * np.pi),
                      damping_ratios=-lam.real / np.where(wn > 0, wn, 1.0), whirl=whirl,
                      whirl_ratio=ratio, mode_type=types, energy_share=share, shapes=x,
                      residuals=res, error_estimate=est, n_rigid=n_rigid, method=method,
                      n_basis=nb, status=status,
                      message=msg, timings=timings)


def modes_status(lam, residuals, est, n_basis, *, campbell: bool = False) -> tuple[str, str]:
    """("ok" | "inaccurate" | "failed", message): non-finite eigenvalues or residuals fail
    (e.g. an overflowing stiffness); a reduction error estimate above :data:`ERROR_LIMIT`
    is inaccurate, with advice naming the scene key that enlarges the basis.  (Residuals
    are reported, not judged: an eigenvalue is accurate to about the residual squared.)"""
    if not (np.all(np.isfinite(lam)) and np.all(np.isfinite(residuals))):
        return "failed", ("non-finite eigenvalues or residuals: the matrices overflow or are "
                          "not finite (check rotor.material E, rho and the bearing values)")
    key = "rotor.campbell.n_modes" if campbell else "rotor.modes.count"
    advice = (f"; the reduced basis ({n_basis} modes, about 3 x {key} + 16 lateral ones) "
              f"grows with {key}")
    if est > ERROR_LIMIT:
        return "inaccurate", f"reduction error estimate {est:.2e} > {ERROR_LIMIT:g}{advice}"
    return "ok", ""
