"""Housing FE model: dolfinx 0.5.2 elasticity, master modes, bore coupling values.

The only module of vibrogear that imports dolfinx, PETSc or SLEPc, always inside functions, so
importing it costs nothing.  Under ``mpirun`` the mesh is read on rank 0 and partitioned by
dolfinx; K and M are assembled and solved distributed.  Meshing, the on-disk cache and the MPI
orchestration live in :mod:`.housing_run` (``housing_modes``).

    K = int sigma(u) : eps(v) dx (+ k_f int u . v ds_base),  M = int rho u . v dx,
    K x = omega^2 M x,  x^T M x = 1,  B_S = beta K_S  (paper eq. (3)).
"""
from __future__ import annotations

import logging
import os
import resource
import time
from pathlib import Path

import numpy as np

from ..config.housing import MaterialConfig
from ..geometry.housing import BoreGeometry, HousingMesh, read_msh_arrays
from .block_lanczos import Breakdown, block_lanczos
from .housing_result import HousingModes
from .housing_surface_data import outer_surface

__all__ = ["HousingModes", "HousingSolveError", "solve_mesh_modes", "assemble_mesh_matrices"]

log = logging.getLogger(__name__)

_PREVIEW_MODES = 6
_PREVIEW_POINTS = 4000


class HousingSolveError(RuntimeError):
    """The eigen-solve failed or converged too few modes."""


