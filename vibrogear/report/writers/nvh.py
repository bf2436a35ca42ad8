"""Files of ``nvh``: ``spectra.npz``, ``erp.csv``, ``nvh_waterfall_<quantity>.png``,
``erp.png``, ``surface_velocity_<rpm>.xdmf`` / ``.h5`` (ParaView), and with a housing
``housing_ods.png`` / ``housing_ods_anim.png`` (the operating deflection shape at the ERP
peak) and ``nvh_housing_modes.png`` (:func:`write_ods`).

``spectra.npz``: ``rpm`` (P,), ``order`` (K,) bin frequency in orders of the first mesh,
``freq_hz`` (P, K), and per quantity q in ``dte`` [m], ``mesh_force`` [N],
``bearing_force`` [N]: ``amp_<q>`` (P, channels, K) one-sided amplitudes (bin 0: the mean),
``channels_<q>`` the channel names, ``parseval_<q>`` the largest relative Parseval error;
``mesh_hz`` (P, meshes) and ``shaft_hz`` (P, shafts) for order lines; with a housing
``erp_w_per_bin`` (P, K), the ERP of each bin [W] (its sum over bins: ``erp_w``).

The named lines (:mod:`vibrogear.analyses.nvh.line_sources`), one row per line of each point's
spectrum (RSS over the channels) of each quantity: ``line_point`` (index into ``rpm``),
``line_rpm``, ``line_quantity``, ``line_freq_hz``, ``line_amp`` (leakage corrected, the
quantity's unit), ``line_source`` (e.g. "G1 mesh 2x", "z4 relative 1x", "A front BPFO",
"mode 7 (1994 Hz)", "1x G1 mesh - 2x f2", or "unidentified"), ``line_kind`` (mesh, shaft,
free gear, bearing, mode, base, combination, unidentified), ``line_identified``,
``line_offset_hz`` (line minus the matched frequency), ``line_chance`` (the chance of a
match near the line), ``line_alternatives`` (other candidates within the tolerance); per
point ``motion_class`` (the sweep's, -1 without) and ``evidence_<name>`` of the DTE spectrum:
``f1_hz`` (the excitation), ``f2_hz`` and ``nu`` (a quasi-periodic point's second base
frequency and f2 / f1 folded into [0, 1/2]; 0 elsewhere), ``explained`` (line power on the
lattice a f1 + b f2), ``harmonic`` (on the harmonics of f1), ``broadband`` (AC power outside
the identified lines), ``flatness``, ``identified`` (line power named).  The waterfalls mark
the lines by kind.  ``erp.csv``: rpm,
erp_w, erp_db (only with a housing that has surface data).  The surface file holds the
outer-surface triangles with the cell data ``v_rms`` [m/s] (RMS normal velocity per facet).

With ``[nvh] branch_spectra``: ``spectra_branch.npz`` holds, per continuation branch point
(P), ``rpm``, ``branch`` (index of the branch), ``index`` (along it, the order of
continuation = of arclength), ``stable``, ``n_periods``, ``closure`` (|u(n T) - u0| / |u0| of
its one-period record), ``first_pass``, ``order`` (K,) on the common grid k / N (N = lcm of
the n_periods; a period-n orbit has lines only at multiples of 1 / n), ``freq_hz`` (P, K),
``amp_<q>``, ``channels_<q>``, ``parseval_<q>`` as above, with a housing ``erp_w`` and
``erp_w_per_bin``; and ``nvh_waterfall_branch_dte.png``: the DTE over the speeds of the first
pass of branch 0 (its points up to the first fold, where the branch would revisit speeds), the
speeds where the orbit is unstable marked; not drawn when the orbit is unstable at every speed
(it is never observed; its spectra stay in the npz).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ...pipeline.files import atomic_write_bytes, atomic_write_npz
from ..figure import save_figure
from ..plots.nvh import plot_erp, plot_waterfall

__all__ = ["write", "write_branch", "write_surface_velocity", "line_arrays", "write_ods", "V_REF"]

#: reference of the velocity levels [m/s]
V_REF = 1e-9

_LABELS = {"dte": "dynamic transmission error", "mesh_force": "mesh force",
           "bearing_force": "bearing force"}


def _png(fig, path) -> None:
    """The NVH figures are PNG only."""
    save_figure(fig, path, formats=("png",))


def _rss(amp: np.ndarray) -> np.ndarray:
    """Root sum of squares over the channels: (P, C, K) -> (P, K)."""
    return np.sqrt(np.sum(np.asarray(amp) ** 2, axis=1))


def write_surface_velocity(path, vertices, triangles, v_rms) -> Path:
    """The outer-surface triangles with the cell data ``v_rms`` as XDMF + HDF5 (meshio)."""
    import meshio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    mesh = meshio.Mesh(np.asarray(vertices, dtype=float),
                       [("triangle", np.asarray(triangles, dtype=np.int64))],
                       cell_data={"v_rms": [np.asarray(v_rms, dtype=float)]})
    # written in a temporary folder beside it, then moved: the HDF5 file first, the XDMF that
    # names it last, so the pair is whole or the XDMF absent
    import shutil
    import tempfile

    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    try:
        meshio.write(tmp / path.name, mesh, file_format="xdmf")
        for f in sorted(tmp.iterdir(), key=lambda f: f.suffix == ".xdmf"):
            os.replace(f, path.parent / f.name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return path


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    cfg = scene.nvh
    out = Path(out)
    files = {}
    arrays = {"rpm": r.rpm, "order": r.order, "freq_hz": r.freq_hz, "mesh_hz": r.mesh_hz,
              "shaft_hz": r.shaft_hz, "shaft_names": np.array(r.shaft_names)}
    arrays.update(line_arrays(r))
    files["npz"] = _write_spectra(out / "spectra.npz", arrays, r, r.channels)
    max_hz = cfg.max_order * 1.05 * float(np.max(r.mesh_hz))
    title = r.study.title if r.study is not None else scene.scene.name
    for q, amp in r.amplitudes.items():
        if amp.ndim != 3 or amp.shape[1] == 0:
            continue
        label = _LABELS[q] + (" (RSS over channels)" if amp.shape[1] > 1 else "")
        path = out / f"nvh_waterfall_{q}.png"
        _png(plot_waterfall(r.rpm, r.freq_hz, _rss(amp), label=label, unit=r.units[q],
                            max_hz=max_hz, mesh_hz=r.mesh_hz, shaft_hz=r.shaft_hz,
                            max_order=cfg.max_order, shaft_names=r.shaft_names,
                            mesh_names=tuple(r.channels.get("dte", ())),
                            title=f"{title}\n{_LABELS[q]}, steady points from {r.source}",
                            lines=_lines_of(r, q)), path)
        files[f"waterfall_{q}"] = str(path)
    if r.erp_w is not None:
        lines = ["rpm,erp_w,erp_db"] + [f"{p!r},{w!r},{d!r}" for p, w, d in
                                        zip(r.rpm.tolist(), r.erp_w.tolist(),
                                            r.erp_db.tolist())]
        files["erp_csv"] = str(atomic_write_bytes(out / "erp.csv",
                                                  ("\n".join(lines) + "\n").encode()))
        _png(plot_waterfall(r.rpm, r.freq_hz, r.erp_per_bin,
                            label="ERP per bin", unit="W", max_hz=max_hz, mesh_hz=r.mesh_hz,
                            shaft_hz=r.shaft_hz, max_order=cfg.max_order,
                            shaft_names=r.shaft_names,
                            mesh_names=tuple(r.channels.get("dte", ())),
                            title=f"{title}\nERP of the outer housing surface per frequency "
                                  "bin", power=True), out / "nvh_waterfall_erp.png")
        files["waterfall_erp"] = str(out / "nvh_waterfall_erp.png")
        _png(plot_erp(r.rpm, r.erp_w,
                      title=f"{title}\nequivalent radiated power of the outer housing surface "
                            f"(rho c = {cfg.rho_air:g} x {cfg.c_air:g})"), out / "erp.png")
        files["erp_png"] = str(out / "erp.png")
        s = r.surface
        for p, v in r.velocity_fields.items():
            path = write_surface_velocity(out / f"surface_velocity_{p:.0f}.xdmf", s.vertices,
                                          s.triangles, v)
            files[f"surface_velocity_{p:.0f}"] = str(path)
        hcfg = getattr(scene, "housing", None)
        files.update(write_ods(r, out, draw=hcfg.modes.plot if hcfg is not None else (1, 2, 3, 4, 5, 6)))
    if r.branch is not None:
        files.update(write_branch(scene, r, out, max_hz, title))
    return files


def write_ods(r, out: Path, draw=(1, 2, 3, 4, 5, 6)) -> dict:
    """``housing_ods.png`` + ``housing_ods_anim.png``: the operating deflection shape at the
    ERP peak on the outer surface, coloured by the RMS normal velocity of all harmonics in dB
    re 1e-9 m/s, deformed by the harmonic with the most ERP; and ``nvh_housing_modes.png``:
    the housing's master modes ``draw`` (1-based, the first six of them) in this synthesis,
    shaded (when they carry the boundary surface)."""
    from .housing_animation import animate_surface
    from ..figure import write_figure
    from ..plots.housing_surface import DPI, ods_drawing, plot_mode_shapes, plot_surface_field

    files, s, ods = {}, r.surface, r.ods
    hm = getattr(getattr(r.study, "gearbox", None), "housing", None)
    if hm is not None and getattr(hm, "has_shapes", False):
        modes = [i - 1 for i in dict.fromkeys(draw) if i <= hm.n_modes][:6]
        if modes:
            write_figure(plot_mode_shapes(hm, modes), out / "nvh_housing_modes.png", dpi=DPI)
            files["housing_modes_png"] = str(out / "nvh_housing_modes.png")
    if not ods or ods["rpm"] not in r.velocity_fields:
        return files
    k = int(np.flatnonzero(r.rpm == ods["rpm"])[0])
    f_hz = float(r.freq_hz[k, ods["bin"]])
    disp, view = ods_drawing(s.vertices, s.triangles, s.values, ods["modal_velocity"], 2 * np.pi * f_hz)
    with np.errstate(divide="ignore"):
        level = 20.0 * np.log10(np.maximum(r.velocity_fields[ods["rpm"]], 1e-300) / V_REF)
    top = float(level.max())
    label = "RMS normal velocity, dB re 1e-9 m/s"
    what = (f"ERP peak {r.erp_db[k]:.1f} dB re 1e-12 W at {ods['rpm']:.0f} rpm; shape: order "
            f"{r.order[ods['bin']]:.3g} ({f_hz:.0f} Hz, {100 * ods['erp_share']:.0f} % of the ERP)")
    write_figure(plot_surface_field(s.vertices, s.triangles, level, displacement=np.real(disp),
                                    label=label, view=view, vmin=top - 40.0, vmax=top,
                                    title=f"operating deflection shape of the housing\n{what}"),
                 out / "housing_ods.png", dpi=DPI)
    files["ods_png"] = str(out / "housing_ods.png")
    from matplotlib import colors

    animate_surface(out / "housing_ods_anim.png", s.vertices, s.triangles, level, disp,
                    title=f"ODS at {ods['rpm']:.0f} rpm, {f_hz:.0f} Hz", view=view, cmap="inferno",
                    norm=colors.Normalize(top - 40.0, top))
    files["ods_animation"] = str(out / "housing_ods_anim.png")
    return files


def line_arrays(r) -> dict:
    """The named lines of every point and quantity, one row per line, and the per-point
    evidence (module docstring)."""
    rows = [(i, q, ln, j) for q, per in getattr(r, "lines", {}).items()
            for i, ln in enumerate(per) for j in range(ln.freq.size)]
    out = {"line_point": np.array([i for i, _, _, _ in rows], dtype=np.int64),
           "line_rpm": np.array([r.rpm[i] for i, _, _, _ in rows], dtype=float),
           "line_quantity": np.array([q for _, q, _, _ in rows], dtype=str),
           "line_freq_hz": np.array([ln.freq[j] for _, _, ln, j in rows], dtype=float),
           "line_amp": np.array([ln.amp[j] for _, _, ln, j in rows], dtype=float),
           "line_source": np.array([ln.source[j] for _, _, ln, j in rows], dtype=str),
           "line_kind": np.array([ln.kind[j] for _, _, ln, j in rows], dtype=str),
           "line_offset_hz": np.array([ln.offset[j] for _, _, ln, j in rows], dtype=float),
           "line_chance": np.array([ln.chance[j] for _, _, ln, j in rows], dtype=float),
           "line_alternatives": np.array([ln.alternatives[j] for _, _, ln, j in rows],
                                         dtype=str)}
    out["line_identified"] = out["line_kind"] != "unidentified"
    for k in ("line_offset_hz", "line_chance"):       # 0 where nothing was matched
        out[k] = np.where(np.isfinite(out[k]), out[k], 0.0)
    for k, v in getattr(r, "evidence", {}).items():
        out[f"evidence_{k}"] = np.where(np.isfinite(v), v, 0.0)
    if getattr(r, "motion_class", None) is not None:
        out["motion_class"] = np.asarray(r.motion_class, dtype=np.int64)
    return out


def _lines_of(r, q):
    """(frequency, rpm, kind, amplitude, alternatives) of the named lines of quantity
    ``q`` (None without)."""
    per = getattr(r, "lines", {}).get(q)
    if not per:
        return None
    return (np.concatenate([ln.freq for ln in per]),
            np.concatenate([np.full(ln.freq.size, p) for p, ln in zip(r.rpm, per)]),
            np.concatenate([np.array(ln.kind, dtype=str) for ln in per]),
            np.concatenate([np.asarray(ln.amp, dtype=float) for ln in per]),
            np.concatenate([np.array(ln.alternatives, dtype=str) for ln in per]))


def _write_spectra(path: Path, arrays: dict, res, channels: dict) -> str:
    """``arrays`` plus the amplitudes, channel names and Parseval errors of ``res`` (steady
    points or branch orbits) and its ERP where it has one, as a compressed npz."""
    arrays = dict(arrays)
    for q, amp in res.amplitudes.items():
        arrays[f"amp_{q}"] = amp
        arrays[f"channels_{q}"] = np.array(channels[q], dtype=str)
        arrays[f"parseval_{q}"] = np.float64(res.parseval[q])
    if res.erp_per_bin is not None:
        arrays["erp_w_per_bin"], arrays["erp_w"] = res.erp_per_bin, res.erp_w
    return str(atomic_write_npz(path, arrays))


def write_branch(scene, r, out: Path, max_hz: float, title: str) -> dict:
    """``spectra_branch.npz`` and the DTE waterfall of branch 0's first pass (module
    docstring)."""
    b, cfg, files = r.branch, scene.nvh, {}
    arrays = {k: getattr(b, k) for k in ("rpm", "branch", "index", "stable", "n_periods",
                                          "closure", "first_pass", "order", "freq_hz")}
    files["branch_npz"] = _write_spectra(out / "spectra_branch.npz", arrays, b, r.channels)
    amp = b.amplitudes["dte"]
    sel = np.flatnonzero(b.first_pass)
    # an orbit unstable at every speed is never observed: its waterfall is not drawn (the
    # spectra stay in spectra_branch.npz); where some speeds are stable the others are marked
    if amp.shape[1] and sel.size and np.any(np.asarray(b.stable)[sel]):
        sel = sel[np.argsort(b.rpm[sel], kind="stable")]
        # order lines: frequencies proportional to the speed (the steady points' ratios)
        mesh_hz = np.outer(b.rpm[sel], np.asarray(r.mesh_hz)[0] / r.rpm[0])
        shaft_hz = np.outer(b.rpm[sel], np.asarray(r.shaft_hz)[0] / r.rpm[0])
        names = r.shaft_names
        path = out / "nvh_waterfall_branch_dte.png"
        label = _LABELS["dte"] + (" (RSS over channels)" if amp.shape[1] > 1 else "")
        _png(plot_waterfall(b.rpm[sel], b.freq_hz[sel], _rss(amp[sel]), label=label,
                            unit=r.units["dte"], max_hz=max_hz, mesh_hz=mesh_hz,
                            shaft_hz=shaft_hz, max_order=cfg.max_order, shaft_names=names,
                            mesh_names=tuple(r.channels.get("dte", ())),
                            unstable=~np.asarray(b.stable, bool)[sel],
                            title=f"{title}\n{_LABELS['dte']} of the continuation branch "
                                  "(first pass, one orbit period per point)"), path)
        files["waterfall_branch_dte"] = str(path)
    return files
