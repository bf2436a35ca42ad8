"""Housing FE model, stage 1 of 3: dolfinx 0.5.2 elasticity assembly and the solve driver.

The housing FE modules (``fe``: assembly, ``fe_eigen``: the eigen-solve, ``fe_post``: values at
the bores, on the skin and in XDMF; ``surface_mesh.boundary_surface``: the boundary for
pictures) are the only ones of vibrogear that import dolfinx, PETSc or
SLEPc, always inside functions, so importing them costs nothing.  Under ``mpirun`` the mesh is
read on rank 0 and partitioned by dolfinx; K and M are assembled and solved distributed.
Meshing, the on-disk cache and the MPI orchestration live in :mod:`.run` (``housing_modes``).

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

from ...config.model.housing import MaterialConfig
from ...geometry.housing import BoreGeometry, HousingMesh, read_msh_arrays
from ...geometry.housing_hex import read_hex_mesh
from .fe_eigen import HousingSolveError, lowest_modes, matmul
from .fe_post import bore_coupling_values, locate, mode_previews, surface_values, write_shapes
from .result import HousingModes
from .surface_data import outer_surface
from .surface_mesh import boundary_surface

__all__ = ["HousingModes", "HousingSolveError", "solve_mesh_modes", "assemble_mesh_matrices"]

log = logging.getLogger(__name__)

_PREVIEW_MODES = 6


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
    coords = V.tabulate_dof_coordinates()[:V.dofmap.index_map.size_local] if solver.endswith("_gamg") else None
    lam, Vloc, reason, nconv, status, message, info = lowest_modes(
        K, M, count=count, cutoff_hz=cutoff_hz, max_count=max_count, tol=tol, comm=comm, solver=solver,
        coords=coords)
    timings["eigensolve"] = time.perf_counter() - t0
    timings.update({f"eigensolve_{k}": v for k, v in info.pop("timings").items()})
    if comm.rank == 0:
        log.debug("housing eigensolve: %s", info)

    t0 = time.perf_counter()
    nmode = Vloc.shape[1]
    # honest checks with fresh products: ||K x - lam M x|| / ||K x||, max |V^T M V - I|
    MVloc = matmul(M, Vloc)
    scale = 1.0 / np.sqrt(comm.allreduce(np.einsum("ij,ij->j", Vloc, MVloc), op=MPI.SUM))
    Vloc *= scale
    MVloc *= scale
    KVloc = matmul(K, Vloc)
    R = KVloc - MVloc * lam
    resid = np.sqrt(comm.allreduce(np.einsum("ij,ij->j", R, R), op=MPI.SUM)
                    / comm.allreduce(np.einsum("ij,ij->j", KVloc, KVloc), op=MPI.SUM))
    del R, KVloc
    gram = comm.allreduce(Vloc.T @ MVloc, op=MPI.SUM)
    del MVloc
    ortho = float(np.max(np.abs(gram - np.eye(nmode)))) if nmode else 0.0
    uh = fem.Function(V)
    pts, pvals, cvals, n_fallback = bore_coupling_values(dmesh, uh, Vloc, bores, comm)
    prev_pts, prev_vals = mode_previews(dmesh, V, uh, Vloc[:, :_PREVIEW_MODES], comm)
    skin = outer_surface(*surface_values(dmesh, ftags, (mesh.base_tag, *mesh.bore_tags), uh,
                                          Vloc, comm))
    t1 = time.perf_counter()
    shape = boundary_surface(dmesh, ftags, mesh.base_tag, mesh.bore_tags, bores, uh, Vloc,
                             material.rho, comm)
    timings["boundary_surface"] = time.perf_counter() - t1
    timings["postprocess"] = time.perf_counter() - t0

    shapes_path = None
    if shapes > 0 and shapes_dir is not None and nmode:
        t0 = time.perf_counter()
        shapes_path = write_shapes(dmesh, uh, Vloc[:, :shapes], Path(shapes_dir) / "shapes.xdmf", comm)
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
        **skin.as_fields(), **shape,
    )


def _assemble(mesh: HousingMesh, material: MaterialConfig, degree: int, support: str,
              foundation_stiffness: float, comm):
    """(dolfinx mesh, V, K, M, bcs, mass, timings, facet tags): Dirichlet rows 1 in K, 0 in M."""
    os.environ.setdefault("XDG_CACHE_HOME", str(Path.home() / ".cache"))
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    dmesh, facet_tags = read_mesh(mesh.path, comm)
    timings["mesh_read"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    forms = housing_forms(dmesh, facet_tags, mesh.base_tag, material, degree, support, foundation_stiffness)
    timings["form_compilation"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    K, M, mass = assemble_forms(forms, comm)
    timings["assembly"] = time.perf_counter() - t0
    return dmesh, forms["V"], K, M, forms["bcs"], mass, timings, facet_tags


def stiffness_jit_params() -> dict:
    """FFCx/CFFI options for the stiffness kernel: on x86-64 compiled for this CPU (``-O3
    -march=native``; the Q3 hexahedron's K assembled in 3.5 s instead of 5.0 s on the benchmark
    machine, of which ~2.4 s is the insertion into the matrix), with a hash of the CPU's model and
    flags as a define, so the JIT cache, keyed by the compile line, keeps one build per CPU kind
    where machines share a home directory.  Elsewhere dolfinx's defaults ({} here)."""
    import hashlib
    import platform

    if platform.machine() not in ("x86_64", "AMD64"):
        return {}
    tag = platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            tag += "".join(line for line in fh.read(200_000).splitlines(True)
                           if line.startswith(("model name", "flags")))[:20_000]
    except OSError:
        pass
    cpu = hashlib.sha1(tag.encode()).hexdigest()[:12]
    return {"cffi_extra_compile_args": ["-O3", "-march=native", "-g0", f"-DVIBROGEAR_CPU_{cpu}"]}


