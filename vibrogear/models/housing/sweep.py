"""Housing geometry sweep that reuses the previous variant (serial; dolfinx/PETSc inside functions).

A sweep of the parametric all-hex housing (``[housing.mesh] element = "hex"``) over a geometric
parameter (a wall thickness) solves the variants in order, each from what the one before left:

- **mesh**: the first variant's grid records its cell counts (:class:`..geometry.hex_grid.CellCounts`);
  a further variant whose own grid has the same counts gets the previous mesh with its nodes moved
  (:func:`..geometry.housing_hex.moved_hex_nodes`: the same cells and DOF numbering, the node
  coordinates of the variant's own fresh mesh).  The dolfinx mesh, function space, compiled forms,
  the stiffness matrix's sparsity and the factor's symbolic analysis (ordering) stay.  Where the
  counts differ (a grid line appears or merges, e.g. a bore block's edge, 0.25 x wall from the
  inner face) the variant is meshed afresh and starts a new chain: replaying the old counts there
  would solve another mesh than the variant's own (measured before the outer sizes followed
  ``edge_size``: 35 % more cells from 10 to 11.7 mm walls, as slow as the fresh solve).  The
  ``housing_sweep`` analysis gives every point the base housing's mesh sizes, so one grid serves
  as long as the geometry allows.
- **matrices**: K re-assembled into the same matrix; the GLL-lumped diagonal mass as the vector
  int rho phi_i dx (the diagonal the fresh solve extracts from the full M, whose off-diagonal part it
  checked to be zero on the chain's first variant).
- **eigen-solve**: the Cholesky factor refactored numerically (the ordering reused), then
  Rayleigh-Ritz on the block Krylov space of the previous variant's ``count + guard`` modes
  (:func:`.krylov_refine.krylov_refine`: two solves with ``count + guard`` right-hand sides and one with as many
  as pairs still missing the tolerance, instead of block Lanczos from a random block), to the fresh
  solve's criterion, SLEPc's ||K^-1 M x - theta x||_M / theta (:func:`.krylov_refine.ritz_criterion`), at the
  sweep's tolerance (:data:`DEFAULT_TOL`); where that is not met the variant is solved afresh.
  (Block Lanczos started from those modes stalls: the nearly invariant start block leaves near-zero
  new blocks.  Without the refactor, the previous factor as a preconditioner, the criterion has to
  do without K^-1 of the new K: the residual in the M^-1 norm, Weinstein's bound, weighs the
  mesh-scale part of the residual by lambda_j^2 and stayed above 0.7 (relative) after three block
  Davidson steps whose eigenvalues were 2e-5 off (docs/performance.md); LOBPCG's criterion
  evaluated with the old factor passed low modes 3 % off.)
- **count**: not proven (a Sylvester inertia of K - sigma M needs an indefinite factor); a wanted
  eigenvalue missed altogether would have to come from above the previous variant's guard modes,
  so the wanted Ritz values, index by index, must move together by less than that band, or the
  variant is solved afresh (:func:`_reused`).

Every variant, fresh or reused, gets the fresh solve's residual check, max ||K x - lambda M x|| /
||K x|| over its modes: with a new product with K for a fresh variant, and for a reused one with
K X = M Xp from the Krylov relation (:func:`krylov_refine`), verified against one true product of
a random combination of the columns (:func:`_check`).  ``reuse=False`` gives the fresh solve of
each variant by the same stages (for the benchmark's side-by-side comparison).
"""
from __future__ import annotations

import os
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ...config.model.housing import HousingConfig
from ...geometry.hex_grid import CellCounts, TopologyChange
from ...geometry.housing import BASE_TAG
from ...geometry.housing_hex import hex_housing_arrays, moved_hex_nodes
from .block_lanczos import Breakdown
from .fe_common import HousingSolveError
from .krylov_refine import krylov_refine

__all__ = ["SweepVariant", "sweep_housing_modes", "reusable", "DEFAULT_TOL"]

#: the reused start's tolerance on SLEPc's criterion ||A x - theta x||_M / theta (A = K^-1 M,
#: theta = 1 / lambda), the fresh solve's criterion: some eigenvalue lies within this relative
#: distance of each Ritz value, so 1e-2 bounds each frequency's error by 0.5 % (the fresh solve's
#: tolerance, housing.modes.tol = 1e-8 by default, is far below what a sweep of frequencies needs)
DEFAULT_TOL = 1e-2