def solve_mesh_modes(mesh: HousingMesh, *, material: MaterialConfig, degree: int = 2,
                     bores: tuple[BoreGeometry, ...] = (), count: int = 20,
                     cutoff_hz: float | None = None, max_count: int = 400, tol: float = 1e-10,
                     solver: str = "block", support: str = "fixed", foundation_stiffness: float = 0.0, shapes: int = 0,
                     shapes_dir: Path | None = None) -> HousingModes:
    """Master modes of the solid in ``mesh`` with its ``base_tag`` facets clamped (or on springs)."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    dmesh, V, K, M, _, mass, timings, ftags = _assemble(mesh, material, degree, support,
                                                         foundation_stiffness, comm)
    n_dofs = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    from dolfinx import fem  # after _assemble, which sets XDG_CACHE_HOME before the first dolfinx import

    t0 = time.perf_counter()
    lam, Vloc, reason, nconv, status, message, info = _eigensolve(
        K, M, count=count, cutoff_hz=cutoff_hz, max_count=max_count, tol=tol, comm=comm, solver=solver)
    timings["eigensolve"] = time.perf_counter() - t0
    timings.update({f"eigensolve_{k}": v for k, v in info.pop("timings").items()})
    if comm.rank == 0:
        log.debug("housing eigensolve: %s", info)

    t0 = time.perf_counter()
    nmode = Vloc.shape[1]
    # honest checks with fresh products: ||K x - lam M x|| / ||K x||, max |V^T M V - I|
    MVloc = _matmul(M, Vloc)
    scale = 1.0 / np.sqrt(comm.allreduce(np.einsum("ij,ij->j", Vloc, MVloc), op=MPI.SUM))
    Vloc *= scale
    MVloc *= scale
    KVloc = _matmul(K, Vloc)
    R = KVloc - MVloc * lam
    resid = np.sqrt(comm.allreduce(np.einsum("ij,ij->j", R, R), op=MPI.SUM)
                    / comm.allreduce(np.einsum("ij,ij->j", KVloc, KVloc), op=MPI.SUM))
    del R, KVloc
    gram = comm.allreduce(Vloc.T @ MVloc, op=MPI.SUM)
    del MVloc
    ortho = float(np.max(np.abs(gram - np.eye(nmode)))) if nmode else 0.0
    uh = fem.Function(V)
    pts, pvals, cvals, n_fallback = _bore_values(dmesh, uh, Vloc, bores, comm)
    prev_pts, prev_vals = _preview(dmesh, V, uh, Vloc[:, :_PREVIEW_MODES], comm)
    skin = outer_surface(*_surface_values(dmesh, ftags, (mesh.base_tag, *mesh.bore_tags), uh,
                                          Vloc, comm))
    timings["postprocess"] = time.perf_counter() - t0

    shapes_path = None
    if shapes > 0 and shapes_dir is not None and nmode:
        t0 = time.perf_counter()
        shapes_path = _write_shapes(dmesh, uh, Vloc[:, :shapes], Path(shapes_dir) / "shapes.xdmf", comm)
        timings["xdmf"] = time.perf_counter() - t0
    for mat in (K, M):
        mat.destroy()
    peak = comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, op=MPI.SUM)
    return HousingModes(
        freqs_hz=np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi), bore_values=pvals, bore_points=pts,
        bore_n_points=tuple(b.n_points for b in bores),
        bore_centers=np.array([b.center for b in bores], dtype=float).reshape(-1, 3),
        bore_axes=np.array([b.axis for b in bores], dtype=float).reshape(-1, 3),
        bore_center_values=cvals, bore_names=tuple(b.name for b in bores), beta=material.beta,
        n_dofs=int(n_dofs), degree=degree, residuals=resid, orthogonality_error=ortho, mass_kg=float(mass),
        n_fallback_points=int(n_fallback), status=status, message=message, converged_reason=reason,
        n_converged=int(nconv), timings=timings, peak_memory_mb=float(peak), n_processes=comm.size,
        shapes_path=shapes_path, preview_points=prev_pts, preview_values=prev_vals,
        **skin.as_fields(),
    )


def _assemble(mesh: HousingMesh, material: MaterialConfig, degree: int, support: str,
              foundation_stiffness: float, comm):
    """(dolfinx mesh, V, K, M, bcs, mass, timings, facet tags): Dirichlet rows 1 in K, 0 in M."""
    os.environ.setdefault("XDG_CACHE_HOME", str(Path.home() / ".cache"))
    from mpi4py import MPI
    import dolfinx
    import dolfinx.fem.petsc  # noqa: F401  (explicit import needed in 0.5.2)
    import ufl
    from dolfinx import fem
    from petsc4py import PETSc

    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    dmesh, facet_tags = _read_mesh(mesh.path, comm)
    timings["mesh_read"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    V = fem.VectorFunctionSpace(dmesh, ("Lagrange", degree))
    E, nu, rho = material.E, material.nu, material.rho
    mu, lmbda = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    sig = lambda w: 2 * mu * eps(w) + lmbda * ufl.tr(eps(w)) * ufl.Identity(3)  # noqa: E731
    a_ufl = ufl.inner(sig(u), eps(v)) * ufl.dx
    fdim = dmesh.topology.dim - 1
    dmesh.topology.create_connectivity(fdim, dmesh.topology.dim)
    base_facets = facet_tags.indices[facet_tags.values == mesh.base_tag]
    bcs = []
    if support == "elastic":
        ds = ufl.Measure("ds", domain=dmesh, subdomain_data=facet_tags)
        a_ufl = a_ufl + foundation_stiffness * ufl.inner(u, v) * ds(mesh.base_tag)
    else:
        dofs = fem.locate_dofs_topological(V, fdim, base_facets)
        bcs = [fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), dofs, V)]
    rho_c = fem.Constant(dmesh, PETSc.ScalarType(rho))
    a = fem.form(a_ufl)
    m = fem.form(rho_c * ufl.inner(u, v) * ufl.dx)
    mass_form = fem.form(rho_c * ufl.dx)
    timings["form_compilation"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    K = dolfinx.fem.petsc.assemble_matrix(a, bcs=bcs, diagonal=1.0)
    K.assemble()
    M = dolfinx.fem.petsc.assemble_matrix(m, bcs=bcs, diagonal=0.0)
    M.assemble()
    mass = comm.allreduce(fem.assemble_scalar(mass_form), op=MPI.SUM)
    timings["assembly"] = time.perf_counter() - t0
    return dmesh, V, K, M, bcs, mass, timings, facet_tags


def assemble_mesh_matrices(mesh: HousingMesh, *, material: MaterialConfig, degree: int = 2,
                           bores: tuple[BoreGeometry, ...] = (), support: str = "fixed",
                           foundation_stiffness: float = 0.0) -> dict:
    """Serial only: K, M (scipy CSR over all DOF, Dirichlet rows 1 in K and 0 in M), ``free`` (the
    unclamped DOF), and T (B*P*3, all DOF): displacement at the bore coupling points, rows in the
    (B, P, 3) C-order of ``HousingModes.bore_values`` (padding rows empty).  T comes from the same
    point location and ``Function.eval`` as the modes' bore values: T @ x reproduces them."""
    import scipy.sparse as sp
    from mpi4py import MPI
    from dolfinx import fem

    comm = MPI.COMM_WORLD
    if comm.size > 1:
        raise HousingSolveError("the full housing matrices are built in serial only (run without mpirun)")
    dmesh, V, K, M, bcs, mass, timings, _ = _assemble(mesh, material, degree, support,
                                                       foundation_stiffness, comm)
    t0 = time.perf_counter()
    n = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
    mask = np.ones(n)
    fem.set_bc(mask, bcs)
    Ks, Ms = (sp.csr_matrix(A.getValuesCSR()[::-1], shape=A.getSize()) for A in (K, M))
    for A in (K, M):
        A.destroy()
    nb, P = len(bores), max((b.n_points for b in bores), default=0)
    pts, rows, cols, vals, n_fallback = np.full((nb, P, 3), np.nan), [], [], [], 0
    if nb:
        flat = np.vstack([b.points() for b in bores])
        cells, _, n_fallback = _locate(dmesh, flat, comm)
        uh = fem.Function(V)
        arr = uh.x.array
        arr[:] = 0.0
        k = 0
        for j, b in enumerate(bores):
            pts[j, :b.n_points] = flat[k:k + b.n_points]
            for p in range(b.n_points):
                for d in V.dofmap.cell_dofs(cells[k]):     # one probe per node: (phi_d, phi_d, phi_d)
                    arr[3 * d:3 * d + 3] = 1.0
                    vals.extend(uh.eval(flat[k:k + 1], cells[k:k + 1]).reshape(3))
                    arr[3 * d:3 * d + 3] = 0.0
                    rows.extend((j * P + p) * 3 + np.arange(3))
                    cols.extend(3 * d + np.arange(3))
                k += 1
    T = sp.csr_matrix((vals, (rows, cols)), shape=(nb * P * 3, n))
    timings["extract"] = time.perf_counter() - t0
    return dict(K=Ks, M=Ms, free=np.flatnonzero(mask != 0.0), T=T, bore_points=pts, mass_kg=float(mass),
                n_fallback_points=int(n_fallback), timings=timings)