def housing_forms(dmesh, facet_tags, base_tag: int, material: MaterialConfig, degree: int, support: str,
           foundation_stiffness: float) -> dict:
    """The compiled stiffness, mass and volume forms on ``dmesh`` (dict: V, a, m, mass, bcs, hexes);
    they follow the mesh's node coordinates, so a moved mesh is re-assembled with the same forms."""
    os.environ.setdefault("XDG_CACHE_HOME", str(Path.home() / ".cache"))
    import dolfinx.fem.petsc  # noqa: F401  (explicit import needed in 0.5.2)
    import ufl
    from dolfinx import fem
    from petsc4py import PETSc

    V = fem.VectorFunctionSpace(dmesh, ("Lagrange", degree))
    E, nu, rho = material.E, material.nu, material.rho
    mu, lmbda = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    sig = lambda w: 2 * mu * eps(w) + lmbda * ufl.tr(eps(w)) * ufl.Identity(3)  # noqa: E731
    hexes = dmesh.topology.cell_type.name == "hexahedron"
    # hexahedra: (p + 1)^3 Gauss points, exact for the stiffness of a parallelepiped (FFCx's own
    # estimate for the trilinear map asks for (p + 2)^3 or more)
    a_ufl = ufl.inner(sig(u), eps(v)) * ufl.dx(metadata={"quadrature_degree": 2 * degree} if hexes else {})
    fdim = dmesh.topology.dim - 1
    dmesh.topology.create_connectivity(fdim, dmesh.topology.dim)
    base_facets = facet_tags.indices[facet_tags.values == base_tag]
    bcs = []
    if support == "elastic":
        ds = ufl.Measure("ds", domain=dmesh, subdomain_data=facet_tags)
        a_ufl = a_ufl + foundation_stiffness * ufl.inner(u, v) * ds(base_tag)
    else:
        dofs = fem.locate_dofs_topological(V, fdim, base_facets)
        bcs = [fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), dofs, V)]
    rho_c = fem.Constant(dmesh, PETSc.ScalarType(rho))
    # hexahedra: Gauss-Lobatto-Legendre quadrature on the element's own nodes lumps the mass
    # exactly onto the diagonal (spectral-element lumping; docs/housing.md, "Hexahedra")
    md = {"quadrature_rule": "GLL", "quadrature_degree": 2 * degree - 1} if hexes else {}
    return {"V": V, "a": fem.form(a_ufl, jit_params=stiffness_jit_params()),
            "m": fem.form(rho_c * ufl.inner(u, v) * ufl.dx(metadata=md)),
            "mass": fem.form(rho_c * ufl.dx), "bcs": bcs, "hexes": hexes, "rho": rho_c}


