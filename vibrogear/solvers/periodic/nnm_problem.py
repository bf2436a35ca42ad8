"""Nonlinear normal modes (NNMs): the conservative system of a ReducedModel and its
free-period shooting problem, bordered for the corrector of :mod:`.corrector`.

The conservative system (:func:`conservative_model`).  Damping (modal, linear links, contact),
harmonic forcing, mesh-stiffness modulation and transmission error are removed; the static
load F0 is kept, so NNMs are periodic orbits about the loaded static equilibrium, and every
contact keeps its law (it may separate and impact; the integrator locates the switches and
the variational equations jump by the saltation matrix, as in forced shooting).  The spin
terms (gyroscopic and circulatory: ``Kc1``, ``Bc1``) are dropped with the damping: the NNMs
are those of the structure at rest; the linear coupling's stiffness is symmetrised (a
non-symmetric part is circulatory, not conservative; its size is reported).  The system is
then autonomous and its energy (:func:`energy`)

    E(u) = x'.x' / 2 + x.W x / 2 + (P x).Kc (P x) / 2 + sum_j Phi_j(c_j . x) - F0 . x,
    Phi_j = k_hi (delta - g_hi)^(p+1) / (p+1) beyond g_hi, k_lo (g_lo - delta)^(p+1) / (p+1)
            below g_lo, 0 between,

is conserved along every orbit.

Free period.  The conservative model's parameter is the orbit's circular frequency omega
(model time units): its "excitation" frequency is omega_per_param * param = omega and nothing
else depends on it, so the forced shooting residual H(u0, omega) = u(2 pi / omega; u0) - u0 of
:func:`~.shooting.periodic_flow` is the free-period problem, with dH/domega = -f(u(T)) T / omega.
The unknowns of the continuation are z = (u0, omega / scale).

Bordering (:class:`NnmCorrectorProblem`).  A conservative orbit is one of a two-parameter
family (time shift and energy): M f(u0) = f(u0) and grad E(u0) . (M - I) = 0.  As the free
gears' orbit families are bordered in :mod:`.shooting`, the corrector's Jacobian is

    [[M - I, dH/domega, grad E / |grad E|, B_r], [v_phase^T, 0, 0, 0], [V_r^T, 0, 0, 0]]

with the phase condition v_phase . u0 = 0 (the velocity of the monitored contact's deformation
zero at t = 0, ``phase = "monitor"``, or of the start mode's coordinate, ``"mode"``) and the
energy's multiplier lam (zero on an orbit: the unfolding of Munoz-Almaraz et al. 2003).  A
zero-stiffness coordinate e of the tangent stiffness (a free gear) that touches nothing over
the orbit adds its neutral pair as in shooting: V_r = [e, 0] (phase in position), B_r = [0, e]
(its conserved momentum).  The trivial multipliers (two for the phase and energy, two per
neutral free coordinate) are reported and left out of the stability verdict.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ...models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel
from ..integrator.trust import mechanical_energy
from ..linear import tangent_matrices
from ..static import static_forces
from .corrector import CorrectorProblem
from .floquet import NEUTRAL_RTOL

__all__ = ["conservative_model", "energy", "energy_gradient", "tangent_stiffness",
           "linear_modes_at", "rigid_basis", "onset_amplitude", "NnmCorrectorProblem",
           "phase_vector"]


def conservative_model(model: ReducedModel) -> tuple[ReducedModel, float]:
    """(the conservative autonomous model, |skew part of Kc0| / |Kc0|); its parameter is
    the orbit's circular frequency omega in model time units (``param_name`` "omega")."""
    cp, ct, fo = model.coupling, model.contacts, model.forcing
    skew = 0.0
    Kc = cp.Kc0
    if Kc.size:
        skew = float(np.linalg.norm(Kc - Kc.T) / max(np.linalg.norm(Kc), 1e-300))
        Kc = 0.5 * (Kc + Kc.T)
    zr = np.zeros_like(cp.Kc0)
    coupling = LinearCoupling(cp.P, Kc, zr, zr, zr)
    forcing = Forcing(F0=fo.F0, Fc=np.zeros_like(fo.Fc), Fs=np.zeros_like(fo.Fs))
    zh = np.zeros_like(ct.stiffness_cos)
    contacts = ContactSet(ct.directions, ct.k_hi, ct.k_lo, ct.gap_hi, ct.gap_lo, ct.exponent,
                          np.zeros_like(ct.damping), zh, zh, zh, zh, ct.names)
    out = dataclasses.replace(model, damping=np.zeros_like(model.damping), coupling=coupling,
                              forcing=forcing, contacts=contacts, omega_per_param=1.0,
                              spin_per_param=0.0, param_name="omega",
                              harmonic_orders=None,    # no forcing: the free period alone
                              period_limit=None,
                              name=f"{model.name} (conservative)")
    return out, skew