def _read_mesh(path: Path, comm):
    """Distributed dolfinx mesh + facet tags (Debian's gmshio.read_from_msh is broken in 0.5.2)."""
    import ufl
    from dolfinx import cpp, mesh as dmesh_mod

    if comm.rank == 0:
        x, cells, facets, values = read_msh_arrays(path)
    else:
        x, cells = np.zeros((0, 3)), np.zeros((0, 4), dtype=np.int64)
        facets, values = np.zeros((0, 3), dtype=np.int64), np.zeros(0, dtype=np.int32)
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.tetrahedron, 1))
    msh = dmesh_mod.create_mesh(comm, cells, x, domain)
    tdim = msh.topology.dim
    ents, vals = cpp.io.distribute_entity_data(msh._mesh if hasattr(msh, "_mesh") else msh, tdim - 1,
                                               facets, values)
    msh.topology.create_connectivity(tdim - 1, tdim)
    msh.topology.create_connectivity(tdim - 1, 0)
    adj = cpp.graph.AdjacencyList_int32(ents)
    ft = dmesh_mod.meshtags_from_entities(msh, tdim - 1, adj, vals.astype(np.int32))
    return msh, ft


_PREFIX = "vghousing_"
#: columns per block of the block Lanczos solver: MUMPS / CHOLMOD forward-backward sweeps with 16
#: right-hand sides cost ~ 1/5 of 16 single sweeps (the factor is read once per sweep), while the
#: Krylov space needed for 100 modes grows only ~ 1.7x against single-vector Krylov-Schur
_BLOCK = 16
#: extra applications of (K^-1 M) to the random start block: removes the rough high-frequency part
#: of the random vectors, which low-degree block Krylov polynomials would leave in the residuals
_SMOOTH = 2


def _factor(K, comm):
    """KSP (preonly, Cholesky) factored once; CHOLMOD on one process (METIS/AMD ordering: ~25 % fewer
    factor entries than MUMPS with PORD and half the time per triangular solve), MUMPS under MPI
    (ICNTL(14) = 50: INFOG(1) = -9 otherwise).  ``-vghousing_st_pc_factor_mat_solver_type``
    overrides the choice."""
    from petsc4py import PETSc

    K.setOption(PETSc.Mat.Option.SPD, True)
    opts = PETSc.Options()
    package = "cholmod" if comm.size == 1 and PETSc.Sys.hasExternalPackage("suitesparse") else "mumps"
    set_icntl = f"{_PREFIX}st_mat_mumps_icntl_14" not in opts
    if set_icntl:
        opts[f"{_PREFIX}st_mat_mumps_icntl_14"] = 50
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(f"{_PREFIX}st_")
    ksp.setOperators(K)
    ksp.setType(PETSc.KSP.Type.PREONLY)
    pc = ksp.getPC()
    pc.setType(PETSc.PC.Type.CHOLESKY)
    pc.setFactorSolverType(package)
    ksp.setFromOptions()
    try:
        ksp.setUp()
    finally:
        if set_icntl:
            opts.delValue(f"{_PREFIX}st_mat_mumps_icntl_14")
    return ksp


