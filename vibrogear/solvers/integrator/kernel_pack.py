"""Packing of a ReducedModel into the plain arrays the compiled kernels take (numpy only).

The packing detects the structure the products can skip (exact: only zeros are
skipped, results change by round-off only): rows of P with a single nonzero (identity
rows over the shaft modes of a gearbox) are projected by one product and their part of
the coupling force is folded into WT = Pu^T [Kc | Bc] (one short axpy per nonzero
projection); the contact directions and the dense rows of P are stacked in G and used
over each row's nonzero column range; contacts without stiffness / error harmonics and
zero forcing harmonics skip their harmonic loops.  Parameter-free arrays are packed once
per model (models are immutable).
"""
from __future__ import annotations

import weakref
from collections import namedtuple

import numpy as np

from ...models.contact_law import smooth_contacts

__all__ = ["ModelArrays", "model_arrays"]

ModelArrays = namedtuple("ModelArrays", [
    "w2", "damp", "P", "Kc", "Bc", "Kc1", "Bc1", "F0", "Fc", "Fs",
    "C", "k_hi", "k_lo", "g_hi", "g_lo", "expo", "cdamp", "kmc", "kms", "ec", "es", "smooth",
    "harm", "eharm", "kharm", "fharm",
    # hmul[h]: the order n_h of harmonic slot h (cs[h] = cos(n_h Om t))
    "hmul",
    # Structure, detected at pack time (see _pack).  G = [C; dense rows of P], with the
    # nonzero column range [glo, ghi) of each row and gdst its output slot (contact j, or
    # the row of P).  Row k of P is row pg[k] of G (pg[k] >= 0, k in pdk) or has at most
    # one nonzero, pval[k] at column pcol[k] (pg[k] = -1: identity rows over shaft modes).
    "G", "glo", "ghi", "gdst", "pg", "pcol", "pval", "pdk",
    # Coupling at the parameter: WT[l] (row ranges [wlo, whi)) = column l of
    # Pu^T [Kc | Bc], Pu = P restricted to its single-entry rows, so that their part of
    # P^T (Kc px + Bc pv) is sum_l WT[l] q[l], q = [px; pv]; the dense rows of P take
    # Kc, Bc row by row over the nonzero ranges [klo, khi), [blo, bhi).  Same for the
    # spin derivative (Kc1, Bc1).
    "WT", "wlo", "whi", "klo", "khi", "blo", "bhi",
    "W1T", "w1lo", "w1hi", "k1lo", "k1hi", "b1lo", "b1hi",
])

_STATIC: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


_AT_PARAM: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def model_arrays(model, param: float) -> tuple:
    """Pack ``model`` at ``param`` into ModelArrays plus (Omega, spin, dOmega/dp, dspin/dp).

    The parameter-free arrays are packed once per model (models are immutable) and reused;
    so is the last parameter's packing (a sweep point or a shooting flow calls the
    integrator many times at one parameter: repacking the spin-dependent coupling cost
    ~140 us per call on the two-stage gearbox, a quarter of a one-period call)."""
    last = _AT_PARAM.get(model)
    if last is not None and last[0] == param:
        return last[1]
    out = _AT_PARAM[model] = (param, _model_arrays(model, param))
    return out[1]


def _model_arrays(model, param: float) -> tuple:
    arrs = _STATIC.get(model)
    if arrs is None:
        arrs = _STATIC[model] = _pack(model)
    spin = model.spin_per_param * param
    cp = model.coupling
    if spin != 0.0 and cp.P.shape[0]:
        Kc = np.ascontiguousarray(cp.Kc0 + spin * cp.Kc1, dtype=np.float64)
        Bc = np.ascontiguousarray(cp.Bc0 + spin * cp.Bc1, dtype=np.float64)
        arrs = arrs._replace(Kc=Kc, Bc=Bc, **_coupling_ops(Kc, Bc, arrs.P, arrs.pg))
    return arrs, model.omega_per_param * param, spin, model.omega_per_param, model.spin_per_param