@dataclass(frozen=True)
class SweepVariant:
    """One variant's lowest ``count`` frequencies and how they were computed.

    ``start``: "fresh" (random block) or "previous" (the previous variant's modes); ``mesh``:
    "generated" or "moved"; ``timings`` (s) by stage: mesh, forms, assembly, factorization,
    iterations, check; ``residual``: max ||K x - lambda M x|| / ||K x|| over the modes; ``bound``: the
    acceptance criterion's largest value (the fresh solve's tolerance where fresh); ``product_check``:
    the relative difference of K X taken from the Krylov relation against one true product (0 where
    K X was a true product, see :func:`_check`); ``spread``, ``band``: the count's guard of a reused
    variant (how far apart its wanted Ritz values moved, relative, against the previous variant's
    lambda_(count + guard) / lambda_count - 1; :func:`_reused`)."""
    freqs_hz: np.ndarray
    n_dofs: int
    start: str
    mesh: str
    seconds: float
    residual: float
    steps: int
    n_rhs: int
    timings: dict = field(default_factory=dict)
    note: str = ""
    bound: float = float("nan")
    product_check: float = 0.0
    spread: float = float("nan")
    band: float = float("nan")


def reusable(cfg: HousingConfig) -> str | None:
    """None where a sweep of ``cfg`` can reuse the previous variant, else why not."""
    if cfg.source != "parametric":
        return f"housing.source = {cfg.source!r} (only the parametric box has a structured grid)"
    if cfg.mesh.element != "hex":
        return "housing.mesh.element = 'tet' (gmsh meshes each variant afresh; use element = 'hex')"
    if cfg.modes.cutoff_hz is not None:
        return "housing.modes.cutoff_hz is set (the reused start needs a fixed mode count)"
    if cfg.modes.solver != "block":
        return f"housing.modes.solver = {cfg.modes.solver!r} (the reuse is built on block Lanczos)"
    return None


def _physics(cfg: HousingConfig) -> tuple:
    """What the compiled forms depend on besides the node coordinates."""
    m = cfg.material
    return (m.E, m.nu, m.rho, cfg.mesh.degree, cfg.support, cfg.foundation_stiffness)


class _Chain:
    """The state one variant leaves the next: mesh, forms, K, factor, Ritz vectors."""

    def __init__(self, cfg, counts, cells, facets, values, dmesh, forms, K, ksp, X):
        self.physics = _physics(cfg)
        self.counts, self.cells, self.facets, self.values = counts, cells, facets, values
        self.dmesh, self.forms, self.K, self.ksp, self.X = dmesh, forms, K, ksp, X

    def destroy(self):
        self.ksp.destroy()
        self.K.destroy()


def _mass_diagonal(forms, comm):
    """The GLL-lumped mass matrix's diagonal (owned DOF, Dirichlet DOF 0) as the vector int rho phi_i dx."""
    import dolfinx.fem.petsc
    import ufl
    from dolfinx import fem
    from petsc4py import PETSc

    if "lumped" not in forms:
        V = forms["V"]
        degree = V.ufl_element().degree()
        forms["lumped"] = fem.form(forms["rho"] * ufl.inner(ufl.as_vector((1.0, 1.0, 1.0)), ufl.TestFunction(V))
                                   * ufl.dx(metadata={"quadrature_rule": "GLL", "quadrature_degree": 2 * degree - 1}))
    b = dolfinx.fem.petsc.assemble_vector(forms["lumped"])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    fem.set_bc(b, forms["bcs"], scale=0.0)
    n = forms["V"].dofmap.index_map.size_local * forms["V"].dofmap.index_map_bs
    out = np.array(b.array[:n])
    b.destroy()
    return out


def _check(K, lam, X, mdiag, comm, KX=None) -> tuple[float, float]:
    """max ||K x - lam M x|| / ||K x|| over the modes, as the fresh solve's check.

    ``KX``: K X known without a product (the Krylov refinement's K Z = M Zp); it is then checked
    against one true product with K, K (X w) = (K X) w for a random combination w of all the
    columns, and replaced by the full product where the two differ by more than 1e-6.  Returns (the
    residual, that relative difference (0 where the full product was taken))."""
    from mpi4py import MPI
    from .fe_eigen import matmul

    MX = mdiag[:, None] * X
    scale = 1.0 / np.sqrt(comm.allreduce(np.einsum("ij,ij->j", X, MX), op=MPI.SUM))
    X = X * scale
    MX *= scale
    mismatch = 0.0
    if KX is not None:
        KX *= scale                           # the caller's own array
        w = np.random.default_rng(20261129).standard_normal(X.shape[1])
        Kv = matmul(K, np.asfortranarray((X @ w)[:, None]))[:, 0]
        d = comm.allreduce(float(np.sum((Kv - KX @ w) ** 2)), op=MPI.SUM)
        mismatch = float(np.sqrt(d / comm.allreduce(float(np.sum(Kv ** 2)), op=MPI.SUM)))
        if not mismatch <= 1e-6:
            KX = None
    if KX is None:
        KX = matmul(K, X)
    R = KX - MX * lam
    resid = np.sqrt(comm.allreduce(np.einsum("ij,ij->j", R, R), op=MPI.SUM)
                    / comm.allreduce(np.einsum("ij,ij->j", KX, KX), op=MPI.SUM))
    return (float(resid.max()) if resid.size else 0.0), mismatch


