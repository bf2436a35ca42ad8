"""The housing's master modes as consumed by the modal synthesis, and their on-disk form.

No dolfinx here: a cached result loads with numpy alone.

Array conventions (m = number of master modes, B = number of bores = 2 x shafts,
P = the largest rolling-element count; bores with fewer points are padded with NaN):

- ``freqs_hz``            (m,)         natural frequencies, ascending
- ``bore_points``         (B, P, 3)    coupling-point coordinates, m (global housing frame)
- ``bore_values``         (B, P, 3, m) mass-normalised mode values (x, y, z) at those points
- ``bore_centers``        (B, 3)       bore-axis point at the middle of the bore length
- ``bore_center_values``  (B, 3, m)    bore-centre motion = mean of the ring-point values
- ``bore_axes``           (B, 3)       unit axis pointing out of the housing
- ``surface_*``                        the outer surface and the modes' normal displacement
                                       there (:mod:`.housing_surface_data`; empty arrays when
                                       the modes come from another program)
"""
from __future__ import annotations

import json
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import numpy as np

from ...status import Outcome, Status
from .surface_data import SURFACE_FIELDS, empty_surface_fields
from .surface_mesh import SHAPE_FIELDS, empty_shape_fields

__all__ = ["HousingModes", "save_modes", "load_modes", "WALL_STAGES"]

#: the top-level stages of ``HousingModes.timings`` (the others are parts of these):
#: meshing to post-processing of an FE solve, ``read`` of another program's modes
WALL_STAGES = ("meshing", "mesh_read", "form_compilation", "assembly", "eigensolve",
               "postprocess", "xdmf", "read")

_ARRAYS = ("freqs_hz", "bore_values", "bore_points", "bore_centers", "bore_axes",
           "bore_center_values", "residuals", "preview_points", "preview_values") + SURFACE_FIELDS + SHAPE_FIELDS


def _empty(fields, name: str):
    """A dataclass field defaulting to entry ``name`` of ``fields()`` (the empty arrays of a
    housing without surface data)."""
    return field(default_factory=lambda: fields()[name])


