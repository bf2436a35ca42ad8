"""Housing master modes with the on-disk cache and MPI orchestration (no dolfinx here).

:func:`housing_modes` meshes (gmsh, rank 0), solves (:func:`.housing.solve_mesh_modes`, the
one dolfinx/PETSc/SLEPc module) and caches; a cache hit does no FE work and never imports
dolfinx.  Under ``mpirun`` every rank returns the same :class:`HousingModes`; only rank 0
writes cache entries; an exception on one rank aborts all of them (no hang).

:func:`housing_matrices` (serial only) gives the full, non-reduced free-DOF K and M and the bore
interpolation operators on the same mesh, for checks of the modal reduction; cached likewise.
"""
from __future__ import annotations

import dataclasses
import logging
import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import numpy as np

from ...config.model.housing import HousingConfig
from ...geometry.housing import HousingMesh
from ...geometry.housing_import import build_mesh, mesh_bores, mesh_info
from ...cache import cache_key, discard_entry, entry_dir, new_workspace, open_entry, publish_entry
from .result import HousingModes, load_modes, save_modes

__all__ = ["HousingModes", "HousingMatrices", "housing_modes", "housing_matrices", "housing_matrices_key",
           "housing_cache_key", "housing_cache_keys", "HousingNumericalError",
           "under_mpi"]

log = logging.getLogger(__name__)

#: layout of the modes / matrices cache entries, part of their keys: entries of an older
#: layout (1: no outer-surface data, 2: no boundary-surface shapes) are rebuilt, never misread
CACHE_FORMAT = 3


class HousingNumericalError(ArithmeticError):
    """The housing FE assembly or eigensolve failed numerically; the message says which
    stage and the likely cause (the runner reports it as a numerical failure, exit 1)."""


def _solve_failure(cfg: HousingConfig, stage: str, exc: BaseException) -> HousingNumericalError:
    hints = []
    if not 1e6 <= cfg.material.E <= 1e13:
        hints.append(f"housing.material.E = {cfg.material.E:g} Pa is far outside the range of "
                     "solids (1e6..1e13 Pa), so the stiffness matrix over- or underflows")
    if cfg.support == "elastic" and cfg.foundation_stiffness < 1e6:
        hints.append(f"housing.foundation_stiffness = {cfg.foundation_stiffness:g} N/m^3 is so "
                     "soft that the housing is nearly free (singular stiffness matrix); use "
                     "support = 'fixed' or a stiffer foundation (1e8..1e12 N/m^3)")
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    return HousingNumericalError(f"housing FE {stage} failed ({type(exc).__name__}: {text})"
                             + (f"; likely cause: {'; '.join(hints)}" if hints else
                                "; the stiffness matrix is probably singular or not finite"))


def under_mpi() -> bool:
    return int(os.environ.get("OMPI_COMM_WORLD_SIZE", os.environ.get("PMI_SIZE", "1"))) > 1


def _comm():
    if not under_mpi():
        return None
    from mpi4py import MPI
    return MPI.COMM_WORLD


def _bcast(comm, value):
    return value if comm is None else comm.bcast(value, root=0)


def _rank(comm) -> int:
    return 0 if comm is None else comm.rank


def housing_cache_key(cfg: HousingConfig, stage: str) -> str:
    """The cache key of a housing stage, the one place it is defined: ``"mesh"`` depends on
    the geometry and the resolved mesh sizes only; ``"modes"`` and ``"matrices"`` on the whole
    housing config (``modes.solver`` and ``tol`` included) plus the resolved mesh sizes (and
    share its hash)."""
    # the resolved mesh sizes: a changed default rule (mesh.size / bore_size left out) must
    # give a new key, not the entry solved on the old default mesh
    resolved = {"size": cfg.mesh_size, "bore_size": cfg.bore_mesh_size}
    if stage == "mesh":
        geo = cfg.key_data()
        for k in ("material", "modes", "support", "foundation_stiffness"):
            geo.pop(k)
        geo["mesh"] = {**resolved, "refine": cfg.mesh.refine}
        return cache_key("housing-mesh", geo)
    if stage not in ("modes", "matrices"):
        raise ValueError(f"unknown housing cache stage {stage!r}")
    return cache_key(f"housing-{stage}", {**cfg.key_data(), "entry_format": CACHE_FORMAT,
                                          "resolved_mesh": resolved})


