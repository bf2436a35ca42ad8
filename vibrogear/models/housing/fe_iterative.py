"""Housing FE model: the iterative (AMG) linear solver for housings that outgrow the direct factor.

:func:`amg_ksp` builds a KSP on K preconditioned by algebraic multigrid with the six rigid-body
modes as near-null space: PETSc's GAMG (smoothed aggregation, the default) or hypre BoomerAMG
where this PETSc has hypre (``-vghousing_st_pc_type hypre`` overrides).  Memory grows linearly
with the DOF (no fill-in), so it is what remains when the Cholesky factor no longer fits.

- ``"lobpcg_gamg"`` (benchmarks only, see :mod:`.fe_slepc`): one AMG V-cycle (``preonly``).
- ``solver = "krylovschur_gamg"``: the KSP is CG to a relative residual of ``rtol``, the inner
  solve of shift-and-invert (it must be accurate: inexact inner solves corrupt the Krylov basis).

PETSc is imported inside functions (see :mod:`.fe`); nothing here prints.
"""
from __future__ import annotations

import numpy as np

from .fe_common import PREFIX as _PREFIX, option_defaults

__all__ = ["amg_ksp", "rigid_body_modes"]

_ST = f"{_PREFIX}st_"      # the spectral transform's KSP (options -vghousing_st_...)

def rigid_body_modes(coords: np.ndarray, comm) -> np.ndarray:
    """(3 n, 6) M-independent, Euclidean-orthonormal rigid-body modes on the owned nodes ``coords``
    (n x 3, DOF 3 i + c at node i): three translations and three rotations about the centroid."""
    from mpi4py import MPI

    n = coords.shape[0]
    c = comm.allreduce(coords.sum(axis=0), op=MPI.SUM) / max(comm.allreduce(n, op=MPI.SUM), 1)
    x, y, z = (coords - c).T
    B = np.zeros((n, 3, 6))
    for k in range(3):
        B[:, k, k] = 1.0
    B[:, 0, 3], B[:, 1, 3] = -y, x          # about z
    B[:, 1, 4], B[:, 2, 4] = -z, y          # about x
    B[:, 2, 5], B[:, 0, 5] = -x, z          # about y
    B = B.reshape(3 * n, 6)
    G = comm.allreduce(B.T @ B, op=MPI.SUM)
    L = np.linalg.cholesky(G)
    return np.linalg.solve(L, B.T).T


def amg_ksp(K, coords: np.ndarray, comm, *, inner: str = "preonly", rtol: float = 1e-10,
            max_it: int = 2000):
    """KSP on K: ``inner = "preonly"`` (one AMG cycle) or ``"cg"`` (to ``rtol``), AMG preconditioned."""
    from petsc4py import PETSc

    K.setOption(PETSc.Mat.Option.SPD, True)
    B = rigid_body_modes(coords, comm)
    vecs = []
    for j in range(B.shape[1]):
        v = K.createVecRight()
        v.array[:] = B[:, j]
        vecs.append(v)
    ns = PETSc.NullSpace().create(vectors=vecs, comm=comm)
    K.setNearNullSpace(ns)
    defaults = {"pc_gamg_type": "agg", "pc_gamg_agg_nsmooths": 1, "pc_gamg_threshold": 0.02,
                "pc_gamg_square_graph": 1, "mg_levels_ksp_type": "chebyshev",
                "mg_levels_pc_type": "jacobi", "mg_levels_ksp_max_it": 2,
                "pc_hypre_boomeramg_strong_threshold": 0.5, "pc_hypre_boomeramg_nodal_coarsen": 6,
                "pc_hypre_boomeramg_vec_interp_variant": 3, "pc_hypre_boomeramg_coarsen_type": "HMIS",
                "pc_hypre_boomeramg_interp_type": "ext+i", "pc_hypre_boomeramg_P_max": 4,
                "pc_hypre_boomeramg_agg_nl": 1}
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(_ST)
    ksp.setOperators(K)
    if inner == "cg":
        ksp.setType(PETSc.KSP.Type.CG)
        ksp.setTolerances(rtol=rtol, atol=0.0, max_it=max_it)
        ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
    else:
        ksp.setType(PETSc.KSP.Type.PREONLY)
    ksp.getPC().setType(PETSc.PC.Type.GAMG)
    with option_defaults(_ST, defaults):
        ksp.setFromOptions()
        ksp.setUp()
    for v in vecs:
        v.destroy()
    return ksp, ns
