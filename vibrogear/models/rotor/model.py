"""Rotor FE model: a rotating Timoshenko shaft with discs, free gears and bearings.

:func:`build_rotor_model` turns a :class:`~vibrogear.config.model.rotor.RotorConfig` into a frozen
:class:`RotorModel` holding the sparse matrices of paper eq. (2),
``M q'' + (B + w G) q' + (K + w C) q = f``, with ``w`` the shaft spin speed [rad/s].

DOF numbering: node ``n`` owns DOFs ``6 n + k`` with ``k`` in ``u, v, w, phi, theta, psi``
(see :mod:`vibrogear.models.rotor.elements`); free gear ``g`` owns the torsional DOF
``6 n_nodes + g``.  Bearings to ground are kept apart (``K_bearings``, ``B_bearings``) so that
the free shaft (``K``, ``B``) is what modal synthesis needs, and ``model.supported()`` adds
them for an analysis of the rotor on its own.

:func:`master_modes` gives the free, non-rotating, undamped modes (mass-normalised, the
rigid-body modes included) that the gearbox modal synthesis uses.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...config.model.rotor import RotorConfig, node_positions
from .elements import (DOF_NAMES, PHI, PSI, THETA, U, V, W, disc_inertia_from_geometry,
                             shaft_element_matrices)

__all__ = ["RotorModel", "build_rotor_model", "assemble_rotor", "master_modes",
           "MasterModes", "DOF_NAMES", "dof_groups", "lowest_modes", "static_correction"]


@dataclass(frozen=True, eq=False)
class RotorModel:
    """Sparse (CSR) matrices of one shaft and its DOF map.  ``K``/``B`` exclude bearings."""
    M: sp.csr_matrix
    K: sp.csr_matrix
    B: sp.csr_matrix
    G: sp.csr_matrix
    C: sp.csr_matrix
    K_bearings: sp.csr_matrix
    B_bearings: sp.csr_matrix
    node_z: np.ndarray                 # node positions along the axis [m]
    free_gear_dofs: tuple[int, ...]    # torsional DOF index of each free gear
    free_gear_nodes: tuple[int, ...]
    disc_nodes: tuple[int, ...]
    bearing_nodes: tuple[int, ...]
    element_nodes: np.ndarray          # (elements, 2)
    name: str = "rotor"
    labels: dict = field(default_factory=dict)

    @property
    def n_nodes(self) -> int:
        return int(self.node_z.size)

    @property
    def n_dofs(self) -> int:
        return self.M.shape[0]

    def dof(self, node: int, name: str) -> int:
        """Global index of DOF ``name`` (u, v, w, phi, theta, psi) of ``node``."""
        return 6 * int(node) + DOF_NAMES.index(name)

    def node_dofs(self, node: int) -> np.ndarray:
        """The six global DOF indices of ``node`` in the order u, v, w, phi, theta, psi."""
        return 6 * int(node) + np.arange(6)

    def node_at(self, z: float) -> int:
        return int(np.argmin(np.abs(self.node_z - z)))

    def supported(self) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """``(K + K_bearings, B + B_bearings)``: the rotor on its own linear bearings."""
        return (self.K + self.K_bearings).tocsr(), (self.B + self.B_bearings).tocsr()


def dof_groups(model: RotorModel) -> dict[str, np.ndarray]:
    """Boolean masks of the lateral, axial and torsional DOFs (free gears are torsional)."""
    n = model.n_dofs
    k = np.full(n, -1)
    k[: 6 * model.n_nodes] = np.tile(np.arange(6), model.n_nodes)
    lateral = np.isin(k, (U, V, PHI, THETA))
    axial = k == W
    torsional = (k == PSI) | (k == -1)
    return {"lateral": lateral, "axial": axial, "torsional": torsional}


def _inertia(item, rho_default: float) -> tuple[float, float, float]:
    if item.mass is not None:
        return item.mass, item.Id, item.Ip
    rho = item.density if item.density is not None else rho_default
    return disc_inertia_from_geometry(item.outer_diameter, item.inner_diameter, item.width, rho)


def assemble_rotor(*, node_z, elem_outer_d, elem_inner_d, elem_E, elem_G, elem_rho, elem_nu,
                   elem_eta=0.0, discs=(), free_gears=(), bearings=(), name="rotor",
                   labels: dict | None = None) -> RotorModel:
    """Assemble a shaft from per-element arrays (elements join consecutive nodes).

    ``discs``: ``(node, m, Id, Ip)``; ``free_gears``: ``(node, m, Id, Ip, k_t, c_t, ratio)``;
    ``bearings``: ``(node, kxx, kyy, kxy, kyx, kzz, cxx, cyy, cxy, cyx, czz)``.
    """
    z = np.asarray(node_z, float)
    ne = z.size - 1
    el = shaft_element_matrices(np.diff(z), elem_outer_d, elem_inner_d, elem_E, elem_G,
                                elem_rho, elem_nu, elem_eta)
    n_free = len(free_gears)
    n = 6 * z.size + n_free
    dofs = 6 * np.arange(ne)[:, None] + np.arange(12)[None, :]
    rows = np.broadcast_to(dofs[:, :, None], (ne, 12, 12)).ravel()
    cols = np.broadcast_to(dofs[:, None, :], (ne, 12, 12)).ravel()

    def coo(values, extra=()):
        r = [rows] + [np.array([e[0] for e in extra], int)]
        c = [cols] + [np.array([e[1] for e in extra], int)]
        v = [values.ravel()] + [np.array([e[2] for e in extra], float)]
        return sp.coo_matrix((np.concatenate(v), (np.concatenate(r), np.concatenate(c))),
                             shape=(n, n)).tocsr()

    m_extra, g_extra, k_extra, b_extra = [], [], [], []
    for node, m, i_d, i_p in discs:
        d = 6 * node
        m_extra += [(d + U, d + U, m), (d + V, d + V, m), (d + W, d + W, m),
                    (d + PHI, d + PHI, i_d), (d + THETA, d + THETA, i_d), (d + PSI, d + PSI, i_p)]
        g_extra += [(d + PHI, d + THETA, i_p), (d + THETA, d + PHI, -i_p)]
    gear_dofs = []
    for g, (node, m, i_d, i_p, k_t, c_t, ratio) in enumerate(free_gears):
        d, j = 6 * node, 6 * z.size + g
        gear_dofs.append(j)
        m_extra += [(d + U, d + U, m), (d + V, d + V, m), (d + W, d + W, m),
                    (d + PHI, d + PHI, i_d), (d + THETA, d + THETA, i_d), (j, j, i_p)]
        g_extra += [(d + PHI, d + THETA, ratio * i_p), (d + THETA, d + PHI, -ratio * i_p)]
        for lst, val in ((k_extra, k_t), (b_extra, c_t)):
            lst += [(d + PSI, d + PSI, val), (j, j, val), (d + PSI, j, -val), (j, d + PSI, -val)]
    kb, bb = [], []
    for node, kxx, kyy, kxy, kyx, kzz, cxx, cyy, cxy, cyx, czz in bearings:
        d = 6 * node
        kb += [(d + U, d + U, kxx), (d + V, d + V, kyy), (d + U, d + V, kxy),
               (d + V, d + U, kyx), (d + W, d + W, kzz)]
        bb += [(d + U, d + U, cxx), (d + V, d + V, cyy), (d + U, d + V, cxy),
               (d + V, d + U, cyx), (d + W, d + W, czz)]

    def small(entries):
        if not entries:
            return sp.csr_matrix((n, n))
        r, c, v = zip(*entries)
        return sp.coo_matrix((v, (r, c)), shape=(n, n)).tocsr()

    return RotorModel(
        M=coo(el.mass, m_extra), K=coo(el.stiffness, k_extra), B=coo(el.internal_damping, b_extra),
        G=coo(el.gyroscopic, g_extra), C=coo(el.circulatory), K_bearings=small(kb),
        B_bearings=small(bb), node_z=z, free_gear_dofs=tuple(gear_dofs),
        free_gear_nodes=tuple(int(f[0]) for f in free_gears),
        disc_nodes=tuple(int(d[0]) for d in discs), bearing_nodes=tuple(int(b[0]) for b in bearings),
        element_nodes=np.stack([np.arange(ne), np.arange(1, ne + 1)], axis=1), name=name,
        labels=dict(labels or {}))


def build_rotor_model(cfg: RotorConfig) -> RotorModel:
    """The FE model of the scene's ``[rotor]`` section."""
    z = np.asarray(node_positions(cfg.sections))
    props = {k: [] for k in ("do", "di", "E", "G", "rho", "nu", "eta")}
    for s in cfg.sections:
        mat = s.material if s.material is not None else cfg.material
        for key, val in (("do", s.outer_diameter), ("di", s.inner_diameter), ("E", mat.E),
                         ("G", mat.shear_modulus), ("rho", mat.rho), ("nu", mat.poisson),
                         ("eta", mat.internal_damping)):
            props[key].extend([val] * (s.elements or 1))
    rho0 = cfg.material.rho
    node = cfg.node_of
    discs = [(node(d.position), *_inertia(d, rho0)) for d in cfg.discs]
    gears = [(node(g.position), *_inertia(g, rho0), g.torsional_stiffness, g.torsional_damping,
              g.speed_ratio) for g in cfg.free_gears]
    bearings = [(node(b.position), b.kxx, b.kyy, b.kxy, b.kyx, b.kzz, b.cxx, b.cyy, b.cxy,
                 b.cyx, b.czz) for b in cfg.bearings]
    labels = {"discs": [d.name for d in cfg.discs], "free_gears": [g.name for g in cfg.free_gears],
              "bearings": [b.name for b in cfg.bearings]}
    return assemble_rotor(node_z=z, elem_outer_d=props["do"], elem_inner_d=props["di"],
                          elem_E=props["E"], elem_G=props["G"], elem_rho=props["rho"],
                          elem_nu=props["nu"], elem_eta=props["eta"], discs=discs,
                          free_gears=gears, bearings=bearings, name=cfg.name, labels=labels)