def assemble_forms(forms: dict, comm, K=None):
    """(K, M, mass) of :func:`housing_forms`; ``K``: a matrix of the same forms to assemble into (its
    sparsity pattern, and so a factor's symbolic analysis, stays)."""
    from mpi4py import MPI
    import dolfinx.fem.petsc
    from dolfinx import fem
    from petsc4py import PETSc

    a, m, bcs = forms["a"], forms["m"], forms["bcs"]
    if K is None:
        K = dolfinx.fem.petsc.assemble_matrix(a, bcs=bcs, diagonal=1.0)
    else:
        K.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(K, a, bcs=bcs, diagonal=1.0)
    K.assemble()
    M = dolfinx.fem.petsc.assemble_matrix(m, bcs=bcs, diagonal=0.0)
    M.assemble()
    if forms["hexes"]:                        # keep the diagonal only: the rest is exactly zero
        diag = M.getDiagonal()
        full, on_diag = M.norm(PETSc.NormType.FROBENIUS), diag.norm()
        if full ** 2 - on_diag ** 2 > 1e-10 * on_diag ** 2:     # round-off of the two sums: ~1e-16
            raise HousingSolveError(f"the GLL-lumped hexahedral mass matrix is not diagonal (off-diagonal "
                                    f"Frobenius norm {max(full ** 2 - on_diag ** 2, 0) ** 0.5:.3g} against "
                                    f"{on_diag:.3g}): the element's nodes are not the GLL points")
        M.destroy()
        M = PETSc.Mat().createAIJ(K.getSizes(), nnz=(1, 0), comm=comm)
        M.setDiagonal(diag)
        M.assemble()
        diag.destroy()
    mass = comm.allreduce(fem.assemble_scalar(forms["mass"]), op=MPI.SUM)
    return K, M, mass


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
        cells, _, n_fallback = locate(dmesh, flat, comm)
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

def read_mesh(path: Path, comm):
    """Distributed dolfinx mesh + facet tags (Debian's gmshio.read_from_msh is broken in 0.5.2)."""
    import ufl
    from dolfinx import cpp, mesh as dmesh_mod

    hexes = Path(path).suffix == ".npz"          # geometry.housing_hex writes .npz
    nv, nf = (8, 4) if hexes else (4, 3)
    if comm.rank == 0:
        x, cells, facets, values = read_hex_mesh(path) if hexes else read_msh_arrays(path)
    else:
        x, cells = np.zeros((0, 3)), np.zeros((0, nv), dtype=np.int64)
        facets, values = np.zeros((0, nf), dtype=np.int64), np.zeros(0, dtype=np.int32)
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.hexahedron if hexes else ufl.tetrahedron, 1))
    msh = dmesh_mod.create_mesh(comm, cells, x, domain)
    tdim = msh.topology.dim
    ents, vals = cpp.io.distribute_entity_data(msh._mesh if hasattr(msh, "_mesh") else msh, tdim - 1,
                                               facets, values)
    msh.topology.create_connectivity(tdim - 1, tdim)
    msh.topology.create_connectivity(tdim - 1, 0)
    adj = cpp.graph.AdjacencyList_int32(ents)
    ft = dmesh_mod.meshtags_from_entities(msh, tdim - 1, adj, vals.astype(np.int32))
    return msh, ft


