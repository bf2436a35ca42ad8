"""Element matrices of a rotating shaft: pure, vectorised functions (no assembly here).

Node DOF order (paper eq. (2)): ``u, v, w, phi, theta, psi`` = displacements along x, y, z and
rotations about x, y, z.  The shaft axis is ``z``: ``u, v`` are lateral, ``w`` axial, ``psi``
torsion.  Slopes: ``du/dz = theta`` and ``dv/dz = -phi`` (right-handed rotations).

The lateral Timoshenko element uses the interdependent interpolation (shape functions that
solve the static Timoshenko equations exactly, shear parameter ``Phi = 12 E I / (kappa G A
L^2)``); its mass, rotary inertia, gyroscopic and stiffness matrices are integrated exactly by
4-point Gauss quadrature, vectorised over all elements.  Axial and torsional parts are the
linear bar elements.  Spin is about ``+z``; the gyroscopic matrix ``G`` enters as ``Omega G q'``
and the circulatory matrix ``C`` from viscous internal damping ``eta`` as ``Omega C q``
(``C = -eta K_lateral S``, ``S`` the generator of a rotation about ``z``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DOF_NAMES", "U", "V", "W", "PHI", "THETA", "PSI", "LATERAL", "SectionProperties",
           "section_properties", "cowper_shear_coefficient", "timoshenko_shape_functions",
           "shaft_element_matrices", "ShaftElementMatrices", "disc_inertia_from_geometry",
           "rotation_generator"]

DOF_NAMES = ("u", "v", "w", "phi", "theta", "psi")
U, V, W, PHI, THETA, PSI = range(6)
#: lateral DOFs of a node (the ones the gyroscopic and circulatory terms couple)
LATERAL = (U, V, PHI, THETA)

# element-local indices of the two planes, in beam order (displacement, slope-like rotation)
_XZ = np.array([U, THETA, 6 + U, 6 + THETA])        # slope du/dz = theta
_YZ = np.array([V, PHI, 6 + V, 6 + PHI])            # slope dv/dz = -phi
_T_YZ = np.array([1.0, -1.0, 1.0, -1.0])             # beam vector = T a_yz

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(4)
_GAUSS_X = 0.5 * (_GAUSS_X + 1.0)
_GAUSS_W = 0.5 * _GAUSS_W


@dataclass(frozen=True)
class SectionProperties:
    """Cross-section properties per element (arrays of equal length)."""
    area: np.ndarray            # A [m^2]
    inertia: np.ndarray         # I, diametral second moment [m^4]
    polar: np.ndarray           # J = 2 I [m^4]
    kappa: np.ndarray           # shear coefficient


def cowper_shear_coefficient(outer_d, inner_d, nu):
    """Cowper's shear coefficient of a (hollow) circular section."""
    m = np.asarray(inner_d, float) / np.asarray(outer_d, float)
    nu = np.asarray(nu, float)
    a = (1.0 + m * m) ** 2
    return 6.0 * (1.0 + nu) * a / ((7.0 + 6.0 * nu) * a + (20.0 + 12.0 * nu) * m * m)


def section_properties(outer_d, inner_d, nu) -> SectionProperties:
    do = np.asarray(outer_d, float)
    di = np.asarray(inner_d, float)
    area = np.pi / 4.0 * (do ** 2 - di ** 2)
    inertia = np.pi / 64.0 * (do ** 4 - di ** 4)
    return SectionProperties(area, inertia, 2.0 * inertia, cowper_shear_coefficient(do, di, nu))


def timoshenko_shape_functions(xi, length, phi):
    """Interdependent Timoshenko shape functions at ``xi`` in [0, 1] for elements with
    ``length`` and shear parameter ``phi`` (arrays over elements).

    Returns ``(Nv, dNv/dz, Nr, dNr/dz)``, each (elements, points, 4), for the beam vector
    ``(v1, r1, v2, r2)`` with ``r = dv/dz`` at the nodes: ``v = Nv b``, rotation ``r = Nr b``.
    """
    x = np.asarray(xi, float)[None, :]
    L = np.asarray(length, float)[:, None]
    p = np.asarray(phi, float)[:, None]
    c = 1.0 / (1.0 + p)
    x2, x3 = x * x, x * x * x
    nv = np.stack([c * (1 - 3 * x2 + 2 * x3 + p * (1 - x)),
                   c * L * (x - 2 * x2 + x3 + p * (x - x2) / 2),
                   c * (3 * x2 - 2 * x3 + p * x),
                   c * L * (-x2 + x3 - p * (x - x2) / 2)], axis=-1)
    dnv = np.stack([c * (-6 * x + 6 * x2 - p) / L,
                    c * (1 - 4 * x + 3 * x2 + p * (1 - 2 * x) / 2),
                    c * (6 * x - 6 * x2 + p) / L,
                    c * (-2 * x + 3 * x2 - p * (1 - 2 * x) / 2)], axis=-1)
    nr = np.stack([c * 6 * (x2 - x) / L,
                   c * (1 - 4 * x + 3 * x2 + p * (1 - x)),
                   c * 6 * (x - x2) / L,
                   c * (-2 * x + 3 * x2 + p * x)], axis=-1)
    dnr = np.stack([c * 6 * (2 * x - 1) / L ** 2,
                    c * (-4 + 6 * x - p) / L,
                    c * 6 * (1 - 2 * x) / L ** 2,
                    c * (-2 + 6 * x + p) / L], axis=-1)
    return nv, dnv, nr, dnr