def _col_ranges(M: np.ndarray) -> tuple:
    """Per row of M, the range [lo, hi) of columns holding its nonzeros (0, 0 if none):
    the products skip the zeros outside it (block-diagonal Kc, Bc; local contact rows)."""
    if M.shape[1] == 0:
        return np.zeros(M.shape[0], np.int64), np.zeros(M.shape[0], np.int64)
    nz = M != 0.0
    any_ = nz.any(axis=1)
    lo = np.where(any_, np.argmax(nz, axis=1), 0).astype(np.int64)
    hi = np.where(any_, M.shape[1] - np.argmax(nz[:, ::-1], axis=1), 0).astype(np.int64)
    return lo, hi


def _coupling_ops(Kc, Bc, P, pg, suffix: str = "") -> dict:
    """WT, its row ranges and the row ranges of Kc, Bc (see ModelArrays)."""
    Pu = np.where((pg < 0)[:, None], P, 0.0)
    # one nonzero per row of Pu: every entry of WT is a single product (no rounding sums)
    WT = np.ascontiguousarray(np.vstack([Kc.T @ Pu, Bc.T @ Pu]), dtype=np.float64)
    out = dict(zip(("WT", "wlo", "whi"), (WT, *_col_ranges(WT))))
    out.update(zip(("klo", "khi"), _col_ranges(Kc)))
    out.update(zip(("blo", "bhi"), _col_ranges(Bc)))
    return {k[0] + suffix + k[1:]: v for k, v in out.items()}


def _pack(model) -> tuple:
    cp, fo, ct = model.coupling, model.forcing, model.contacts
    f64 = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731
    i64 = lambda a: np.ascontiguousarray(a, dtype=np.int64)  # noqa: E731
    P = f64(cp.P)
    r = P.shape[0]
    nc = ct.count
    # rows of P with at most one nonzero (identity rows over the shaft modes) need no
    # dense product: their projection is one scaled entry of the state
    nnz = np.count_nonzero(P, axis=1)
    single = nnz <= 1
    pcol = np.where(nnz == 1, np.argmax(P != 0.0, axis=1), 0)
    pval = np.where(single, P[np.arange(r), pcol] if r else np.zeros(0), 0.0)
    dense = np.flatnonzero(~single)
    pg = np.full(r, -1, dtype=np.int64)
    pg[dense] = nc + np.arange(dense.size)
    G = f64(np.vstack([f64(ct.directions), P[dense]]))
    glo, ghi = _col_ranges(G)

    def flags(*arrs):
        return f64(np.any(np.hstack(arrs) != 0.0, axis=1) if arrs[0].shape[0] else np.zeros(0))

    Kc, Bc, Kc1, Bc1 = (f64(M) for M in (cp.Kc0, cp.Bc0, cp.Kc1, cp.Bc1))
    return ModelArrays(
        w2=f64(model.omega2), damp=f64(model.damping), P=P, Kc=Kc, Bc=Bc, Kc1=Kc1, Bc1=Bc1,
        F0=f64(fo.F0), Fc=f64(fo.Fc), Fs=f64(fo.Fs),
        C=f64(ct.directions), k_hi=f64(ct.k_hi), k_lo=f64(ct.k_lo), g_hi=f64(ct.gap_hi),
        g_lo=f64(ct.gap_lo), expo=f64(ct.exponent), cdamp=f64(ct.damping),
        kmc=f64(ct.stiffness_cos), kms=f64(ct.stiffness_sin), ec=f64(ct.error_cos),
        es=f64(ct.error_sin),
        # C1 contacts (Hertzian exponent > 1, no damping) switch without located events
        smooth=f64(smooth_contacts(ct.exponent, ct.damping)),
        # contacts with mesh-stiffness or transmission-error harmonics (any / error / stiffness)
        harm=flags(ct.stiffness_cos, ct.stiffness_sin, ct.error_cos, ct.error_sin),
        eharm=flags(ct.error_cos, ct.error_sin), kharm=flags(ct.stiffness_cos, ct.stiffness_sin),
        fharm=flags(f64(fo.Fc), f64(fo.Fs)),   # forcing harmonics present
        hmul=f64(model.harmonic_orders),
        G=G, glo=glo, ghi=ghi,
        gdst=i64(np.concatenate([np.arange(nc), dense])), pg=pg, pcol=i64(pcol),
        pval=f64(pval), pdk=i64(dense),
        **_coupling_ops(Kc, Bc, P, pg), **_coupling_ops(Kc1, Bc1, P, pg, "1"),
    )