@dataclass(frozen=True, eq=False)
class MasterModes:
    """Free, non-rotating, undamped modes: ``V.T M V = I``, ``V.T K V = diag(omega^2)``."""
    frequencies_hz: np.ndarray
    vectors: np.ndarray           # (n_dofs, m)
    n_rigid: int                  # rigid-body modes (frequency set to exactly 0)
    n_static: int = 0             # static-correction vectors (the last ones, see
                                  # :func:`static_correction`); mass-scaled ones have
                                  # V.T M V < 1 there


#: dense generalized eigensolver below this many DOFs, shift-invert Lanczos above
DENSE_LIMIT = 700


def lowest_modes(K, M, count: int | None = None, cutoff_hz: float | None = None):
    """Lowest undamped modes of ``(K, M)`` (K may be singular): ``(freqs_hz, vectors)``,
    vectors mass-normalised.  Dense below :data:`DENSE_LIMIT` DOFs, else shift-invert."""
    n = K.shape[0]
    want = n if count is None else min(count, n)
    if n <= DENSE_LIMIT or want > n // 3:
        hi = n - 1 if cutoff_hz is not None and count is None else want - 1
        if hi < n - 1:
            lam, vec = sla.eigh(K.toarray(), M.toarray(), subset_by_index=[0, hi], driver="gvx")
        else:
            lam, vec = sla.eigh(K.toarray(), M.toarray(), driver="gvd")
    else:
        # shift below zero: K may be singular (rigid-body modes)
        sigma = -1.0
        k = want
        while True:
            lam, vec = spla.eigsh(K.tocsc(), k=k, M=M.tocsc(), sigma=sigma, which="LM")
            order = np.argsort(lam)
            lam, vec = lam[order], vec[:, order]
            top = np.sqrt(max(lam[-1], 0.0)) / (2 * np.pi)
            if cutoff_hz is None or top > cutoff_hz or k >= n - 2:
                break
            k = min(2 * k, n - 2)
    freqs = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
    mm = np.einsum("ij,ij->j", vec, M @ vec)        # exact mass normalisation
    vec = vec / np.sqrt(mm)[None, :]
    if cutoff_hz is not None:
        keep = freqs <= cutoff_hz
        if count is not None:
            keep &= np.arange(freqs.size) < count
        freqs, vec = freqs[keep], vec[:, keep]
    return freqs, vec