@dataclass(frozen=True)
class ShaftElementMatrices:
    """Per-element 12 x 12 matrices (elements, 12, 12) in the node DOF order above."""
    mass: np.ndarray
    stiffness: np.ndarray
    gyroscopic: np.ndarray        # multiplies Omega q'
    internal_damping: np.ndarray  # eta K (rotating-frame viscous damping), enters B
    circulatory: np.ndarray       # multiplies Omega q


def rotation_generator() -> np.ndarray:
    """12 x 12 generator ``S`` of a rigid rotation about ``z`` for one element's DOFs:
    ``(u, v, phi, theta) -> (-v, u, -theta, phi)`` at each node."""
    s = np.zeros((12, 12))
    for n in (0, 6):
        s[n + U, n + V] = -1.0
        s[n + V, n + U] = 1.0
        s[n + PHI, n + THETA] = -1.0
        s[n + THETA, n + PHI] = 1.0
    return s


def shaft_element_matrices(length, outer_d, inner_d, E, G, rho, nu,
                           internal_damping=0.0) -> ShaftElementMatrices:
    """Matrices of rotating Timoshenko shaft elements; every argument broadcasts over elements.

    ``internal_damping`` is the viscous internal damping coefficient ``eta`` [s]: it adds
    ``eta K`` to B and ``-eta K_lat S`` (circulatory, skew) to C.
    """
    L, do, di, E, G, rho, nu, eta = np.broadcast_arrays(
        *(np.atleast_1d(np.asarray(a, float)) for a in
          (length, outer_d, inner_d, E, G, rho, nu, internal_damping)))
    sec = section_properties(do, di, nu)
    phi = 12.0 * E * sec.inertia / (sec.kappa * G * sec.area * L ** 2)
    nv, dnv, nr, dnr = timoshenko_shape_functions(_GAUSS_X, L, phi)
    w = _GAUSS_W[None, :, None, None] * L[:, None, None, None]

    def integral(a, b):
        return np.sum(w * a[..., :, None] * b[..., None, :], axis=1)

    m_t = (rho * sec.area)[:, None, None] * integral(nv, nv)
    m_r = (rho * sec.inertia)[:, None, None] * integral(nr, nr)
    gam = dnv - nr
    k_b = ((E * sec.inertia)[:, None, None] * integral(dnr, dnr)
           + (sec.kappa * G * sec.area)[:, None, None] * integral(gam, gam))
    r_p = 2.0 * m_r                                  # rho J integral, J = 2 I

    ne = L.size
    M = np.zeros((ne, 12, 12))
    K = np.zeros((ne, 12, 12))
    Gy = np.zeros((ne, 12, 12))
    t = _T_YZ
    ixz = np.ix_(_XZ, _XZ)
    iyz = np.ix_(_YZ, _YZ)
    M[:, ixz[0], ixz[1]] = m_t + m_r
    M[:, iyz[0], iyz[1]] = (m_t + m_r) * t[:, None] * t[None, :]
    K[:, ixz[0], ixz[1]] = k_b
    K[:, iyz[0], iyz[1]] = k_b * t[:, None] * t[None, :]
    # gyroscopic: G[yz, xz] = -T R_p, G[xz, yz] = R_p T (skew)
    Gy[:, _YZ[:, None], _XZ[None, :]] = -t[:, None] * r_p
    Gy[:, _XZ[:, None], _YZ[None, :]] = r_p * t[None, :]

    bar = np.array([[1.0, -1.0], [-1.0, 1.0]])
    bar_m = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    ax = np.array([W, 6 + W])
    tor = np.array([PSI, 6 + PSI])
    M[:, ax[:, None], ax[None, :]] = (rho * sec.area * L)[:, None, None] * bar_m
    K[:, ax[:, None], ax[None, :]] = (E * sec.area / L)[:, None, None] * bar
    M[:, tor[:, None], tor[None, :]] = (rho * sec.polar * L)[:, None, None] * bar_m
    K[:, tor[:, None], tor[None, :]] = (G * sec.polar / L)[:, None, None] * bar

    lat = np.zeros(12, bool)
    lat[list(LATERAL) + [6 + d for d in LATERAL]] = True
    k_lat = K * (lat[:, None] & lat[None, :])
    B = eta[:, None, None] * K
    C = -eta[:, None, None] * (k_lat @ rotation_generator())
    return ShaftElementMatrices(M, K, Gy, B, C)


def disc_inertia_from_geometry(outer_d, inner_d, width, density):
    """Mass, diametral and polar inertia of a uniform annular disc ``(m, Id, Ip)``."""
    m = density * np.pi / 4.0 * (outer_d ** 2 - inner_d ** 2) * width
    ip = m * (outer_d ** 2 + inner_d ** 2) / 8.0
    i_d = ip / 2.0 + m * width ** 2 / 12.0
    return m, i_d, ip