@dataclass(frozen=True, eq=False, kw_only=True)
class HousingModes:
    freqs_hz: np.ndarray
    bore_values: np.ndarray
    bore_points: np.ndarray
    bore_n_points: tuple[int, ...]
    bore_centers: np.ndarray
    bore_axes: np.ndarray
    bore_center_values: np.ndarray
    bore_names: tuple[str, ...]
    beta: float
    n_dofs: int
    degree: int
    residuals: np.ndarray                 # ||K x - lambda M x|| / ||K x|| per mode
    orthogonality_error: float            # max |V^T M V - I|
    mass_kg: float                        # integral of rho over the mesh
    n_fallback_points: int                # coupling points found by the closest-cell fallback
    status: str                           # "ok" | "truncated" (cut-off not reached)
    message: str
    converged_reason: str
    n_converged: int
    timings: Mapping[str, float]
    peak_memory_mb: float                 # sum over MPI ranks of each rank's peak RSS
    n_processes: int
    cached: bool = False
    cache_key: str = ""
    shapes_path: Path | None = None       # XDMF of the first mode shapes (P1-interpolated)
    preview_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    preview_values: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 0)))
    source_info: Mapping[str, object] = field(default_factory=dict)   # what the housing was made from
    surface_vertices: np.ndarray = _empty(empty_surface_fields, "surface_vertices")
    surface_triangles: np.ndarray = _empty(empty_surface_fields, "surface_triangles")
    surface_centers: np.ndarray = _empty(empty_surface_fields, "surface_centers")
    surface_areas: np.ndarray = _empty(empty_surface_fields, "surface_areas")
    surface_weights: np.ndarray = _empty(empty_surface_fields, "surface_weights")
    surface_values: np.ndarray = _empty(empty_surface_fields, "surface_values")
    # the whole boundary triangulated, the modes at its vertices, energy per wall / bore
    # (:mod:`.surface_mesh`; empty when the modes come from another program)
    shape_vertices: np.ndarray = _empty(empty_shape_fields, "shape_vertices")
    shape_triangles: np.ndarray = _empty(empty_shape_fields, "shape_triangles")
    shape_facet_tag: np.ndarray = _empty(empty_shape_fields, "shape_facet_tag")
    shape_values: np.ndarray = _empty(empty_shape_fields, "shape_values")
    region_normals: np.ndarray = _empty(empty_shape_fields, "region_normals")
    region_energy: np.ndarray = _empty(empty_shape_fields, "region_energy")
    shape_vertex_region: np.ndarray = _empty(empty_shape_fields, "shape_vertex_region")
    region_names: tuple[str, ...] = ()

    @property
    def n_modes(self) -> int:
        return int(self.freqs_hz.size)

    @property
    def outcome(self) -> Outcome:
        """The modal solve as an :class:`~vibrogear.status.Outcome`: status ok, or
        ``max_points`` with the housing's message where it is ``truncated`` (max_count modes
        all below the cut-off: the set is incomplete); counters ``dofs``, ``modes``,
        ``converged``; wall time of this run's work (the FE stages, or the cache load, or the
        read of another program's modes); error estimate: the largest eigen residual and the
        mass-orthonormality error."""
        t = self.timings
        wall = t["cache_load"] if "cache_load" in t else sum(t.get(k, 0.0) for k in WALL_STAGES)
        st = Status.OK if self.status == "ok" else Status.MAX_POINTS
        return Outcome(st, self.message or st.message,
                       {"dofs": self.n_dofs, "modes": self.n_modes, "converged": self.n_converged},
                       wall, {"max_eigen_residual": float(np.max(self.residuals, initial=0.0))
                              if self.n_modes else None,
                              "mass_orthonormality_error": self.orthogonality_error})

    @property
    def omegas(self) -> np.ndarray:
        return 2 * np.pi * self.freqs_hz

    @property
    def damping_ratios(self) -> np.ndarray:
        """Modal damping ratios of B_S = beta K_S: zeta_i = beta omega_i / 2."""
        return 0.5 * self.beta * self.omegas

    @property
    def has_surface(self) -> bool:
        """Whether the outer surface and the modes' normal displacement there are known."""
        return bool(self.surface_areas.size) and self.surface_values.shape[-1] == self.n_modes

    @property
    def has_shapes(self) -> bool:
        """Whether the boundary surface and the modes' displacement at its vertices are known."""
        return bool(len(self.shape_triangles)) and self.shape_values.shape[-1] == self.n_modes

    def mode_motion(self) -> tuple[tuple[str, ...], np.ndarray]:
        """(the dominant motion of each mode, e.g. "front wall bending (71 % of KE)", the region
        each picture should face): :func:`.surface_mesh.mode_labels` of the stored shares
        ("" / 0 without the boundary surface)."""
        if not self.has_shapes or not len(self.region_energy):
            return ("",) * self.n_modes, np.zeros(self.n_modes, dtype=np.int64)
        from .surface_mesh import mode_labels
        return mode_labels(self.region_energy, self.region_names, self.region_normals,
                           self.shape_vertices, self.shape_values, self.shape_vertex_region)

    def bore(self, i: int) -> np.ndarray:
        """Mode values at the coupling points of bore ``i``: (n_i, 3, m), no padding."""
        return self.bore_values[i, :self.bore_n_points[i]]


def save_modes(res: HousingModes, folder: Path) -> None:
    """Write ``modes.npz`` + ``meta.json`` into ``folder`` (created)."""
    folder.mkdir(parents=True, exist_ok=True)
    np.savez(folder / "modes.npz", **{k: np.asarray(getattr(res, k)) for k in _ARRAYS})
    meta = {k: getattr(res, k) for k in ("bore_n_points", "bore_names", "beta", "n_dofs", "degree",
                                          "orthogonality_error", "mass_kg", "n_fallback_points",
                                          "status", "message", "converged_reason", "n_converged",
                                          "peak_memory_mb", "n_processes", "source_info",
                                          "region_names")}
    meta["timings"] = dict(res.timings)
    meta["shapes"] = res.shapes_path.name if res.shapes_path is not None else None
    (folder / "meta.json").write_text(json.dumps(meta, indent=1))


def load_modes(folder: Path, *, key: str = "") -> HousingModes:
    meta = json.loads((folder / "meta.json").read_text())
    with np.load(folder / "modes.npz") as z:
        arrays = {k: z[k] for k in _ARRAYS}
    shapes = meta.pop("shapes")
    meta["source_info"] = meta.get("source_info") or {}
    meta["bore_n_points"] = tuple(meta["bore_n_points"])
    meta["bore_names"] = tuple(meta["bore_names"])
    meta["region_names"] = tuple(meta["region_names"])
    return HousingModes(**arrays, **meta, cached=True, cache_key=key,
                        shapes_path=(folder / shapes) if shapes else None)


def publish(tmp: Path, final: Path) -> Path:
    """Atomically move a finished cache entry into place (a concurrent winner is kept)."""
    try:
        os.rename(tmp, final)
    except OSError:
        shutil.rmtree(tmp, ignore_errors=True)
    return final
