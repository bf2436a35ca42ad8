"""Housing FE model, stage 2 of 3: the generalized eigen-problem K x = omega^2 M x.

Block Lanczos on the CHOLMOD / MUMPS factor of K (default), or a SLEPc method of
:mod:`.fe_slepc` on that factor or on the AMG solver of :mod:`.fe_iterative`; the distributed
products and solves they share.  PETSc and SLEPc are
imported inside functions (see :mod:`.fe`).
"""
from __future__ import annotations

import time

import numpy as np

from .block_lanczos import Breakdown, block_lanczos
from .fe_common import PREFIX as _PREFIX, HousingSolveError, option_defaults


#: columns per block of the block Lanczos solver: MUMPS / CHOLMOD forward-backward sweeps with 16
#: right-hand sides cost ~ 1/5 of 16 single sweeps (the factor is read once per sweep), while the
#: Krylov space needed for 100 modes grows only ~ 1.7x against single-vector Krylov-Schur
BLOCK = 16
#: extra applications of (K^-1 M) to the random start block: removes the rough high-frequency part
#: of the random vectors, which low-degree block Krylov polynomials would leave in the residuals
_SMOOTH = 2


#: the process that ran a CHOLMOD factorisation (None: none has).  CHOLMOD's supernodal
#: factorisation starts GNU OpenMP threads of its own (a team of 4, whatever OMP_NUM_THREADS
#: says), and GNU OpenMP is not fork-safe: a process forked from one that has them deadlocks
#: in its own first CHOLMOD factorisation (an optimisation's evaluations, each building a
#: housing in a worker process, after the parent had built one: cholmod_super_numeric waits
#: forever).  A process whose pid differs from this one was forked from it: MUMPS there.
_CHOLMOD_PID: list = [None]


def _cholmod_safe() -> bool:
    import os
    return _CHOLMOD_PID[0] in (None, os.getpid())


def cholesky_factor(K, comm):
    """KSP (preonly, Cholesky) factored once; CHOLMOD on one process (METIS/AMD ordering: ~25 % fewer
    factor entries than MUMPS with PORD and half the time per triangular solve), MUMPS under MPI
    (ICNTL(14) = 50: INFOG(1) = -9 otherwise) and in a process forked from one that ran
    CHOLMOD (:data:`_CHOLMOD_PID`).  ``-vghousing_st_pc_factor_mat_solver_type`` overrides the
    choice."""
    import os

    from petsc4py import PETSc

    K.setOption(PETSc.Mat.Option.SPD, True)
    package = "cholmod" if (comm.size == 1 and PETSc.Sys.hasExternalPackage("suitesparse")
                            and _cholmod_safe()) else "mumps"
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(f"{_PREFIX}st_")
    ksp.setOperators(K)
    ksp.setType(PETSc.KSP.Type.PREONLY)
    pc = ksp.getPC()
    pc.setType(PETSc.PC.Type.CHOLESKY)
    pc.setFactorSolverType(package)
    with option_defaults(f"{_PREFIX}st_", {"mat_mumps_icntl_14": 50}):
        ksp.setFromOptions()
        if pc.getFactorSolverType() == "cholmod":
            _CHOLMOD_PID[0] = os.getpid()
        ksp.setUp()
    return ksp


def _dense(arr, comm):
    """Distributed PETSc dense matrix holding the local rows ``arr`` (copied, column-major)."""
    from petsc4py import PETSc

    n, k = arr.shape
    N = comm.allreduce(n)
    return PETSc.Mat().createDense(((n, N), (k, k)), array=np.asfortranarray(arr), comm=comm)


def matmul(A, X):
    """Local rows of A @ X for a PETSc AIJ matrix A and local rows X (n_own x k)."""
    if X.shape[1] == 0:
        return np.zeros_like(X)
    D = _dense(X, A.comm.tompi4py())
    C = A.matMult(D)
    out = np.array(C.getDenseArray(), order="F")
    D.destroy()
    C.destroy()
    return out


def matsolve(F, Y, comm):
    """Local rows of K^-1 Y with the factor F: one forward/backward sweep for all columns."""
    B = _dense(Y, comm)
    X = _dense(np.zeros_like(Y), comm)
    F.matSolve(B, X)
    out = np.array(X.getDenseArray(), order="F")
    B.destroy()
    X.destroy()
    return out


