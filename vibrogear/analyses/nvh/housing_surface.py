"""The housing's outer-surface normal velocity from the reduced model's housing coordinates,
and its equivalent radiated power (ERP).

In the modal synthesis the housing enters as its own master modes (mass-normalised, no
static correction: :mod:`vibrogear.models.gearbox.master_level`), so its displacement is exactly
u_h(x, t) = sum_i phi_i(x) x_i(t) over the housing coordinates x_i of the reduced model,
and the outer surface's normal velocity is

    v_n(x, t) = sum_i phi_n,i(x) x_i'(t)        (x_i' in 1/s: the model's rate x omega_ref)

with phi_n,i the normal displacement of mode i at the surface quadrature points stored with
the housing modes (:mod:`vibrogear.models.housing.surface_data`).  Left out: the housing
modes above the scene's count (their static residual is not in the synthesis either).

ERP = rho c integral over the surface of mean_t(v_n^2) dA = 1/2 rho c sum over harmonics of
integral |v_n,h|^2 dA (the usual ERP: 1/2 rho c |v|^2 per harmonic amplitude |v|), computed
as rho c mean_t(x'^T G x') with G = Phi^T diag(w) Phi (m x m, the surface quadrature
weights w).  dB re 1e-12 W.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

__all__ = ["SurfaceMap", "surface_map", "erp_watts", "erp_spectrum", "erp_db",
           "rms_velocity_field", "P_REF_W"]

#: reference power of the ERP level [W]
P_REF_W = 1e-12


@dataclass(frozen=True, eq=False)
class SurfaceMap:
    """Housing coordinates of the reduced model -> outer-surface normal velocity."""
    columns: np.ndarray          # (m,) indices of the housing coordinates in x
    values: np.ndarray           # (nf, 3, m) phi_n at the facets' edge midpoints
    weights: np.ndarray          # (nf, 3) quadrature weights [m^2]
    vertices: np.ndarray         # (nv, 3)
    triangles: np.ndarray        # (nf, 3)
    areas: np.ndarray            # (nf,)
    rate_unit: float = 1.0       # model rate x rate_unit = 1/s

    @cached_property
    def gram(self) -> np.ndarray:
        """G = Phi^T diag(w) Phi: integral of v_n^2 over the surface = x'^T G x' (formed once
        a map: every point's and every branch orbit's ERP reads it; 4 ms each on the demo's
        3250 facets, 2 s a run when it was formed at every read)."""
        phi = self.values.reshape(-1, self.values.shape[-1])
        return phi.T @ (self.weights.reshape(-1, 1) * phi)

    @property
    def area(self) -> float:
        return float(self.areas.sum())

    def modal_rates(self, states: np.ndarray, n_modes: int) -> np.ndarray:
        """Physical housing modal velocities (m, n samples) [1/s scale] from model states
        (n samples, 2 n_modes)."""
        return self.rate_unit * np.asarray(states)[:, n_modes + self.columns].T


def surface_map(gearbox) -> tuple[SurfaceMap | None, str]:
    """The map of a :class:`~vibrogear.models.gearbox.model.GearboxModel`, or (None, why not)."""
    hm = getattr(gearbox, "housing", None)
    if hm is None:
        return None, "no housing in this scene: ERP and the surface velocity are left out"
    if not hm.has_surface:
        return None, ("the housing modes carry no outer-surface data (modes read from another "
                      "program): ERP and the surface velocity are left out")
    from ...models.gearbox.synthesis import subsystem_offsets

    subs = gearbox.subsystems
    k = next(i for i, s in enumerate(subs) if s.kind == "housing")
    off = subsystem_offsets(subs)
    m = subs[k].n_modes
    return SurfaceMap(columns=np.arange(off[k], off[k] + m), values=hm.surface_values[..., :m],
                      weights=hm.surface_weights, vertices=hm.surface_vertices,
                      triangles=hm.surface_triangles, areas=hm.surface_areas,
                      rate_unit=float(gearbox.omega_ref)), ""


def erp_watts(gram: np.ndarray, rates: np.ndarray, rho: float, c: float) -> float:
    """rho c mean_t(x'^T G x') for modal velocities ``rates`` (m, n samples over whole
    periods) [W]."""
    rates = np.asarray(rates, dtype=float)
    return float(rho * c * np.mean(np.einsum("it,ij,jt->t", rates, gram, rates)))


def erp_spectrum(gram: np.ndarray, rates: np.ndarray, rho: float, c: float) -> np.ndarray:
    """The ERP per frequency bin (n // 2 + 1,) [W] of modal velocities ``rates`` (m, n samples
    over whole periods): rho c X_k^H G X_k / n^2 from the DFT X_k of the rates, doubled for
    0 < k < n/2 (the one-sided spectrum); by Parseval its sum is :func:`erp_watts`."""
    rates = np.asarray(rates, dtype=float)
    n = rates.shape[-1]
    X = np.fft.rfft(rates, axis=-1) / n
    p = np.real(np.einsum("ik,ij,jk->k", X.conj(), gram, X))
    p[1:] *= 2.0
    if n % 2 == 0:
        p[-1] *= 0.5
    return rho * c * p


def erp_db(watts) -> np.ndarray:
    """ERP level [dB re 1e-12 W] (-inf for 0 W)."""
    w = np.asarray(watts, dtype=float)
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(w / P_REF_W)


def rms_velocity_field(smap: SurfaceMap, rates: np.ndarray) -> np.ndarray:
    """RMS normal velocity per facet (nf,) [m/s]: sqrt(integral over the facet of
    mean_t(v_n^2) / its area), the quadrature of the ERP."""
    v = smap.values @ np.asarray(rates, dtype=float)          # (nf, 3, n samples)
    ms = np.einsum("fq,fqt->f", smap.weights, v ** 2) / v.shape[-1]
    return np.sqrt(ms / np.maximum(smap.areas, np.finfo(float).tiny))
