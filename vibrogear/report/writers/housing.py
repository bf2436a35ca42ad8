"""Files and figures of the housing analyses.

* ``write_modes`` (:mod:`vibrogear.analyses.housing.modes`, ``modes``): ``modes.csv`` (with the
  dominant motion of each mode), ``housing_modes.npz`` (the coupling data),
  ``mode_shapes.xdmf/.h5`` (when shapes were written), ``housing_modes.png`` (the modes of
  ``[housing.modes] plot``, 6 per figure, shaded on the boundary surface; more figures
  ``housing_modes_2.png``, ...; the old point previews where the modes carry no surface) and
  ``housing_mode_<n>_anim.png`` (the first of them swinging, an animated PNG);
* ``write_sweep`` (:mod:`vibrogear.analyses.housing.sweep`): ``housing_sweep.csv`` and
  ``housing_sweep.png``;
* ``write_convergence`` (:mod:`vibrogear.analyses.housing.convergence`):
  ``housing_convergence.csv`` and ``housing_error_vs_time.png``.

``write_modes`` returns ``{role: file name}`` as listed in ``summary.json``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ...pipeline.files import atomic_copy, atomic_write_csv, atomic_write_npz
from ..figure import write_figure

__all__ = ["write_modes", "write_sweep", "write_convergence", "write_modes_outputs"]


def _dominant(res) -> list[str]:
    v = res.preview_values
    out = []
    for i in range(res.n_modes):
        if v.ndim == 3 and i < v.shape[-1] and len(v):
            out.append("xyz"[int(np.argmax(np.sqrt((v[:, :, i] ** 2).mean(axis=0))))])
        else:
            out.append("")
    return out


def write_modes_outputs(res, out: Path, *, plot: bool = True,
                        draw: tuple[int, ...] = (1, 2, 3, 4, 5, 6)) -> dict[str, str]:
    """modes.csv, housing_modes.npz (coupling data), shapes XDMF, PNG of the first modes."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = {}
    dom = _dominant(res)
    motion = list(res.mode_motion()[0]) if hasattr(res, "mode_motion") else [""] * res.n_modes
    atomic_write_csv(out / "modes.csv",
                     ["index", "frequency_hz", "damping_ratio", "residual", "dominant_direction",
                      "dominant_motion"],
                     [[i + 1, f"{f:.8g}", f"{res.damping_ratios[i]:.6g}",
                       f"{res.residuals[i]:.3e}", dom[i], motion[i]] for i, f in enumerate(res.freqs_hz)])
    files["modes"] = "modes.csv"
    atomic_write_npz(out / "housing_modes.npz", dict(
        freqs_hz=res.freqs_hz, bore_values=res.bore_values, bore_points=res.bore_points,
        bore_centers=res.bore_centers, bore_axes=res.bore_axes,
        bore_center_values=res.bore_center_values, bore_n_points=np.array(res.bore_n_points),
        bore_names=np.array(res.bore_names), beta=res.beta, n_dofs=res.n_dofs),
        compressed=False)
    files["coupling"] = "housing_modes.npz"
    if res.shapes_path is not None and Path(res.shapes_path).is_file():
        src = Path(res.shapes_path)
        for ext in (".xdmf", ".h5"):
            s = src.with_suffix(ext)
            if s.is_file():
                atomic_copy(s, out / f"mode_shapes{ext}")
        files["shapes"] = "mode_shapes.xdmf"
    if plot and res.n_modes and getattr(res, "has_shapes", False):
        files.update(_shaded_modes(res, out, draw))
    elif plot and res.n_modes and len(res.preview_points):
        from ..plots.housing import DPI, plot_mode_previews
        write_figure(plot_mode_previews(res), out / "housing_modes.png", dpi=DPI)
        files["plot"] = "housing_modes.png"
    return files


def _shaded_modes(res, out: Path, draw) -> dict[str, str]:
    """The modes ``draw`` (1-based; those beyond the solved count left out) 6 per figure, and
    the first one animated."""
    from .housing_animation import animate_surface
    from ..plots.housing_surface import DPI, hatched_faces, mode_panel_data, plot_mode_shapes

    modes = [i - 1 for i in dict.fromkeys(draw) if i <= res.n_modes]
    files = {}
    for g in range(0, len(modes), 6):
        name = "housing_modes.png" if g == 0 else f"housing_modes_{g // 6 + 1}.png"
        write_figure(plot_mode_shapes(res, modes[g:g + 6]), out / name, dpi=DPI)
        files["plot" if g == 0 else f"plot_{g // 6 + 1}"] = name
    if modes:
        from matplotlib import colors

        disp, val, view, title = mode_panel_data(res, modes[0])
        name = f"housing_mode_{modes[0] + 1}_anim.png"
        animate_surface(out / name, res.shape_vertices, res.shape_triangles, val, disp,
                        title=title, view=view, norm=colors.Normalize(0.0, 1.0),
                        tags=res.shape_facet_tag,
                        hatch=hatched_faces(res.shape_triangles, res.shape_facet_tag))
        files["animation"] = name
    return files


def write_modes(scene, outcome, out, previous=None) -> dict[str, str]:
    return write_modes_outputs(outcome.result, Path(out), draw=scene.housing.modes.plot)


def write_sweep(scene, outcome, out, previous=None) -> dict[str, str]:
    """``housing_sweep.csv`` and ``.png``."""
    from ..plots.housing import DPI, plot_sweep

    r = outcome.result
    out = Path(out)
    n = r.freqs.shape[1]
    atomic_write_csv(out / "housing_sweep.csv",
                     [r.parameter, "n_dofs"] + [f"f{j + 1}_hz" for j in range(n)],
                     [[f"{row['value']:.6g}", row["n_dofs"]] + [f"{x:.6g}" for x in fr]
                      for row, fr in zip(r.rows, r.freqs)])
    write_figure(plot_sweep(r.parameter, [row["value"] for row in r.rows], r.freqs),
                 out / "housing_sweep.png", dpi=DPI)
    return {"csv": "housing_sweep.csv", "plot": "housing_sweep.png"}


def write_convergence(scene, outcome, out, previous=None) -> dict[str, str]:
    """``housing_convergence.csv`` and ``housing_error_vs_time.png``."""
    from ..plots.housing import DPI, plot_error_vs_time

    r = outcome.result
    out = Path(out)
    atomic_write_csv(out / "housing_convergence.csv",
                     ["degree", "size_m", "n_dofs", "fe_seconds", "max_rel_error"] +
                     [f"f{j + 1}_hz" for j in range(r.n_freqs)],
                     [[row["degree"], f"{row['size']:.5g}", row["n_dofs"],
                       f"{row['fe_seconds']:.3f}", f"{row['max_rel_error']:.4e}"] +
                      [f"{f:.6g}" for f in row["freqs"]] for row in r.rows])
    write_figure(plot_error_vs_time(list(r.rows), target=r.target_error),
                 out / "housing_error_vs_time.png", dpi=DPI)
    return {"csv": "housing_convergence.csv", "plot": "housing_error_vs_time.png"}