def _dense(arr, comm):
    """Distributed PETSc dense matrix holding the local rows ``arr`` (copied, column-major)."""
    from petsc4py import PETSc

    n, k = arr.shape
    N = comm.allreduce(n)
    return PETSc.Mat().createDense(((n, N), (k, k)), array=np.asfortranarray(arr), comm=comm)


def _matmul(A, X):
    """Local rows of A @ X for a PETSc AIJ matrix A and local rows X (n_own x k)."""
    if X.shape[1] == 0:
        return np.zeros_like(X)
    D = _dense(X, A.comm.tompi4py())
    C = A.matMult(D)
    out = np.array(C.getDenseArray(), order="F")
    D.destroy()
    C.destroy()
    return out


def _matsolve(F, Y, comm):
    """Local rows of K^-1 Y with the factor F: one forward/backward sweep for all columns."""
    B = _dense(Y, comm)
    X = _dense(np.zeros_like(Y), comm)
    F.matSolve(B, X)
    out = np.array(X.getDenseArray(), order="F")
    B.destroy()
    X.destroy()
    return out


def _block_lanczos(K, M, F, comm, *, want, max_dim, tol):
    """Block Lanczos (:mod:`.block_lanczos`) with PETSc operators: the factor F of K, M."""
    from mpi4py import MPI

    return block_lanczos(
        K.getLocalSize()[0], solve=lambda Y: _matsolve(F, Y, comm),
        mmul=lambda W: _matmul(M, W),
        gram=lambda A, B: comm.allreduce(A.T @ B, op=MPI.SUM),
        want=want, max_dim=max_dim, tol=tol, block=_BLOCK, smooth=_SMOOTH,
        seed=20261122 + comm.rank)


def _eigensolve(K, M, *, count, cutoff_hz, max_count, tol, comm, solver="block"):
    """Lowest modes of K x = lambda M x: Cholesky of K (shift 0), then block Lanczos (default) or
    SLEPc Krylov-Schur with shift-and-invert at 0 (``solver = "krylovschur"``, and the fallback).

    Returns (lam, X local rows (n_own x m), converged reason, n converged, status, message, info)."""
    timings = {}
    t0 = time.perf_counter()
    ksp = _factor(K, comm)
    timings["factorization"] = time.perf_counter() - t0
    lam_cut = None if cutoff_hz is None else (2 * np.pi * cutoff_hz) ** 2
    status, message = "ok", ""
    info = {"solver": solver, "package": ksp.getPC().getFactorSolverType()}
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
            lam, X, st = _block_lanczos(K, M, ksp.getPC().getFactorMatrix(), comm, want=want, tol=tol,
                                        max_dim=max(3 * nev + 100, 2 * nev + 16 * _BLOCK))
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
            if lam_cut is None and nconv < count:
                ksp.destroy()
                raise HousingSolveError(f"block Lanczos converged {nconv} of {count} modes")
            ksp.destroy()
            info["timings"] = timings
            return lam, X, "CONVERGED_TOL", nconv, status, message, info
    t0 = time.perf_counter()
    lam, X, rname, nconv, status, message = _krylov_schur(K, M, ksp, count=count, cutoff_hz=cutoff_hz,
                                                          max_count=max_count, tol=tol, comm=comm)
    timings["iterations"] = time.perf_counter() - t0
    ksp.destroy()
    n = K.getLocalSize()[0]
    Xloc = np.empty((n, len(X)), order="F")
    for i, x in enumerate(X):
        Xloc[:, i] = x.array
        x.destroy()
    info["timings"] = timings
    return lam, Xloc, rname, nconv, status, message, info


