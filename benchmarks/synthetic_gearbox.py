"""A synthetic gearbox-sized ReducedModel, so the integrator benchmarks can run before the
real gearbox model (housing + rotors + couplings) exists.

Units: time in MILLISECONDS, lengths in MICROMETRES, masses in kg, hence forces in
newtons (kg um / ms^2 = N), stiffnesses in N/um (1 N/um = 1e6 N/m), Hertz constants in
N/um^1.5, circular frequencies in rad/ms.  Modal coordinates are mass-normalised.
The parameter is the input shaft speed in rpm: mesh circular frequency
W = z_pinion * 2 pi rpm / 60000 rad/ms (29 teeth: 1000-4000 rpm = 483-1933 Hz mesh), spin
s = 2 pi rpm / 60000 rad/ms (gyroscopic coupling).

Structure (``m`` modes, default 160):
  * mode 0 is the rigid torsional mode of the drive line (0 Hz), held only by the mesh;
    modes 1.. are elastic, 150 Hz - 5 kHz with the modal density growing with frequency,
    1-3 % modal damping;
  * a rank-8 linear coupling: an SPD shaft/coupling stiffness (about 10 % of the modal
    stiffness seen through it), light damping and a skew gyroscopic term Bc1 * spin;
  * contact 0 (the monitor): the gear mesh, a dead zone with gap_hi = 0, gap_lo =
    -backlash (80 um), 300 N/um with +-12 % / 3 % mesh-stiffness harmonics, 5 % mesh
    damping (only in contact) and a 3-harmonic kinematic transmission error of about
    2.7 um peak.  Its direction has a unit component on the rigid mode, so the mean input
    torque (F0 on mode 0) is carried by a mean mesh force ``mesh_force``: 700 N by
    default (2.3 um static compression, a lightly loaded mesh: it opens twice a mesh
    period near its resonance, about 2700-3300 rpm, and stays closed elsewhere; at
    4000 N it never opens in 750-5000 rpm);
  * contacts 1..: ``n_contacts - 1`` one-sided Hertzian rolling elements (exponent 1.5,
    10 N/um^1.5 ~ 1e10 N/m^1.5, no damping, so C1 and switched without events) in 4
    bearings x 10 elements, each bearing ring with a 2 um interference preload and a
    0.5-1.5 kN radial load.  The structural compliance at the mesh is half the mesh
    compliance, at a bearing about that of its loaded elements.

u0 is the static equilibrium under the mean load (vibrogear.solvers.static, without the
transmission error): the mesh is closed and the bearing elements preloaded (those
opposite the radial load may open).  At the default load the transmission error at
t = 0 (2.7 um) exceeds the static mesh compression, so a run from u0 starts with a short
transient with a few mesh impacts.
"""
from __future__ import annotations

import numpy as np

from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel
from vibrogear.solvers.static import static_equilibrium

__all__ = ["synthetic_gearbox", "gearbox_case", "Z_PINION", "UNITS"]

Z_PINION = 29
UNITS = "time ms, length um, mass kg, force N; param = input speed in rpm"
RPM_TO_RAD_PER_MS = 2.0 * np.pi / 60000.0

K_MESH = 300.0            # N/um
BACKLASH = 80.0           # um
K_HERTZ = 10.0            # N/um^1.5
PRELOAD = 2.0             # um interference of every rolling element
N_EL = 10                 # rolling elements per bearing


def _frequencies_hz(m: int) -> np.ndarray:
    """0 Hz (rigid torsion), then m-1 elastic modes 150 Hz .. 5 kHz, denser at the top."""
    s = np.linspace(0.0, 1.0, m - 1)
    return np.concatenate([[0.0], 150.0 + (5000.0 - 150.0) * s ** 0.6])


def _direction(rng, w2, compliance, rigid=0.0):
    """Random modal direction (low modes participating more) with the given static
    compliance sum_i c_i^2 / w_i^2 over the elastic modes; ``rigid`` on mode 0."""
    m = w2.shape[0]
    c = np.zeros(m)
    el = slice(1, m)
    c[el] = rng.normal(size=m - 1) / (1.0 + np.sqrt(w2[el]) / 10.0)
    c[el] *= np.sqrt(compliance / np.sum(c[el] ** 2 / w2[el]))
    c[0] = rigid
    return c


