"""Housing master modes with the on-disk cache and MPI orchestration (no dolfinx here).

:func:`housing_modes` meshes (gmsh, rank 0), solves (:func:`.housing.solve_mesh_modes`, the
one dolfinx/PETSc/SLEPc module) and caches; a cache hit does no FE work and never imports
dolfinx.  Under ``mpirun`` every rank returns the same :class:`HousingModes`; only rank 0
writes cache entries; an exception on one rank aborts all of them (no hang).
"""
from __future__ import annotations

import dataclasses
import os
import sys
import tempfile
import time
import traceback
from pathlib import Path

from ..config.housing import HousingConfig
from ..geometry.housing import HousingMesh, bore_layout, build_housing_mesh
from ..cache import cache_key, entry_dir
from .housing_result import HousingModes, load_modes, publish, save_modes

__all__ = ["HousingModes", "housing_modes", "housing_cache_keys", "under_mpi"]


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


def housing_cache_keys(cfg: HousingConfig) -> tuple[str, str]:
    """(mesh key, modes key): the mesh depends on geometry and mesh sizes only."""
    geo = dataclasses.asdict(cfg)
    for k in ("material", "modes", "support", "foundation_stiffness"):
        geo.pop(k)
    geo["mesh"] = {"size": cfg.mesh_size, "bore_size": cfg.bore_mesh_size, "refine": cfg.mesh.refine}
    return cache_key("housing-mesh", geo), cache_key("housing-modes", dataclasses.asdict(cfg))


def housing_modes(cfg: HousingConfig, *, cache: bool = True) -> HousingModes:
    """Mesh -> assemble -> solve, with the on-disk cache (a hit does no FE work)."""
    comm = _comm()
    mesh_key, modes_key = housing_cache_keys(cfg)
    final = entry_dir(modes_key)
    if cache and _bcast(comm, (final / "meta.json").is_file() if _rank(comm) == 0 else None):
        t0 = time.perf_counter()
        res = load_modes(final, key=modes_key)
        return dataclasses.replace(res, timings={**res.timings, "cache_load": time.perf_counter() - t0})
    try:
        return _compute(cfg, comm, mesh_key, modes_key, cache)
    except Exception:
        if comm is not None and comm.size > 1:
            sys.stderr.write(f"[rank {comm.rank}] housing FE failed; aborting all ranks\n")
            traceback.print_exc()
            sys.stderr.flush()
            comm.Abort(1)
        raise


def _compute(cfg, comm, mesh_key, modes_key, cache) -> HousingModes:
    rank = _rank(comm)
    root = (entry_dir(modes_key).parent if cache else Path(tempfile.gettempdir()))
    work = _bcast(comm, Path(tempfile.mkdtemp(prefix=f".{modes_key}.", dir=root)) if rank == 0 else None)
    mesh_dir = entry_dir(mesh_key)
    t_mesh = 0.0
    if rank == 0:
        if cache and (mesh_dir / "mesh.msh").is_file():
            hm = _load_mesh_meta(mesh_dir)
        else:
            tmp = Path(tempfile.mkdtemp(prefix=f".{mesh_key}.", dir=root))
            hm = build_housing_mesh(cfg, tmp / "mesh.msh")
            t_mesh = hm.seconds
            _save_mesh_meta(hm, tmp)
            if cache:
                publish(tmp, mesh_dir)
                hm = hm._replace(path=mesh_dir / "mesh.msh")
            if not (hm.path.is_file()):
                hm = _load_mesh_meta(mesh_dir)
        msg = hm
    else:
        msg = None
    hm = _bcast(comm, msg)
    if comm is not None and os.environ.get("VIBROGEAR_HOUSING_FAIL_RANK") == str(comm.rank):
        raise RuntimeError("injected failure (VIBROGEAR_HOUSING_FAIL_RANK, for the MPI abort test)")
    m = cfg.modes
    from .housing import solve_mesh_modes

    res = solve_mesh_modes(hm, material=cfg.material, degree=cfg.mesh.degree, bores=bore_layout(cfg),
                           count=m.count, cutoff_hz=m.cutoff_hz, max_count=m.max_count, tol=m.tol,
                           solver=m.solver, support=cfg.support, foundation_stiffness=cfg.foundation_stiffness,
                           shapes=m.shapes, shapes_dir=work)
    res = dataclasses.replace(res, timings={"meshing": t_mesh, **res.timings}, cache_key=modes_key)
    if rank == 0:
        save_modes(res, work)
        if cache:
            final = publish(work, entry_dir(modes_key))
            res = dataclasses.replace(res, shapes_path=(final / res.shapes_path.name)
                                      if res.shapes_path is not None else None)
    return _bcast(comm, res) if comm is not None else res


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
