"""Housing FE model: SLEPc's own eigen-solvers for K x = omega^2 M x.

One driver for the SLEPc methods of ``[housing.modes] solver`` (:data:`SLEPC_SOLVERS`): Krylov-Schur
and subspace iteration in shift-and-invert at 0, LOBPCG with K^-1 (or one AMG cycle) as its
preconditioner.  The linear solver comes in as a ready KSP: the Cholesky factor of
:func:`.fe_eigen._factor` (direct) or the AMG-preconditioned KSP of :mod:`.fe_iterative`.  PETSc and
SLEPc are imported inside functions (see :mod:`.fe`); nothing here prints.
"""
from __future__ import annotations

import numpy as np

from .fe_common import PREFIX as _PREFIX, HousingSolveError

__all__ = ["SLEPC_SOLVERS", "slepc_eigensolve"]

#: solver name -> (SLEPc EPS type, spectral transform, linear solver: "direct" factor or "amg").
#: The LOBPCG entries are for the benchmarks only (not in ``HOUSING_SOLVERS``): with K^-1 as
#: preconditioner SLEPc 3.18's LOBPCG broke down (LAPACK sygvd, info > n) or hit max_it, and with
#: one GAMG cycle it did not converge 20 modes of a 17k-DOF housing in 500 iterations
SLEPC_SOLVERS = {
    "krylovschur": ("krylovschur", "sinvert", "direct"),
    "subspace": ("subspace", "sinvert", "direct"),
    "lobpcg": ("lobpcg", "precond", "direct"),
    "krylovschur_gamg": ("krylovschur", "sinvert", "amg"),
    "lobpcg_gamg": ("lobpcg", "precond", "amg"),
}


def _eps(K, M, ksp, method: str, tol: float, comm, max_it: int):
    from slepc4py import SLEPc

    eps_type, st_type, _ = SLEPC_SOLVERS[method]
    eps = SLEPc.EPS().create(comm)
    eps.setOptionsPrefix(_PREFIX)
    eps.setOperators(K, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(eps_type)
    st = eps.getST()
    if st_type == "sinvert":
        eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
        eps.setTarget(0.0)
        st.setType(SLEPc.ST.Type.SINVERT)
        st.setShift(0.0)
    else:                                  # LOBPCG: smallest lambda, preconditioned by ksp
        eps.setWhichEigenpairs(SLEPc.EPS.Which.SMALLEST_REAL)
        st.setType(SLEPc.ST.Type.PRECOND)
        st.setShift(0.0)
    st.setKSP(ksp)
    if eps_type != "lobpcg":
        eps.setPurify(False)  # Dirichlet rows are 1 in K, 0 in M: no leakage onto clamped DOF
    eps.setTolerances(tol, max_it)
    return eps


def _definite_mass(K, M):
    """M with eps on its zero (clamped) diagonal: LOBPCG needs a definite M.  eps = 1e-3 min M_ii /
    max K_ii puts the clamped DOF's eigenvalues 1/eps far above any of the housing's."""
    from petsc4py import PETSc

    dm, dk = M.getDiagonal(), K.getDiagonal()
    pos = dm.array[dm.array > 0]
    comm = K.getComm().tompi4py()
    from mpi4py import MPI

    mmin = comm.allreduce(pos.min() if pos.size else np.inf, op=MPI.MIN)
    eps = 1e-3 * mmin / dk.norm(PETSc.NormType.INFINITY)
    Mp = M.duplicate(copy=True)
    dm.array[dm.array == 0.0] = eps
    Mp.setDiagonal(dm, addv=PETSc.InsertMode.INSERT_VALUES)
    dm.destroy()
    dk.destroy()
    return Mp


def slepc_eigensolve(K, M, ksp, *, method: str, count: int, cutoff_hz: float | None, max_count: int,
                     tol: float, comm, max_it: int = 500):
    """Lowest modes with the SLEPc ``method`` of :data:`SLEPC_SOLVERS` and the linear solver ``ksp``.

    With ``cutoff_hz`` the number of requested pairs doubles (from 20) until one lies above the
    cut-off or ``max_count`` is reached (status ``truncated``).  Returns (lam ascending, local rows
    of X (n_own x m), converged reason, n converged, status, message, statistics); raises
    HousingSolveError where fewer than ``count`` pairs converged."""
    Mp = _definite_mass(K, M) if SLEPC_SOLVERS[method][0] == "lobpcg" else M
    eps = _eps(K, Mp, ksp, method, tol, comm, max_it)
    try:
        return _solve(eps, K, method, count, cutoff_hz, max_count)
    finally:
        eps.destroy()
        if Mp is not M:
            Mp.destroy()


def _solve(eps, K, method, count, cutoff_hz, max_count):
    """The pairs of :func:`slepc_eigensolve` from its set-up ``eps``; raises
    HousingSolveError where fewer than ``count`` converged (without a cut-off)."""
    from petsc4py import PETSc
    from slepc4py import SLEPc

    eps.setFromOptions()
    nev = count if cutoff_hz is None else min(20, max_count)
    lam_cut = None if cutoff_hz is None else (2 * np.pi * cutoff_hz) ** 2
    status, message, its = "ok", "", 0
    while True:
        eps.setDimensions(nev, PETSc.DECIDE, PETSc.DECIDE)
        eps.solve()
        its += eps.getIterationNumber()
        nconv = eps.getConverged()
        lam = np.array([eps.getEigenvalue(i).real for i in range(nconv)])
        if lam_cut is None or nconv < nev or (lam.size and lam.max() >= lam_cut):
            break
        if nev >= max_count:
            status, message = "truncated", (f"max_count = {max_count} modes all lie below cutoff_hz = "
                                            f"{cutoff_hz:g}; raise housing.modes.max_count")
            break
        nev = min(2 * nev, max_count)
    reason = SLEPc.EPS.ConvergedReason
    rname = {getattr(reason, k): k for k in dir(reason) if not k.startswith("_")}.get(
        eps.getConvergedReason(), str(eps.getConvergedReason()))
    if lam_cut is None and nconv < count:
        raise HousingSolveError(f"SLEPc {method} converged {nconv} of {count} modes ({rname})")
    order = np.argsort(lam)
    want = list(order[:nev]) if lam_cut is None else [i for i in order if lam[i] < lam_cut][:max_count]
    stats = {"eps_iterations": int(its), "ncv": int(eps.getDimensions()[1]), "method": method,
             "linear_iterations": int(eps.getST().getKSP().getIterationNumber())}
    X = np.empty((K.getLocalSize()[0], len(want)), order="F")
    x = K.createVecRight()
    for j, i in enumerate(want):
        eps.getEigenpair(int(i), x)
        X[:, j] = x.array
    x.destroy()
    return lam[want], X, rname, nconv, status, message, stats