def synthetic_gearbox(m: int = 160, n_contacts: int = 41, seed: int = 0, *,
                      mesh_force: float = 700.0):
    """(ReducedModel, u0) of a synthetic gearbox (see the module docstring for the units)."""
    if m < 10 or n_contacts < 2:
        raise ValueError("need m >= 10 modes and n_contacts >= 2")
    rng = np.random.default_rng(seed)
    H, r = 3, 8
    w = 2.0 * np.pi * _frequencies_hz(m) / 1000.0            # rad/ms
    w2 = w ** 2
    zeta = np.concatenate([[0.0], rng.uniform(0.01, 0.03, m - 1)])
    damping = 2.0 * zeta * w

    # low-rank coupling: SPD stiffness ~10 % of what the modes show through P, gyroscopic Bc1
    P = np.vstack([_direction(rng, w2, 1.0) for _ in range(r)])
    P /= np.linalg.norm(P, axis=1, keepdims=True)
    k_seen = 1.0 / np.mean(np.sum(P[:, 1:] ** 2 / w2[1:], axis=1))
    Q = rng.normal(size=(r, r))
    Kc0 = 0.1 * k_seen * (Q @ Q.T / r + 0.5 * np.eye(r))
    G = rng.normal(size=(r, r))
    Bc1 = 0.5 * (G - G.T)                                      # per rad/ms of spin
    z = np.zeros((r, r))
    coupling = LinearCoupling(P=P, Kc0=Kc0, Kc1=z, Bc0=0.02 * np.sqrt(k_seen) * np.eye(r),
                              Bc1=Bc1)

    # contact 0: the gear mesh (dead zone, backlash, TE, mesh-stiffness harmonics)
    c_mesh = _direction(rng, w2, 0.5 / K_MESH, rigid=1.0)
    m_eq = 1.0 / np.sum(c_mesh ** 2)
    dirs = [c_mesh]
    k_hi, k_lo, g_hi, g_lo = [K_MESH], [K_MESH], [0.0], [-BACKLASH]
    expo, cdamp = [1.0], [2.0 * 0.05 * np.sqrt(K_MESH * m_eq)]
    F0 = np.zeros(m)
    F0[0] = mesh_force * c_mesh[0]                                 # mean input torque
    names = ["mesh"]

    # bearings: rings of one-sided Hertzian rolling elements with an interference preload
    n_el = n_contacts - 1
    n_b = max(1, int(np.ceil(n_el / N_EL)))
    k_ring = N_EL / 2 * 1.5 * K_HERTZ * np.sqrt(PRELOAD + 5.0)  # tangent of a loaded ring
    for b in range(n_b):
        cx = _direction(rng, w2, 1.0 / k_ring)
        cy = _direction(rng, w2, 1.0 / k_ring)
        cy -= cx * (cx @ cy) / (cx @ cx)                       # orthogonal in-plane directions
        cy *= np.linalg.norm(cx) / np.linalg.norm(cy)
        count = min(N_EL, n_el - b * N_EL)
        phi = 2.0 * np.pi * np.arange(count) / count + rng.uniform(0.0, 2.0 * np.pi / count)
        dirs += [np.cos(p) * cx + np.sin(p) * cy for p in phi]
        names += [f"bearing{b}.{e}" for e in range(count)]
        psi = rng.uniform(0.0, 2.0 * np.pi)
        F0 += rng.uniform(500.0, 1500.0) * (np.cos(psi) * cx + np.sin(psi) * cy)
    nb = n_el
    k_hi += [K_HERTZ] * nb
    k_lo += [0.0] * nb
    g_hi += [-PRELOAD] * nb
    g_lo += [-np.inf] * nb
    expo += [1.5] * nb
    cdamp += [0.0] * nb

    nc = len(dirs)
    kmc, kms, ec, es = (np.zeros((nc, H)) for _ in range(4))
    kmc[0] = [0.12, 0.03, 0.0]
    kms[0] = [0.0, 0.02, 0.01]
    ec[0] = [2.0, 0.5, 0.2]
    es[0] = [0.0, 0.3, 0.1]
    contacts = ContactSet(np.array(dirs), np.array(k_hi), np.array(k_lo), np.array(g_hi),
                          np.array(g_lo), np.array(expo), np.array(cdamp), kmc, kms, ec, es,
                          names=tuple(names))
    forcing = Forcing(F0=F0, Fc=np.zeros((H, m)), Fs=np.zeros((H, m)))
    model = ReducedModel(omega2=w2, damping=damping, coupling=coupling, forcing=forcing,
                         contacts=contacts, omega_per_param=Z_PINION * RPM_TO_RAD_PER_MS,
                         spin_per_param=RPM_TO_RAD_PER_MS, monitor=0,
                         name=f"synthetic_gearbox_m{m}_nc{nc}_s{seed}", param_name="rpm")
    st = static_equilibrium(model, 0.0)
    if not st.converged:
        raise RuntimeError(f"synthetic gearbox: {st.message}")
    return model, st.u0


def gearbox_case():
    """(model, u0, params) for bench_gearbox_integrator.py: 2000-3500 rpm input speed in
    steps of 250 (3 points taken: 2000, 2750 (mesh opening), 3500 rpm)."""
    model, u0 = synthetic_gearbox()
    return model, u0, np.linspace(2000.0, 3500.0, 7)