def housing_cache_keys(cfg: HousingConfig) -> tuple[str, str]:
    """(mesh key, modes key)."""
    return housing_cache_key(cfg, "mesh"), housing_cache_key(cfg, "modes")


def _cached_modes(key: str) -> HousingModes | None:
    """The verified modes entry ``key`` loaded, or None (an invalid one is removed)."""
    folder = open_entry(key)
    if folder is None:
        return None
    try:
        return load_modes(folder, key=key)
    except Exception as exc:                 # valid checksums but unreadable: another layout
        discard_entry(key, f"cannot be read: {exc}")
        return None


def housing_modes(cfg: HousingConfig, *, cache: bool = True) -> HousingModes:
    """Mesh -> assemble -> solve, with the on-disk cache (a hit does no FE work; an invalid
    entry is rebuilt with a warning)."""
    if cfg.source == "modal":                # another FE program's modes: read, no FE work here
        from .modal import read_modal_housing
        return read_modal_housing(cfg)
    comm = _comm()
    mesh_key, modes_key = housing_cache_keys(cfg)
    if cache and _bcast(comm, _cached_modes(modes_key) is not None if _rank(comm) == 0 else None):
        t0 = time.perf_counter()
        res = _cached_modes(modes_key)
        if res is not None:
            return dataclasses.replace(res, timings={**res.timings, "cache_load": time.perf_counter() - t0})
    try:
        return _compute(cfg, comm, mesh_key, modes_key, cache)
    except Exception as exc:
        if comm is not None and comm.size > 1:
            log.critical("[rank %d] housing FE failed; aborting all ranks", comm.rank,
                         exc_info=True)
            comm.Abort(1)
        if _is_numerical(exc):
            raise _solve_failure(cfg, "modal solve", exc) from exc
        raise


def _is_numerical(exc: BaseException) -> bool:
    """PETSc/SLEPc, CHOLMOD and linear-algebra errors (not the package's own errors)."""
    mod = type(exc).__module__ or ""
    return (isinstance(exc, (ArithmeticError, np.linalg.LinAlgError))
            or mod.split(".")[0] in ("petsc4py", "slepc4py", "sksparse", "scipy")
            or "CHOLMOD" in str(exc) or "not positive definite" in str(exc))


def _compute(cfg, comm, mesh_key, modes_key, cache) -> HousingModes:
    rank = _rank(comm)
    root = entry_dir(modes_key).parent if cache else Path(tempfile.gettempdir())
    work = _bcast(comm, (new_workspace(modes_key) if cache else
                         Path(tempfile.mkdtemp(prefix=f".{modes_key}.", dir=root))) if rank == 0 else None)
    try:
        hm, t_mesh = _mesh(cfg, mesh_key, root, cache) if rank == 0 else (None, 0.0)
    except BaseException:                    # e.g. an imported file's bore cuts no face
        shutil.rmtree(work, ignore_errors=True)
        raise
    hm = _bcast(comm, hm)
    if comm is not None and os.environ.get("VIBROGEAR_HOUSING_FAIL_RANK") == str(comm.rank):
        raise RuntimeError("injected failure (VIBROGEAR_HOUSING_FAIL_RANK, for the MPI abort test)")
    m = cfg.modes
    from .fe import solve_mesh_modes

    try:
        res = solve_mesh_modes(hm, material=cfg.material, degree=cfg.mesh.degree,
                               bores=mesh_bores(cfg, hm), count=m.count, cutoff_hz=m.cutoff_hz,
                               max_count=m.max_count, tol=m.tol, solver=m.solver,
                               support=cfg.support, foundation_stiffness=cfg.foundation_stiffness,
                               shapes=m.shapes, shapes_dir=work)
    except BaseException:
        if rank == 0:
            shutil.rmtree(work, ignore_errors=True)      # no half-built entry left behind
        raise
    res = dataclasses.replace(res, timings={"meshing": t_mesh, **res.timings}, cache_key=modes_key,
                              source_info={"source": cfg.source, **mesh_info(cfg, hm),
                                           **({"cell_type": hm.cell_type} if hm.cell_type != "tetrahedron" else {})})
    if rank == 0:
        save_modes(res, work)
        if cache:
            final = publish_entry(work, modes_key)
            res = dataclasses.replace(res, shapes_path=(final / res.shapes_path.name)
                                      if res.shapes_path is not None else None)
    return _bcast(comm, res) if comm is not None else res