def _krylov_schur(K, M, ksp, *, count, cutoff_hz, max_count, tol, comm):
    """SLEPc shift-and-invert Krylov-Schur at sigma = 0 reusing the factored ``ksp``."""
    from petsc4py import PETSc
    from slepc4py import SLEPc

    eps = SLEPc.EPS().create(comm)
    eps.setOptionsPrefix(_PREFIX)
    eps.setOperators(K, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTarget(0.0)
    eps.setPurify(False)  # Dirichlet rows are 1 in K, 0 in M: no leakage onto clamped DOF
    eps.setTolerances(tol, 500)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(0.0)
    st.setKSP(ksp)
    eps.setFromOptions()
    nev = count if cutoff_hz is None else min(20, max_count)
    lam_cut = None if cutoff_hz is None else (2 * np.pi * cutoff_hz) ** 2
    status, message = "ok", ""
    while True:
        eps.setDimensions(nev, PETSc.DECIDE, PETSc.DECIDE)
        eps.solve()
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
    order = np.argsort(lam)
    want = order[:nev] if lam_cut is None else [i for i in order if lam[i] < lam_cut][:max_count]
    if lam_cut is None and nconv < count:
        eps.destroy()
        raise HousingSolveError(f"SLEPc converged {nconv} of {count} modes ({rname})")
    X = []
    for i in want:
        x = K.createVecRight()
        eps.getEigenpair(int(i), x)
        X.append(x)
    eps.destroy()
    return lam[list(want)], X, rname, nconv, status, message


def _locate(dmesh, points, comm):
    """For each point, (local cell or -1, owning rank); fallback to the closest cell."""
    from mpi4py import MPI
    import dolfinx.geometry as geo

    tdim = dmesh.topology.dim
    tree = geo.BoundingBoxTree(dmesh, tdim)
    cand = geo.compute_collisions(tree, points)
    coll = geo.compute_colliding_cells(dmesh, cand, points)
    n_local_cells = dmesh.topology.index_map(tdim).size_local
    cells = np.full(len(points), -1, dtype=np.int32)
    for k in range(len(points)):
        c = [c for c in coll.links(k) if c < n_local_cells]
        if len(c):
            cells[k] = c[0]
    found = np.where(cells >= 0, comm.rank, comm.size).astype(np.int32)
    owner = np.empty_like(found)
    comm.Allreduce(found, owner, op=MPI.MIN)
    missing = np.flatnonzero(owner == comm.size)
    n_fallback = len(missing)
    if n_fallback:
        entities = np.arange(n_local_cells, dtype=np.int32)
        mid = geo.create_midpoint_tree(dmesh, tdim, entities)
        closest = geo.compute_closest_entity(tree, mid, dmesh, points[missing])
        x = dmesh.geometry.x
        dist = np.full(len(missing), np.inf)
        for j, c in enumerate(closest):
            if c >= 0:
                verts = dmesh.geometry.dofmap.links(c)
                dist[j] = np.min(np.linalg.norm(x[verts] - points[missing[j]], axis=1))
        best = np.empty_like(dist)
        comm.Allreduce(dist, best, op=MPI.MIN)
        for j, k in enumerate(missing):
            mine = dist[j] == best[j] and np.isfinite(dist[j])
            cand_rank = comm.rank if mine else comm.size
            owner[k] = comm.allreduce(cand_rank, op=MPI.MIN)
            if owner[k] == comm.rank:
                cells[k] = closest[j]
    return cells, owner, n_fallback


def _bore_values(dmesh, uh, Vloc, bores, comm):
    from mpi4py import MPI

    nb, m = len(bores), Vloc.shape[1]
    P = max((b.n_points for b in bores), default=0)
    pts = np.full((nb, P, 3), np.nan)
    vals = np.full((nb, P, 3, m), np.nan)
    cvals = np.zeros((nb, 3, m))
    if nb == 0:
        return pts, vals, cvals, 0
    flat = np.vstack([b.points() for b in bores])
    cells, owner, n_fallback = _locate(dmesh, flat, comm)
    mine = np.flatnonzero(owner == comm.rank)
    local = np.zeros((len(flat), 3, m))
    for i in range(m):
        uh.vector.array[:] = Vloc[:, i]
        uh.x.scatter_forward()
        if len(mine):
            local[mine, :, i] = uh.eval(flat[mine], cells[mine])
    allv = np.zeros_like(local)
    comm.Allreduce(local, allv, op=MPI.SUM)
    k = 0
    for j, b in enumerate(bores):
        n = b.n_points
        pts[j, :n] = flat[k:k + n]
        vals[j, :n] = allv[k:k + n]
        cvals[j] = allv[k:k + n].mean(axis=0)
        k += n
    return pts, vals, cvals, n_fallback


def _surface_values(dmesh, ftags, skip_tags, uh, Vloc, comm):
    """Exterior facets not tagged ``skip_tags`` (base, bores), gathered on rank 0: their vertex
    coordinates (nf, 3, 3), ordered so that (b - a) x (c - a) points out of the solid, and each
    mode's displacement along that normal at the three edge midpoints (nf, 3, m)."""
    import dolfinx.mesh
    from dolfinx import cpp

    tdim = dmesh.topology.dim
    fdim = tdim - 1
    dmesh.topology.create_connectivity(fdim, tdim)
    f2c = dmesh.topology.connectivity(fdim, tdim)
    facets = dolfinx.mesh.exterior_facet_indices(dmesh.topology)
    facets = facets[facets < dmesh.topology.index_map(fdim).size_local]
    facets = np.setdiff1d(facets, ftags.indices[np.isin(ftags.values, skip_tags)])
    x = dmesh.geometry.x
    cmesh = dmesh._mesh if hasattr(dmesh, "_mesh") else dmesh
    tri = x[cpp.mesh.entities_to_geometry(cmesh, fdim, facets, False)]        # (nf, 3, 3)
    cells = np.array([f2c.links(f)[0] for f in facets], dtype=np.int32)
    centroid = np.array([x[dmesh.geometry.dofmap.links(c)].mean(axis=0) for c in cells])
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    flip = np.einsum("ij,ij->i", normal, tri[:, 0] - centroid.reshape(-1, 3)) < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    normal[flip] *= -1.0
    unit = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    mids = 0.5 * (tri + tri[:, [1, 2, 0]])                                     # edge midpoints
    pts, where = mids.reshape(-1, 3), np.repeat(cells, 3)
    vals = np.zeros((len(facets), 3, Vloc.shape[1]))
    for i in range(Vloc.shape[1]):
        uh.vector.array[:] = Vloc[:, i]
        uh.x.scatter_forward()
        if len(pts):
            u = uh.eval(pts, where).reshape(-1, 3, 3)
            vals[:, :, i] = np.einsum("fqc,fc->fq", u, unit)
    tris, allv = comm.gather(tri, root=0), comm.gather(vals, root=0)
    if comm.rank != 0:
        return np.zeros((0, 3, 3)), np.zeros((0, 3, Vloc.shape[1]))
    return np.concatenate(tris), np.concatenate(allv)


def _preview(dmesh, V, uh, Vloc, comm):
    """Boundary dof coordinates and the first modes there, subsampled, for plots."""
    import dolfinx.mesh
    from dolfinx import fem

    fdim = dmesh.topology.dim - 1
    facets = dolfinx.mesh.exterior_facet_indices(dmesh.topology)
    blocks = fem.locate_dofs_topological(V, fdim, facets)
    blocks = blocks[blocks < V.dofmap.index_map.size_local]
    xyz = V.tabulate_dof_coordinates()[blocks]
    vals = np.stack([Vloc[:, i].reshape(-1, 3)[blocks] for i in range(Vloc.shape[1])], axis=-1)
    all_xyz = comm.gather(xyz, root=0)
    all_vals = comm.gather(vals, root=0)
    if comm.rank != 0:
        return np.zeros((0, 3)), np.zeros((0, 3, Vloc.shape[1]))
    xyz, vals = np.vstack(all_xyz), np.concatenate(all_vals, axis=0)
    order = np.lexsort(np.round(xyz, 9).T)
    step = max(1, len(order) // _PREVIEW_POINTS)
    sel = order[::step]
    return xyz[sel], vals[sel]


def _write_shapes(dmesh, uh, Vloc, path: Path, comm) -> Path:
    from dolfinx import fem
    from dolfinx.io import XDMFFile

    V1 = fem.VectorFunctionSpace(dmesh, ("Lagrange", 1))
    u1 = fem.Function(V1)
    u1.name = "mode_shape"
    with XDMFFile(comm, str(path), "w") as f:
        f.write_mesh(dmesh)
        for i in range(Vloc.shape[1]):
            uh.vector.array[:] = Vloc[:, i]
            uh.x.scatter_forward()
            u1.interpolate(uh)
            f.write_function(u1, t=float(i + 1))
    return path
