"""Modal synthesis (paper eqs (4)-(8)): subsystem master modes + physical couplings ->
one :class:`~vibrogear.models.reduced.ReducedModel`.

Every subsystem s contributes m_s master coordinates x_s with q_s = V_s x_s (V_s
mass-normalised).  Couplings are given in physical coordinates as sparse
:class:`PhysicalVector` s over the subsystems' *coupling DOF* (a shaft: all its FE DOF; the
housing: the displacement components at its bore coupling points), and become modal
directions d = sum_s V_s[idx]^T val.  The result, in eq. (6)'s global condensed form:

    x'' + (diag(2 zeta w) + P^T Bc(s) P) x' + (diag(w^2) + P^T Kc(s) P) x
        + sum_j d_j f_j(d_j . x - e_j(t), d_j . x') = F0,

where the low-rank part P stacks (i) identity rows over the shaft coordinates that carry the
block-diagonal projected damping V^T B_s V, gyroscopic p_s V^T G_s V and circulatory
p_s V^T C_s V terms (eq. (7); they scale with the spin, omega_s = p_s omega_1) and (ii) one
row per linear link (axial bearing springs, radial bearing damping, external torsional
couplings) and (iii) the rows of general blocks (:class:`LinearBlock`: the cross-coupled
part of anisotropic bearings).  Nothing m x m is ever formed except these blocks.

Time is scaled: the model's time unit is 1 / ``omega_ref`` seconds (tau = omega_ref t), so
that displacements and velocities have the same magnitude in the integrator's error norm.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from ..reduced import ContactSet, Forcing, LinearCoupling, ReducedModel

__all__ = ["PhysicalVector", "Subsystem", "ContactLaw", "LinearLink", "LinearBlock",
           "modal_vector", "modal_projection", "synthesize", "subsystem_offsets"]


@dataclass(frozen=True, eq=False)
class PhysicalVector:
    """A linear functional of the physical coordinates: sum over parts of val . q_s[idx]."""
    parts: tuple[tuple[int, np.ndarray, np.ndarray], ...]

    @staticmethod
    def of(*parts) -> "PhysicalVector":
        return PhysicalVector(tuple((int(s), np.asarray(i, dtype=np.int64),
                                     np.asarray(v, dtype=float)) for s, i, v in parts))


@dataclass(frozen=True, eq=False)
class Subsystem:
    """Master modes of one subsystem at its coupling DOF."""
    name: str
    kind: str                       # "shaft" | "housing"
    n_dofs: int                     # FE DOF of the full subsystem
    freqs_hz: np.ndarray            # (m_s,)
    vectors: np.ndarray             # (n_coupling_dofs, m_s) mode values at the coupling DOF
    damping_ratio: np.ndarray       # (m_s,) modal damping ratios (diagonal part)
    spin_ratio: float = 0.0         # p_s (omega_s = p_s omega_1); 0 for the stator
    B: np.ndarray | None = None     # (m_s, m_s) projected damping V^T B_s V (non-diagonal part)
    G: np.ndarray | None = None     # (m_s, m_s) projected gyroscopic V^T G_s V
    C: np.ndarray | None = None     # (m_s, m_s) projected circulatory V^T C_s V
    labels: dict = field(default_factory=dict)

    @property
    def n_modes(self) -> int:
        return int(self.freqs_hz.size)


@dataclass(frozen=True, eq=False)
class ContactLaw:
    """A nonlinear contact along ``vector`` (physical units: N/m^p, m, N s/m)."""
    name: str
    vector: PhysicalVector
    k_hi: float
    k_lo: float
    gap_hi: float
    gap_lo: float
    exponent: float
    damping: float = 0.0
    stiffness_cos: tuple = ()
    stiffness_sin: tuple = ()
    error_cos: tuple = ()
    error_sin: tuple = ()
    kind: str = ""                  # "mesh" | "bearing"
    group: str = ""                 # e.g. the bearing or mesh name


@dataclass(frozen=True, eq=False)
class LinearLink:
    """A linear spring/damper along ``vector``: force -(k v.q + c v.q') v."""
    name: str
    vector: PhysicalVector
    stiffness: float
    damping: float = 0.0


@dataclass(frozen=True, eq=False)
class LinearBlock:
    """A general (non-symmetric) linear coupling over r physical functionals v_i:
    force -sum_ij v_i (K_ij v_j.q + C_ij v_j.q'), e.g. the cross-coupled (skew) part of an
    anisotropic bearing.  Symmetric couplings are better given as :class:`LinearLink` s."""
    name: str
    vectors: tuple                  # PhysicalVector per row
    stiffness: np.ndarray           # (r, r) [N/m]
    damping: np.ndarray             # (r, r) [N s/m]


def subsystem_offsets(subsystems) -> np.ndarray:
    return np.concatenate([[0], np.cumsum([s.n_modes for s in subsystems])]).astype(int)


def modal_vector(vec: PhysicalVector, subsystems, offsets=None) -> np.ndarray:
    """d with d . x = vec . q for q = V x."""
    offsets = subsystem_offsets(subsystems) if offsets is None else offsets
    d = np.zeros(offsets[-1])
    for s, idx, val in vec.parts:
        d[offsets[s]:offsets[s + 1]] += val @ subsystems[s].vectors[idx, :]
    return d


def modal_projection(subsystems, forces: dict) -> np.ndarray:
    """sum_s V_s^T f_s: the modal force of the physical forces ``forces`` {subsystem index:
    (n_coupling_dofs,) vector over its coupling DOF}; zero on the other subsystems."""
    offsets = subsystem_offsets(subsystems)
    out = np.zeros(offsets[-1])
    for s, f in forces.items():
        out[offsets[s]:offsets[s + 1]] = subsystems[s].vectors.T @ np.asarray(f, dtype=float)
    return out


def _harmonics(laws, name: str, H: int) -> np.ndarray:
    out = np.zeros((len(laws), H))
    for j, law in enumerate(laws):
        h = getattr(law, name)
        out[j, :len(h)] = h
    return out


def synthesize(subsystems, contacts, links, static_force: PhysicalVector | None, *,
               omega_ref: float, omega_per_param: float, spin_per_param: float,
               monitor: int = 0, name: str = "gearbox", param_name: str = "rpm",
               blocks=(), order_forcing=(), mesh_orders=None,
               period_limit=None) -> ReducedModel:
    """Assemble the reduced model (see the module docstring); ``static_force`` is the
    constant external load (twist-angle torques, weight), in physical units; ``blocks``
    (:class:`LinearBlock`) add general low-rank rows after the links; ``order_forcing``:
    (n, cos force, sin force) PhysicalVectors of forcing at n times the base frequency W
    (a torque order), each its own harmonic slot after the mesh harmonics 1..H;
    ``mesh_orders``: the orders of the contacts' harmonic slots (default 1..H), each contact's
    harmonics given over all of them; ``period_limit``: the ReducedModel's."""
    offsets = subsystem_offsets(subsystems)
    m = int(offsets[-1])
    w = np.concatenate([2 * np.pi * s.freqs_hz for s in subsystems]) / omega_ref
    zeta = np.concatenate([s.damping_ratio for s in subsystems])
    omega2, damping = w ** 2, 2.0 * zeta * w

    # low-rank part: identity rows over the shafts with block terms, then the links
    rows, K0, K1, B0, B1 = [], [], [], [], []
    for k, s in enumerate(subsystems):
        if s.B is None and s.G is None and s.C is None:
            continue
        n = s.n_modes
        eye = np.zeros((n, m))
        eye[:, offsets[k]:offsets[k + 1]] = np.eye(n)
        rows.append(eye)
        zero = np.zeros((n, n))
        B0.append(zero if s.B is None else s.B / omega_ref)
        B1.append(zero if s.G is None else s.spin_ratio * s.G / omega_ref)
        K0.append(zero)
        K1.append(zero if s.C is None else s.spin_ratio * s.C / omega_ref ** 2)
    if links:
        rows.append(np.array([modal_vector(l.vector, subsystems, offsets) for l in links]))
        K0.append(np.diag([l.stiffness for l in links]) / omega_ref ** 2)
        B0.append(np.diag([l.damping for l in links]) / omega_ref)
        zero = np.zeros((len(links), len(links)))
        K1.append(zero)
        B1.append(zero)
    for blk in blocks:
        r = len(blk.vectors)
        rows.append(np.array([modal_vector(v, subsystems, offsets) for v in blk.vectors]))
        K0.append(np.asarray(blk.stiffness, dtype=float).reshape(r, r) / omega_ref ** 2)
        B0.append(np.asarray(blk.damping, dtype=float).reshape(r, r) / omega_ref)
        K1.append(np.zeros((r, r)))
        B1.append(np.zeros((r, r)))
    if rows:
        coupling = LinearCoupling(np.vstack(rows), sla.block_diag(*K0), sla.block_diag(*K1),
                                  sla.block_diag(*B0), sla.block_diag(*B1))
    else:
        coupling = LinearCoupling.none(m)

    H = max([len(getattr(c, a)) for c in contacts for a in
             ("stiffness_cos", "stiffness_sin", "error_cos", "error_sin")] + [1])
    if mesh_orders is not None:
        H = len(mesh_orders)
    F0 = np.zeros(m) if static_force is None else \
        modal_vector(static_force, subsystems, offsets) / omega_ref ** 2
    K = len(order_forcing)
    Fc, Fs = np.zeros((H + K, m)), np.zeros((H + K, m))
    for k, (_, fc, fs) in enumerate(order_forcing):
        Fc[H + k] = modal_vector(fc, subsystems, offsets) / omega_ref ** 2
        Fs[H + k] = modal_vector(fs, subsystems, offsets) / omega_ref ** 2
    orders = np.concatenate([np.arange(1.0, H + 1.0) if mesh_orders is None else
                             np.asarray(mesh_orders, dtype=float),
                             [float(o[0]) for o in order_forcing]])
    forcing = Forcing(F0, Fc, Fs)
    H = H + K
    if contacts:
        f = lambda a: np.array([getattr(c, a) for c in contacts], dtype=float)  # noqa: E731
        cset = ContactSet(
            directions=np.array([modal_vector(c.vector, subsystems, offsets) for c in contacts]),
            k_hi=f("k_hi") / omega_ref ** 2, k_lo=f("k_lo") / omega_ref ** 2,
            gap_hi=f("gap_hi"), gap_lo=f("gap_lo"), exponent=f("exponent"),
            damping=f("damping") / omega_ref,
            stiffness_cos=_harmonics(contacts, "stiffness_cos", H),
            stiffness_sin=_harmonics(contacts, "stiffness_sin", H),
            error_cos=_harmonics(contacts, "error_cos", H),
            error_sin=_harmonics(contacts, "error_sin", H),
            names=tuple(c.name for c in contacts))
    else:
        cset = ContactSet.empty(m, H)
    names = tuple(f"{s.name}:{k}" for s in subsystems for k in range(s.n_modes))
    return ReducedModel(omega2=omega2, damping=damping, coupling=coupling, forcing=forcing,
                        contacts=cset, omega_per_param=omega_per_param,
                        spin_per_param=spin_per_param, monitor=monitor, name=name,
                        param_name=param_name,
                        state_names=names + tuple(f"d/dt {n}" for n in names),
                        time_unit_s=1.0 / omega_ref, force_unit_n=omega_ref ** 2,
                        length_unit="m", harmonic_orders=orders, period_limit=period_limit)