def _mesh(cfg, mesh_key, root, cache) -> tuple[HousingMesh, float]:
    """The housing mesh from the mesh cache or gmsh (one process), and the meshing seconds."""
    mesh_dir = open_entry(mesh_key) if cache else None
    if mesh_dir is not None:
        try:
            return _load_mesh_meta(mesh_dir), 0.0
        except Exception as exc:             # valid checksums but unreadable: another layout
            discard_entry(mesh_key, f"cannot be read: {exc}")
    tmp = new_workspace(mesh_key) if cache else Path(tempfile.mkdtemp(prefix=f".{mesh_key}.", dir=root))
    try:
        hm = build_mesh(cfg, tmp / "mesh.msh")
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    seconds = hm.seconds
    _save_mesh_meta(hm, tmp)
    if cache:
        mesh_dir = publish_entry(tmp, mesh_key)
        hm = hm._replace(path=mesh_dir / "mesh.msh")
    if not hm.path.is_file():
        hm = _load_mesh_meta(mesh_dir)
    return hm, seconds


def _save_mesh_meta(hm: HousingMesh, folder: Path) -> None:
    import json
    d = hm._asdict()
    d["path"] = hm.path.name
    (folder / "mesh.json").write_text(json.dumps(d))


def _load_mesh_meta(folder: Path) -> HousingMesh:
    import json
    d = json.loads((folder / "mesh.json").read_text())
    d["path"] = folder / d["path"]
    d["bore_tags"] = tuple(d["bore_tags"])
    return HousingMesh(**d)


@dataclass(frozen=True, eq=False, kw_only=True)
class HousingMatrices:
    """The non-reduced housing on the mesh of :func:`housing_modes` (same config, same DOF).

    N = number of free (unclamped) DOF, B bores, P the largest rolling-element count.

    - ``K``, ``M``       (N, N) scipy CSR, symmetric; K SPD (clamped DOF removed); B_S = beta K
    - ``T``              (B*P*3, N) CSR: x -> displacements at the bore coupling points, row
                         (b*P + p)*3 + c, i.e. ``(T @ X).reshape(B, P, 3, -1)`` is laid out like
                         ``HousingModes.bore_values`` (padding points: empty rows, value 0, not NaN)
    - ``T_center``       (B*3, N) CSR: row b*3 + c = mean of bore b's ring rows, as
                         ``bore_center_values``
    - ``free_dofs``      (N,) indices of the free DOF in dolfinx's serial numbering (3*node + c)
    - ``bore_points``    (B, P, 3) coupling points (NaN padding), as ``HousingModes.bore_points``
    """
    K: object
    M: object
    T: object
    T_center: object
    free_dofs: np.ndarray
    n_dofs_total: int
    bore_points: np.ndarray
    bore_n_points: tuple[int, ...]
    bore_names: tuple[str, ...]
    beta: float
    degree: int
    mass_kg: float
    n_fallback_points: int
    timings: Mapping[str, float] = field(default_factory=dict)
    cached: bool = False
    cache_key: str = ""

    @property
    def n_dofs(self) -> int:
        return int(self.K.shape[0])


_SPARSE = ("K", "M", "T", "T_center")
_META = ("n_dofs_total", "bore_n_points", "bore_names", "beta", "degree", "mass_kg", "n_fallback_points")


def housing_matrices_key(cfg: HousingConfig) -> str:
    return housing_cache_key(cfg, "matrices")