def energy(model: ReducedModel, u) -> float:
    """The conserved energy of the conservative model at the state u (module docstring):
    :func:`~..integrator.trust.mechanical_energy`."""
    return mechanical_energy(model, np.asarray(u, dtype=float))


def energy_gradient(model: ReducedModel, u) -> np.ndarray:
    """grad E = [restoring force - F0, velocity] (:func:`~..static.static_forces`)."""
    u = np.asarray(u, dtype=float)
    m = model.n_modes
    return np.concatenate([-static_forces(model, u[:m], 0.0)[0], u[m:]])


def tangent_stiffness(model: ReducedModel, x: np.ndarray) -> np.ndarray:
    """d(restoring force)/dx of the conservative model at the positions x (symmetric:
    :func:`~..linear.tangent_matrices`)."""
    K = tangent_matrices(model, x, 0.0)[0]
    return 0.5 * (K + K.T)


#: an eigenvalue of the tangent stiffness below this times the largest is a rigid coordinate
RIGID_RTOL = 1e-10


def linear_modes_at(model: ReducedModel, x: np.ndarray):
    """(omega, phi, rigid): the elastic modes of the conservative model linearised at x
    (ascending circular frequencies, unit mass-normalised shapes as columns, model units) and
    the rigid coordinates' basis (m x r, zero stiffness: free gears)."""
    lam, vec = np.linalg.eigh(tangent_stiffness(model, np.asarray(x, float)))
    top = max(float(np.max(np.abs(lam), initial=0.0)), 1e-300)
    rigid = lam <= RIGID_RTOL * top
    return np.sqrt(lam[~rigid]), vec[:, ~rigid], vec[:, rigid]


def rigid_basis(model: ReducedModel, x: np.ndarray) -> np.ndarray:
    return linear_modes_at(model, x)[2]


def onset_amplitude(model: ReducedModel, x_s: np.ndarray, phi: np.ndarray) -> float:
    """The modal amplitude a of the linear mode x = x_s + a phi cos(omega t) at which a contact
    first reaches one of its gaps (a switch: contact loss or onset); inf if none ever does."""
    ct = model.contacts
    if not ct.count:
        return float("inf")
    d = ct.directions @ x_s
    s = np.abs(ct.directions @ phi)
    best = np.inf
    for gap in (ct.gap_hi, ct.gap_lo):
        dist = np.abs(d - gap)
        ok = np.isfinite(gap) & (s > 1e-14 * max(float(s.max()), 1e-300))
        if np.any(ok):
            best = min(best, float(np.min(dist[ok] / s[ok])))
    return best


def phase_vector(model: ReducedModel, phi: np.ndarray, phase: str) -> np.ndarray:
    """The phase condition's unit vector v (v . u0 = 0): the velocity of the monitored
    contact's deformation (``"monitor"``) or of the start mode's coordinate (``"mode"``)."""
    m = model.n_modes
    v = np.zeros(2 * m)
    if phase == "monitor" and model.contacts.count:
        v[m:] = model.contacts.directions[model.monitor]
    else:
        v[m:] = phi
    return v / np.linalg.norm(v)


class NnmCorrectorProblem(CorrectorProblem):
    """The corrector's evaluations (:class:`~.corrector.CorrectorProblem`) with the NNM's
    bordering (module docstring): phase vector ``v_phase``, rigid coordinates ``rigid``
    (m x r basis)."""

    def __init__(self, model, method, v_phase: np.ndarray, rigid: np.ndarray):
        super().__init__(model, 1, method, None)
        self.v_phase = np.asarray(v_phase, dtype=float)
        m = model.n_modes
        self.rigid_states = np.zeros((2 * m, rigid.shape[1]))
        self.rigid_states[:m] = rigid

    def _rigid(self, f) -> np.ndarray:
        """Positions of the free coordinates that are neutral on this orbit (n x k_r)."""
        got = f.__dict__.get("_nnm_rigid")
        if got is None:
            E = self.rigid_states
            got = np.zeros((E.shape[0], 0))
            if E.shape[1] and f.ok:
                A = f.dG_du0
                scale = max(1.0, float(np.linalg.norm(A)))
                _, s, vt = np.linalg.svd(A @ E)
                got = E @ vt[s <= NEUTRAL_RTOL * scale].T
            f.__dict__["_nnm_rigid"] = got
        return got

    def neutral(self, f) -> int:
        """Bordered directions: the phase, plus the neutral free coordinates."""
        return 1 + self._rigid(f).shape[1]

    def borders(self, f) -> tuple[np.ndarray, np.ndarray]:
        """(V, B), both n x k: phase-condition normals and bordering columns."""
        u0 = f.trajectory.u_end - f.G
        g = energy_gradient(self.model, u0)
        g = g / max(float(np.linalg.norm(g)), 1e-300)
        Vr = self._rigid(f)
        m = self.model.n_modes
        Br = np.zeros_like(Vr)
        Br[m:] = Vr[:m]
        return (np.column_stack([self.v_phase, Vr]), np.column_stack([g, Br]))