def _lanczos(K, F, mdiag, comm, *, nev, extra, tol, start):
    """Block Lanczos for ``nev`` modes (+ ``extra`` Ritz vectors) from a random or a given block."""
    from .fe_eigen import BLOCK, petsc_block_lanczos

    b = BLOCK if start is None else start.shape[1]
    max_dim = max(3 * nev + 100, 2 * nev + 16 * BLOCK) if start is None else 4 * b
    return petsc_block_lanczos(K, None, F, comm, want=lambda th: nev if th.size >= nev else None,
                          max_dim=max_dim, tol=tol, start=start, extra=extra,
                          mmul=lambda W: mdiag[:, None] * W)


def _fresh(cfg, count, guard, comm, tmp: Path, timings: dict):
    """Mesh, forms, assembly, factor and a random-start block Lanczos: a new chain."""
    from .fe import assemble_forms, housing_forms, read_mesh
    from .fe_eigen import cholesky_factor

    t0 = time.perf_counter()
    counts = CellCounts()
    x, cells, facets, values = hex_housing_arrays(cfg, counts)
    path = tmp / "mesh.npz"
    with open(path, "wb") as fh:
        np.savez(fh, x=x, cells=cells, facets=facets, values=values)
    dmesh, ftags = read_mesh(path, comm)
    timings["mesh"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    forms = housing_forms(dmesh, ftags, BASE_TAG, cfg.material, cfg.mesh.degree, cfg.support,
                   cfg.foundation_stiffness)
    timings["forms"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    K, M, _ = assemble_forms(forms, comm)         # the full M, checked to be diagonal
    mdiag = np.array(M.getDiagonal().array)
    M.destroy()
    timings["assembly"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ksp = cholesky_factor(K, comm)
    timings["factorization"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    try:
        lam, X, st = _lanczos(K, ksp.getPC().getFactorMatrix(), mdiag, comm, nev=count, extra=guard,
                              tol=cfg.modes.tol, start=None)
    except Breakdown as exc:
        ksp.destroy()
        K.destroy()
        raise HousingSolveError(f"{exc} (the sweep has no Krylov-Schur fallback: run the point as a "
                                "'modes' scene)") from exc
    timings["iterations"] = time.perf_counter() - t0
    chain = _Chain(cfg, counts, cells, facets, values, dmesh, forms, K, ksp, X)
    chain.lam = lam
    return chain, lam, X, mdiag, st


def _reused(chain: _Chain, cfg, count, guard, comm, timings: dict, *, tol: float):
    """The chain's mesh with moved nodes, K re-assembled into its matrix and refactored (numerically:
    the ordering stays), the modes refined from the previous ones (:func:`krylov_refine`)."""
    import dolfinx.fem.petsc
    from mpi4py import MPI
    from .fe_eigen import matsolve

    t0 = time.perf_counter()
    own = CellCounts()                        # the grid the variant's own fresh solve would lay
    hex_housing_arrays(cfg, own)
    if own.values != chain.counts.values:
        raise TopologyChange("the variant's own grid has other cell counts than the previous one's")
    x = moved_hex_nodes(cfg, chain.counts, chain.cells, chain.facets, chain.values)
    geo = chain.dmesh.geometry
    geo.x[:, :] = x[np.asarray(geo.input_global_indices)]
    timings["mesh"] = time.perf_counter() - t0
    timings["forms"] = 0.0
    t0 = time.perf_counter()
    K, forms = chain.K, chain.forms
    K.zeroEntries()
    dolfinx.fem.petsc.assemble_matrix(K, forms["a"], bcs=forms["bcs"], diagonal=1.0)
    K.assemble()
    mdiag = _mass_diagonal(forms, comm)
    timings["assembly"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    chain.ksp.setOperators(K)                 # same pattern: numeric factorization only
    chain.ksp.setUp()
    F = chain.ksp.getPC().getFactorMatrix()
    timings["factorization"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    lam, X, est, k, n_rhs, Xp = krylov_refine(chain.X, solve=lambda B: matsolve(F, B, comm), mdiag=mdiag,
                                              gram=lambda A, B: comm.allreduce(A.T @ B, op=MPI.SUM),
                                              nev=count, tol=tol, reduce=lambda a: comm.allreduce(a, op=MPI.SUM))
    timings["iterations"] = time.perf_counter() - t0
    if not np.all(est[:count] <= tol):
        raise Breakdown(f"the reused start did not converge: criterion {np.nanmax(est[:count]):.2g} > {tol:g} "
                        f"after {k} blocks")
    # the count's guard (no rigorous count: a Sylvester inertia would need an indefinite LDL^T factor
    # of K - sigma M): a wanted eigenvalue missed altogether would have an eigenvector M-orthogonal to
    # the Krylov space of the previous count + guard modes, i.e. come from above the previous guard
    # modes; the wanted Ritz values, index by index, must move together by less than that band
    shift = np.log(lam[:count] / chain.lam[:count])
    band = float(np.log(chain.lam[-1] / chain.lam[count - 1]))
    if not np.ptp(shift) < band:
        raise Breakdown(f"the modes moved apart by {np.expm1(np.ptp(shift)):.1%} against the guard band "
                        f"{np.expm1(band):.1%} (lambda_{len(chain.lam)} / lambda_{count} - 1): a mode may "
                        "have crossed into the wanted ones")
    chain.X, chain.lam = X, lam
    return lam, X, mdiag, {"steps": k, "n_rhs": n_rhs, "est": float(est[:count].max()),
                           "KX": mdiag[:, None] * Xp[:, :count],
                           "spread": float(np.expm1(np.ptp(shift))), "band": float(np.expm1(band))}


def sweep_housing_modes(cfgs: Sequence[HousingConfig], *, count: int, reuse: bool = True,
                        guard: int | None = None, tol: float = DEFAULT_TOL,
                        on_variant: Callable[[int, SweepVariant], None] | None = None) -> list[SweepVariant]:
    """The lowest ``count`` frequencies of each housing in ``cfgs`` (in order; serial).

    ``reuse``: each variant starts from the previous one (module docstring) where
    :func:`reusable` allows and the mesh topology fits; otherwise every variant is solved
    afresh.  ``guard``: Ritz vectors carried beyond ``count`` (default max(8, count / 8)).
    ``on_variant(i, result)`` is called as each variant finishes."""
    from mpi4py import MPI

    os.environ.setdefault("XDG_CACHE_HOME", str(Path.home() / ".cache"))
    comm = MPI.COMM_WORLD
    if comm.size > 1:
        raise HousingSolveError("the reusing housing sweep runs on one process (start it without mpirun)")
    for cfg in cfgs:
        why = reusable(cfg)
        if why is not None:
            raise HousingSolveError(f"the reusing housing sweep needs a parametric all-hex housing: {why}")
    guard = max(8, count // 8) if guard is None else int(guard)
    out: list[SweepVariant] = []
    chain: _Chain | None = None
    with tempfile.TemporaryDirectory(prefix="vibrogear-hsweep-") as tmp:
        for i, cfg in enumerate(cfgs):
            t_all = time.perf_counter()
            timings: dict[str, float] = {}
            note = ""
            res = None
            if reuse and chain is not None and chain.physics == _physics(cfg):
                try:
                    lam, X, mdiag, st = _reused(chain, cfg, count, guard, comm, timings, tol=tol)
                    res = ("previous", "moved")
                except TopologyChange as exc:
                    note = f"meshed afresh: {exc}"
                except Breakdown as exc:
                    note = f"solved afresh: {exc}"
            if res is None:
                if chain is not None:
                    chain.destroy()
                timings.clear()
                sub = Path(tmp) / f"v{i}"
                sub.mkdir()
                chain, lam, X, mdiag, st = _fresh(cfg, count, guard if reuse else 0, comm, sub, timings)
                res = ("fresh", "generated")
            if len(lam) < count:
                raise HousingSolveError(f"variant {i}: block Lanczos converged {len(lam)} of {count} modes")
            t0 = time.perf_counter()
            resid, mismatch = _check(chain.K, lam[:count], X[:, :count], mdiag, comm, KX=st.pop("KX", None))
            bound = cfg.modes.tol if res[0] == "fresh" else st["est"]
            timings["check"] = time.perf_counter() - t0
            if not reuse:
                chain.destroy()
                chain = None
            v = SweepVariant(freqs_hz=np.sqrt(np.maximum(lam[:count], 0.0)) / (2 * np.pi),
                             n_dofs=int(X.shape[0]), start=res[0], mesh=res[1],
                             seconds=time.perf_counter() - t_all, residual=resid, steps=int(st["steps"]),
                             n_rhs=int(st["n_rhs"]), timings=timings, note=note, bound=bound,
                             product_check=mismatch, spread=st.get("spread", float("nan")),
                             band=st.get("band", float("nan")))
            out.append(v)
            if on_variant is not None:
                on_variant(i, v)
        if chain is not None:
            chain.destroy()
    return out