def petsc_block_lanczos(K, M, F, comm, *, want, max_dim, tol, start=None, extra=0, mmul=None):
    """Block Lanczos (:mod:`.block_lanczos`) with PETSc operators: the factor F of K, M (``mmul``:
    M's product instead, e.g. a diagonal M's; ``start``, ``extra``: see :func:`.block_lanczos`)."""
    from mpi4py import MPI

    return block_lanczos(
        K.getLocalSize()[0], solve=lambda Y: matsolve(F, Y, comm),
        mmul=(lambda W: matmul(M, W)) if mmul is None else mmul,
        gram=lambda A, B: comm.allreduce(A.T @ B, op=MPI.SUM),
        want=want, max_dim=max_dim, tol=tol, block=BLOCK, smooth=_SMOOTH,
        seed=20261122 + comm.rank, start=start, extra=extra)


def lowest_modes(K, M, *, count, cutoff_hz, max_count, tol, comm, solver="block", coords=None):
    """Lowest modes of K x = lambda M x.  ``solver``: ``"block"`` (block Lanczos on the Cholesky
    factor of K, falling back to SLEPc Krylov-Schur on a breakdown) or a SLEPc method of
    :data:`.fe_slepc.SLEPC_SOLVERS`, with the factor or, for the ``*_gamg`` ones, the AMG solver of
    :mod:`.fe_iterative` (``coords``: the owned nodes' coordinates, for its rigid-body modes).

    Returns (lam, X local rows (n_own x m), converged reason, n converged, status, message, info)."""
    from .fe_slepc import SLEPC_SOLVERS, slepc_eigensolve

    timings = {}
    info = {"solver": solver}
    lam_cut = None if cutoff_hz is None else (2 * np.pi * cutoff_hz) ** 2
    status, message = "ok", ""
    t0 = time.perf_counter()
    ns = None
    if solver != "block" and SLEPC_SOLVERS[solver][2] == "amg":
        from .fe_iterative import amg_ksp

        if coords is None:
            raise HousingSolveError(f"solver {solver!r} needs the node coordinates (rigid-body modes)")
        method = SLEPC_SOLVERS[solver][0]
        ksp, ns = amg_ksp(K, coords, comm, inner="cg" if method == "krylovschur" else "preonly",
                          rtol=min(1e-3 * tol, 1e-10))
        timings["preconditioner_setup"] = time.perf_counter() - t0
        info["package"] = ksp.getPC().getType()
    else:
        ksp = cholesky_factor(K, comm)
        timings["factorization"] = time.perf_counter() - t0
        info["package"] = ksp.getPC().getFactorSolverType()
    if solver == "block":
        nev = count if cutoff_hz is None else max_count
        flag = {}

        def want(theta_conv):
            lam_c = 1.0 / theta_conv
            if lam_cut is None:
                return nev if lam_c.size >= nev else None
            below = int(np.sum(lam_c < lam_cut))
            if below < lam_c.size:             # a converged value above the cut-off: all found
                return below
            if below >= max_count:
                flag["truncated"] = True
                return max_count
            return None

        t0 = time.perf_counter()
        try:
            lam, X, st = petsc_block_lanczos(K, M, ksp.getPC().getFactorMatrix(), comm, want=want, tol=tol,
                                        max_dim=max(3 * nev + 100, 2 * nev + 16 * BLOCK))
        except Breakdown as exc:
            info["fallback"] = str(exc)
            solver = "krylovschur"
        else:
            timings["iterations"] = time.perf_counter() - t0
            timings.update({"solves": st.pop("t_solve"), "orthogonalization": st.pop("t_orth"),
                            "mass_products": st.pop("t_mmul")})
            info.update(st)
            if flag.get("truncated"):
                status, message = "truncated", (f"max_count = {max_count} modes all lie below cutoff_hz = "
                                                f"{cutoff_hz:g}; raise housing.modes.max_count")
            nconv = len(lam)
            ksp.destroy()
            if lam_cut is None and nconv < count:
                raise HousingSolveError(f"block Lanczos converged {nconv} of {count} modes")
            info["timings"] = timings
            return lam, X, "CONVERGED_TOL", nconv, status, message, info
    t0 = time.perf_counter()
    try:
        lam, X, rname, nconv, status, message, st = slepc_eigensolve(
            K, M, ksp, method=solver, count=count, cutoff_hz=cutoff_hz, max_count=max_count, tol=tol,
            comm=comm)
    finally:
        ksp.destroy()
        if ns is not None:
            ns.destroy()
    timings["iterations"] = time.perf_counter() - t0
    info.update(st)
    info["timings"] = timings
    return lam, X, rname, nconv, status, message, info