#: relative frequency difference below which modes form one degenerate cluster (the two
#: bending planes of an axisymmetric shaft; the rigid-body modes)
CLUSTER_RTOL = 1e-7


def _cluster_bounds(freqs: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) index ranges of equal frequencies (``freqs`` ascending, rigid = 0)."""
    bounds, start = [], 0
    for k in range(1, freqs.size + 1):
        if k == freqs.size or freqs[k] - freqs[k - 1] > CLUSTER_RTOL * max(freqs[k], 1e-300):
            bounds.append((start, k))
            start = k
    return bounds


def _canonical_basis(vec: np.ndarray, M, bounds) -> np.ndarray:
    """Within each degenerate cluster, replace the eigen-solver's basis (any rotation of
    the subspace, chosen by round-off: it changed with the BLAS thread count) by one that
    depends on the subspace only: its M-orthogonal projection of fixed vectors, then
    M-orthonormalised in a fixed order (a single mode: its sign fixed the same way).  The physics is unchanged; the modal coordinates,
    and everything computed in them, become reproducible."""
    out = vec.copy()
    rng = np.random.default_rng(20261124)
    X = rng.standard_normal((vec.shape[0], max((b - a for a, b in bounds), default=1)))
    for a, b in bounds:
        V = vec[:, a:b]
        W = V @ (V.T @ (M @ X[:, :b - a]))          # projection of fixed vectors
        L = np.linalg.cholesky(W.T @ (M @ W))
        out[:, a:b] = sla.solve_triangular(L, W.T, lower=True).T
    return out


def master_modes(model: RotorModel, count: int | None = None,
                 cutoff_hz: float | None = None) -> MasterModes:
    """Free, non-rotating, undamped modes of the shaft (no bearings), mass-normalised.

    The six rigid-body modes (plus one per free gear with zero torsional stiffness) come
    first.  Give ``count`` (number of modes), ``cutoff_hz`` (all modes up to it) or both
    (at most ``count`` modes up to ``cutoff_hz``).  A count that would cut a degenerate
    cluster (the two bending planes of a pair) is raised to keep the whole cluster: one
    plane alone makes the shaft anisotropic, and which combination of the two planes was
    kept was decided by round-off.  Degenerate clusters get a reproducible basis.
    """
    if count is None and cutoff_hz is None:
        raise ValueError("give count or cutoff_hz")
    ask = None if count is None else count + 2
    freqs, vec = lowest_modes(model.K, model.M, ask, cutoff_hz)
    # rigid-body modes: eigenvalues at round-off level of the stiffness scale
    scale = np.max(model.K.diagonal() / np.maximum(model.M.diagonal(), 1e-300))
    rigid = (2 * np.pi * freqs) ** 2 < 1e-9 * scale
    freqs = np.where(rigid, 0.0, freqs)
    bounds = _cluster_bounds(freqs)
    if count is not None:
        keep = next(b for a, b in bounds if b >= min(count, freqs.size))
        if keep < freqs.size or freqs.size <= count:
            bounds = [(a, b) for a, b in bounds if b <= keep]
        else:          # the asked-for extra modes are one cluster still: keep the count
            keep, bounds = count, [(a, min(b, count)) for a, b in bounds if a < count]
        freqs, vec = freqs[:keep], vec[:, :keep]
    return MasterModes(freqs, _canonical_basis(vec, model.M, bounds), int(np.sum(freqs == 0.0)))


#: Gram eigenvalue (shapes of unit M-norm) below which a static-correction shape counts as
#: dependent on the others
STATIC_RANK_TOL = 1e-10


def static_correction(model: RotorModel, modes: MasterModes, loads,
                      cap_hz: float | None = None) -> MasterModes:
    """``modes`` augmented with the static contribution of the truncated modes under
    ``loads`` (a (n_dofs, k) array of force patterns: unit forces at the coupling DOF).

    Craig-Chang / MacNeal residual flexibility for a free structure: the elastic static
    deflection under the inertia-relieved load, u = G_e P f (P = I - M R R^T removes the
    rigid-body resultant, R the rigid-body modes; solved as (K + M R R^T M) u = P f, whose
    solution is M-orthogonal to R), minus the kept modes' part, gives residual shapes that
    are M- and K-orthogonal to every kept mode.  They are M-orthonormalised (dependent
    shapes dropped) and re-diagonalised on their own, so the kept modes are unchanged and
    the added vectors are pseudo-modes with the Rayleigh frequencies of the residual
    flexibility.  With them the basis spans the exact static response of the shaft (free,
    or on any supports at these DOF) to forces at these DOF: the coupling stiffness of the
    reduced model is the full model's.

    ``cap_hz``: the quasi-static treatment.  A pseudo-mode above ``cap_hz`` (the residual
    shapes of nearby loads combine into local, stiff shapes: tens of kHz) gets its modal
    mass raised so that its frequency is ``cap_hz``: vector scaled by cap / f, frequency
    cap.  Its stiffness, hence every static deflection, is unchanged; its inertia (that of
    modes far above the excitation, which respond quasi-statically) is overstated, which
    amplifies the residual part by 1 / (1 - (f_exc / cap)^2) at an excitation f_exc.
    """
    V, f = modes.vectors, modes.frequencies_hz
    R = V[:, f == 0.0]
    M, K = model.M.tocsc(), model.K.tocsc()
    F = np.asarray(loads, dtype=float).reshape(model.n_dofs, -1)
    MR = M @ R
    PF = F - MR @ (R.T @ F)
    Kreg = K.toarray() + MR @ MR.T
    U = sla.solve(Kreg, PF, assume_a="sym")
    U -= V @ (V.T @ (M @ U))                          # the kept modes' part (incl. rigid)
    U -= V @ (V.T @ (M @ U))                          # twice: round-off
    norms = np.sqrt(np.einsum("ij,ij->j", U, M @ U))
    big = norms > 1e-12 * max(norms.max(initial=0.0), 1e-300)   # else: carried by kept modes
    W = U[:, big] / norms[big]                        # scale-free: forces and moments alike
    for _ in range(2):                                # M-orthonormal shapes; twice: round-off
        G = W.T @ (M @ W)
        lam, Q = np.linalg.eigh(0.5 * (G + G.T))
        keep = lam > STATIC_RANK_TOL * max(lam.max(initial=0.0), 1e-300)
        if not np.any(keep):
            return modes
        W = W @ (Q[:, keep] / np.sqrt(lam[keep]))
    KW = W.T @ (K @ W)
    mu, Z = np.linalg.eigh(0.5 * (KW + KW.T))
    W = W @ Z
    fr = np.sqrt(np.clip(mu, 0.0, None)) / (2 * np.pi)
    W = _canonical_basis(W, M, _cluster_bounds(fr))
    if cap_hz is not None:
        scale = np.minimum(1.0, cap_hz / np.maximum(fr, 1e-300))
        W, fr = W * scale[None, :], fr * scale
    return MasterModes(np.concatenate([f, fr]), np.hstack([V, W]), modes.n_rigid,
                       n_static=int(fr.size))