def _cached_matrices(key: str) -> HousingMatrices | None:
    import json
    import scipy.sparse as sp

    final = open_entry(key)
    if final is None:
        return None
    t0 = time.perf_counter()
    try:
        meta = json.loads((final / "meta.json").read_text())
        with np.load(final / "matrices.npz") as z:
            arrays = {k: sp.csr_matrix((z[k + "_data"], z[k + "_indices"], z[k + "_indptr"]),
                                       shape=tuple(z[k + "_shape"])) for k in _SPARSE}
            arrays.update(free_dofs=z["free_dofs"], bore_points=z["bore_points"])
        meta.update(bore_n_points=tuple(meta["bore_n_points"]), bore_names=tuple(meta["bore_names"]),
                    timings={**meta["timings"], "cache_load": time.perf_counter() - t0})
        return HousingMatrices(**arrays, **meta, cached=True, cache_key=key)
    except Exception as exc:                 # valid checksums but unreadable: another layout
        discard_entry(key, f"cannot be read: {exc}")
        return None


def housing_matrices(cfg: HousingConfig, *, cache: bool = True) -> HousingMatrices:
    """Full free-DOF K, M and bore operators T, T_center (serial; a cache hit does no FE work)."""
    import json
    import scipy.sparse as sp

    if under_mpi():
        raise RuntimeError("housing_matrices is serial: call it without mpirun")
    if cfg.source == "modal":
        from ...config.base import ConfigError
        raise ConfigError("housing.source", "the full housing matrices need an FE model; a 'modal' "
                          "housing has only its modes at the coupling points")
    key = housing_matrices_key(cfg)
    res = _cached_matrices(key) if cache else None
    if res is not None:
        return res
    root = entry_dir(key).parent if cache else Path(tempfile.gettempdir())
    hm, t_mesh = _mesh(cfg, housing_cache_key(cfg, "mesh"), root, cache)
    from .fe import assemble_mesh_matrices

    bores = mesh_bores(cfg, hm)
    try:
        raw = assemble_mesh_matrices(hm, material=cfg.material, degree=cfg.mesh.degree, bores=bores,
                                     support=cfg.support, foundation_stiffness=cfg.foundation_stiffness)
    except Exception as exc:
        if _is_numerical(exc):
            raise _solve_failure(cfg, "assembly", exc) from exc
        raise
    free = raw["free"]
    T = raw["T"][:, free].tocsr()
    T.eliminate_zeros()
    B, P = raw["bore_points"].shape[:2]
    C = sp.lil_matrix((B * 3, B * P * 3))                 # bore centre = mean of its ring rows
    for j, b in enumerate(bores):
        for c in range(3):
            C[3 * j + c, (j * P + np.arange(b.n_points)) * 3 + c] = 1.0 / b.n_points
    res = HousingMatrices(
        K=raw["K"][free][:, free].tocsr(), M=raw["M"][free][:, free].tocsr(), T=T,
        T_center=(C.tocsr() @ T).tocsr(), free_dofs=free, n_dofs_total=int(raw["K"].shape[0]),
        bore_points=raw["bore_points"], bore_n_points=tuple(b.n_points for b in bores),
        bore_names=tuple(b.name for b in bores), beta=cfg.material.beta, degree=cfg.mesh.degree,
        mass_kg=raw["mass_kg"], n_fallback_points=raw["n_fallback_points"],
        timings={"meshing": t_mesh, **raw["timings"]}, cache_key=key)
    if cache:
        tmp = new_workspace(key)
        arrays = {"free_dofs": free, "bore_points": res.bore_points}
        for k in _SPARSE:
            A = getattr(res, k)
            arrays.update({k + "_data": A.data, k + "_indices": A.indices, k + "_indptr": A.indptr,
                           k + "_shape": np.array(A.shape)})
        np.savez(tmp / "matrices.npz", **arrays)
        meta = {k: getattr(res, k) for k in _META}
        (tmp / "meta.json").write_text(json.dumps({**meta, "timings": dict(res.timings)}, indent=1))
        publish_entry(tmp, key)
    return res
