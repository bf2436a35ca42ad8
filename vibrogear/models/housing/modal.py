"""``[housing] source = "modal"``: another FE program's modes at the coupling points (no FE here).

Three layouts (see docs/housing.md, "Housing from modes"):

* **NPZ** -- the ``housing_modes.npz`` that ``vibrogear modes`` writes: ``freqs_hz`` (m,),
  ``bore_values`` (B, P, 3, m), ``bore_points`` (B, P, 3), ``bore_n_points`` (B,), ``bore_names``
  (B,); optional ``bore_centers``, ``bore_axes`` (B, 3), ``bore_center_values`` (B, 3, m),
  ``modal_mass`` (m,), ``n_dofs``.
* **CSV** -- header ``bore,point,x,y,z,direction,mode_1,...,mode_m``; a row with bore
  ``frequency_hz`` gives the frequencies, an optional row ``modal_mass`` the modal masses; every
  other row is one bore point and direction (``x``, ``y`` or ``z``); lines starting with ``#``
  are comments.  Bore centres are the ring means; axes come from the config bore of that name.
* **UFF** (``.unv``/``.uff``, via pyuff) -- node coordinates from dataset 15 or 2411, normal
  modes from datasets 55 (analysis type 2: frequency, modal mass, 3 translations per node).  The
  bore points are the nodes on each config bore's cylinder, grouped along the axis as for an
  imported mesh and ordered by angle; a ring must hold ``rolling_elements`` nodes.  Dataset 58
  holds response functions, not mode shapes, and is refused with that message.

Checks: frequencies finite, >= 0 and ascending; mode values finite; modal masses > 0 (modes are
divided by sqrt(modal mass), so ``x^T M x = 1`` holds after reading); modes whose largest value is
exactly 1 in every mode look normalised to a unit maximum, not to unit modal mass, and are refused
unless the modal masses are given.  Lengths (coordinates and mode values) are multiplied by
``LENGTH_UNITS[length_unit]``; frequencies are in Hz.  What was read is logged and kept in
``HousingModes.source_info``.
"""
from __future__ import annotations

import csv
import logging
import time
from pathlib import Path

import numpy as np

from ...config.base import ConfigError
from ...config.model.housing import LENGTH_UNITS, HousingConfig
from ...geometry.housing import ring_frame
from ...geometry.housing_import import bore_segments, segment_bores
from .result import HousingModes

__all__ = ["read_modal_housing", "read_modal_file", "write_modes_csv"]

log = logging.getLogger(__name__)
_F = "housing.file"


def read_modal_housing(cfg: HousingConfig) -> HousingModes:
    """The :class:`HousingModes` of a ``source = "modal"`` housing config."""
    t0 = time.perf_counter()
    data = read_modal_file(cfg)
    info = data.pop("info")
    m = data["freqs_hz"].size
    if cfg.modes.cutoff_hz is not None:
        keep = int(np.sum(data["freqs_hz"] < cfg.modes.cutoff_hz))
    else:
        keep = min(cfg.modes.count, m)
        if m < cfg.modes.count:
            log.warning("housing %s: %d modes in the file, fewer than housing.modes.count = %d; using %d",
                        cfg.file, m, cfg.modes.count, m)
    for k in ("freqs_hz", "bore_values", "bore_center_values"):
        data[k] = data[k][..., :keep]
    info.update(modes_used=keep, f_min_hz=float(data["freqs_hz"][0]) if keep else None,
                f_max_hz=float(data["freqs_hz"][-1]) if keep else None)
    log.info("housing modal %s: %s", cfg.file, ", ".join(f"{k} = {v}" for k, v in info.items() if k != "file"))
    n = data.pop("n_dofs")
    return HousingModes(**data, beta=cfg.material.beta, n_dofs=int(n), degree=0,
                        residuals=np.full(keep, np.nan), orthogonality_error=float("nan"), mass_kg=float("nan"),
                        n_fallback_points=0, status="ok", message="", converged_reason="read from file",
                        n_converged=keep, timings={"read": time.perf_counter() - t0},
                        peak_memory_mb=0.0, n_processes=1, source_info={"source": "modal", **info})


def read_modal_file(cfg: HousingConfig) -> dict:
    """The arrays of HousingModes (all modes, normalised, in metres) + ``info`` and ``n_dofs``."""
    file = str(cfg.file)
    suffix = Path(file).suffix.lower()
    unit = LENGTH_UNITS[cfg.length_unit]
    if suffix == ".npz":
        raw = _read_npz(file)
    elif suffix == ".csv":
        raw = _read_csv(file)
    else:
        raw = _read_uff(file, cfg)
    freqs, vals, pts, npts = raw["freqs_hz"], raw["bore_values"], raw["bore_points"], raw["bore_n_points"]
    _check_freqs(freqs, file)
    B = len(npts)
    finite_vals = np.concatenate([vals[b, :n].ravel() for b, n in enumerate(npts)]) if B else np.zeros(0)
    if not np.all(np.isfinite(finite_vals)):
        raise ConfigError(_F, f"{file}: mode values at the coupling points are not all finite")
    mm = raw.get("modal_mass")
    info = {"file": file, "format": suffix[1:], "modes_in_file": int(freqs.size), "bores": B,
            "coupling_points": int(sum(npts)), "length_unit": cfg.length_unit}
    if mm is not None:
        mm = np.asarray(mm, dtype=float)
        if mm.shape != freqs.shape or not np.all(np.isfinite(mm)) or np.any(mm <= 0):
            raise ConfigError(_F, f"{file}: modal masses must be {freqs.size} positive finite numbers")
        info["modal_mass_range"] = [float(mm.min()), float(mm.max())]
    elif B and freqs.size and _unit_max(vals, npts):
        raise ConfigError(_F, f"{file}: every mode's largest coupling value is exactly 1: the modes look "
                          "normalised to a unit maximum, not to unit modal mass; give the modal masses "
                          "(modal_mass) so they can be mass-normalised")
    scale = unit if mm is None or np.all(mm == 1.0) else unit / np.sqrt(mm)
    info["mass_normalisation"] = ("as read (unit modal mass)" if mm is None or np.all(mm == 1.0)
                                  else "divided by sqrt(modal mass)")
    vals = vals * scale
    pts = pts * unit
    centers = raw.get("bore_centers")
    centers = (np.array([np.nanmean(pts[b, :n], axis=0) for b, n in enumerate(npts)]).reshape(-1, 3)
               if centers is None else np.asarray(centers, float) * unit)
    cvals = raw.get("bore_center_values")
    cvals = (np.array([vals[b, :n].mean(axis=0) for b, n in enumerate(npts)]).reshape(B, 3, freqs.size)
             if cvals is None else np.asarray(cvals, float) * scale)
    axes = raw.get("bore_axes")
    names = tuple(str(n) for n in raw["bore_names"])
    axes = _config_axes(cfg, names, centers, file) if axes is None else np.asarray(axes, float)
    if cfg.bores and suffix in (".npz", ".csv"):
        _check_against_config(cfg, names, centers, npts, file)
    return dict(freqs_hz=np.asarray(freqs, float), bore_values=vals, bore_points=pts,
                bore_n_points=tuple(int(n) for n in npts), bore_centers=centers, bore_axes=axes,
                bore_center_values=cvals, bore_names=names,
                n_dofs=int(raw.get("n_dofs", 3 * sum(npts))), info=info)


def _check_freqs(f: np.ndarray, file: str) -> None:
    if f.ndim != 1 or f.size == 0:
        raise ConfigError(_F, f"{file}: needs at least one natural frequency")
    if not np.all(np.isfinite(f)):
        raise ConfigError(_F, f"{file}: natural frequencies must be finite")
    if np.any(f < 0):
        raise ConfigError(_F, f"{file}: negative natural frequency {float(f.min()):g} Hz "
                          f"(mode {int(np.argmin(f)) + 1}); frequencies must be >= 0")
    bad = np.flatnonzero(np.diff(f) < 0)
    if bad.size:
        k = int(bad[0])
        raise ConfigError(_F, f"{file}: natural frequencies are not ascending: mode {k + 2} "
                          f"({f[k + 1]:g} Hz) below mode {k + 1} ({f[k]:g} Hz)")


def _unit_max(vals: np.ndarray, npts) -> bool:
    flat = np.concatenate([np.abs(vals[b, :n]).reshape(-1, vals.shape[-1]) for b, n in enumerate(npts)])
    return bool(np.all(np.abs(flat.max(axis=0) - 1.0) <= 1e-12))


def _config_axes(cfg, names, centers, file) -> np.ndarray:
    """Outward unit axes of the file's bores from the config bore lines (front: -axis)."""
    out = np.zeros((len(names), 3))
    for j, n in enumerate(names):
        base, _, side = n.partition("/")
        b = next((b for i, b in enumerate(cfg.bores) if (b.name or f"shaft{i}") == base), None)
        if b is None:
            raise ConfigError("housing.bores", f"{file}: bore {n!r} has no axis in the file and no "
                              f"[[housing.bores]] entry named {base!r} to take it from")
        out[j] = (-1.0 if side == "front" else 1.0) * np.asarray(b.unit_axis)
    return out


def _check_against_config(cfg, names, centers, npts, file) -> None:
    for i, b in enumerate(cfg.bores):
        label = b.name or f"shaft{i}"
        mine = [j for j, n in enumerate(names) if n == label or n.startswith(label + "/")]
        if not mine:
            raise ConfigError(f"housing.bores[{i}].name", f"{file}: has no bore named {label!r} or "
                              f"'{label}/...'; its bores are {', '.join(names)}")
        c, u = np.asarray(b.center, float), np.asarray(b.unit_axis, float)
        for j in mine:
            d = centers[j] - c
            off = float(np.linalg.norm(d - (d @ u) * u))
            if off > 1e-6 + 1e-4 * b.bore_radius:
                raise ConfigError(f"housing.bores[{i}].center", f"{file}: bore {names[j]!r} is centred "
                                  f"{off:.3g} m off the line through {list(b.center)} along {list(b.axis)}")
            if npts[j] != b.rolling_elements:
                raise ConfigError(f"housing.bores[{i}].rolling_elements", f"{file}: bore {names[j]!r} has "
                                  f"{npts[j]} coupling points, the config says {b.rolling_elements}")


def _read_npz(file: str) -> dict:
    try:
        z = np.load(file, allow_pickle=False)
    except Exception as exc:
        raise ConfigError(_F, f"{file}: not a readable .npz file ({exc})") from None
    with z:
        missing = [k for k in ("freqs_hz", "bore_values", "bore_points", "bore_n_points", "bore_names")
                   if k not in z.files]
        if missing:
            raise ConfigError(_F, f"{file}: missing array(s) {', '.join(missing)} (layout: docs/housing.md)")
        out = {k: z[k] for k in z.files}
    B = len(out["bore_n_points"])
    m = out["freqs_hz"].size
    shapes = {"bore_values": (B, None, 3, m), "bore_points": (B, None, 3)}
    for k, shp in shapes.items():
        a = out[k]
        if a.ndim != len(shp) or any(s is not None and s != t for s, t in zip(shp, a.shape)):
            raise ConfigError(_F, f"{file}: {k} has shape {a.shape}, expected "
                              f"{tuple('P' if s is None else s for s in shp)}")
    if "n_dofs" in out:
        out["n_dofs"] = int(out["n_dofs"])
    out.pop("beta", None)
    return out


def _read_csv(file: str) -> dict:
    try:
        with open(file, newline="") as fh:
            rows = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ConfigError(_F, f"{file}: not a readable CSV file ({exc})") from None
    head = [h.strip() for h in rows[0]] if rows else []
    if head[:6] != ["bore", "point", "x", "y", "z", "direction"] or len(head) < 7:
        raise ConfigError(_F, f"{file}: the header must be bore,point,x,y,z,direction,mode_1,... ; got "
                          f"{','.join(head[:8])}")
    m = len(head) - 6
    freqs, mm, pts, vals, order = None, None, {}, {}, []
    for ln, r in enumerate(rows[1:], start=2):
        if len(r) != len(head):
            raise ConfigError(_F, f"{file}: row {ln} has {len(r)} fields, the header {len(head)}")
        try:
            nums = np.array([float(v) for v in r[6:]])
            if r[0] == "frequency_hz":
                freqs = nums
                continue
            if r[0] == "modal_mass":
                mm = nums
                continue
            key, xyz = (r[0], int(r[1])), [float(v) for v in r[2:5]]
        except ValueError as exc:
            raise ConfigError(_F, f"{file}: row {ln}: {exc}") from None
        d = r[5].strip().lower()
        if d not in ("x", "y", "z"):
            raise ConfigError(_F, f"{file}: row {ln}: direction must be x, y or z, got {r[5]!r}")
        if r[0] not in order:
            order.append(r[0])
        pts[key] = xyz
        vals.setdefault(key, np.full((3, m), np.nan))["xyz".index(d)] = nums
    if freqs is None:
        raise ConfigError(_F, f"{file}: no 'frequency_hz' row")
    npts = [1 + max(p for (b, p) in pts if b == name) for name in order]
    B, P = len(order), max(npts, default=0)
    bp, bv = np.full((B, P, 3), np.nan), np.full((B, P, 3, m), np.nan)
    for (name, p), xyz in pts.items():
        j = order.index(name)
        bp[j, p], bv[j, p] = xyz, vals[(name, p)]
    for j, n in enumerate(npts):
        if np.isnan(bv[j, :n]).any():
            raise ConfigError(_F, f"{file}: bore {order[j]!r} lacks a point index or direction "
                              f"(needs points 0..{n - 1}, each with x, y and z rows)")
    out = dict(freqs_hz=freqs, bore_values=bv, bore_points=bp, bore_n_points=np.array(npts), bore_names=order)
    if mm is not None:
        out["modal_mass"] = mm
    return out


def _read_uff(file: str, cfg: HousingConfig) -> dict:
    import pyuff

    try:
        sets = pyuff.UFF(file).read_sets()
    except Exception as exc:
        raise ConfigError(_F, f"{file}: pyuff cannot read it ({type(exc).__name__}: {exc})") from None
    sets = sets if isinstance(sets, list) else [sets]
    kinds = [s.get("type") for s in sets]
    modes = [s for s in sets if s.get("type") == 55 and s.get("analysis_type") == 2]
    if not modes:
        hint = (" (dataset 58 holds response functions, not mode shapes: export the normal modes as "
                "dataset 55)" if 58 in kinds else "")
        raise ConfigError(_F, f"{file}: no normal-mode dataset 55 (analysis type 2); datasets found: "
                          f"{sorted(set(kinds))}{hint}")
    coords = {}
    for s in sets:
        if s.get("type") in (15, 2411):
            for n, x, y, z in zip(s["node_nums"], s["x"], s["y"], s["z"]):
                coords[int(n)] = (x, y, z)
    modes.sort(key=lambda s: s.get("mode_n", 0))
    freqs = np.array([float(s["freq"]) for s in modes])
    mm = np.array([float(s.get("modal_m", 0.0)) for s in modes])
    nodes = [int(n) for n in modes[0]["node_nums"]]
    for s in modes:
        if [int(n) for n in s["node_nums"]] != nodes:
            raise ConfigError(_F, f"{file}: the mode datasets do not list the same nodes")
    if any(n not in coords for n in nodes):
        raise ConfigError(_F, f"{file}: nodes of dataset 55 without coordinates (dataset 15 or 2411)")
    X = np.array([coords[n] for n in nodes], dtype=float) * LENGTH_UNITS[cfg.length_unit]
    phi = np.stack([np.column_stack([s["r1"], s["r2"], s["r3"]]).real for s in modes], axis=-1)  # (N, 3, m)
    bores, rings = [], []
    scale = float(np.linalg.norm(np.ptp(X, axis=0))) if len(X) else 1.0
    for i, b in enumerate(cfg.bores):
        c, u = np.asarray(b.center, float), np.asarray(b.unit_axis, float)
        d = X - c
        s = d @ u
        rad = np.linalg.norm(d - s[:, None] * u, axis=1)
        on = np.flatnonzero(np.abs(rad - b.bore_radius) <= 1e-6 + 1e-4 * b.bore_radius)
        if b.length is not None:
            on = on[np.abs(s[on]) <= 0.5 * b.length + 1e-6]
        if not on.size:
            raise ConfigError(f"housing.bores[{i}]", f"{file}: no node lies on the bore cylinder (radius "
                              f"{b.bore_radius:g} m about the line through {list(b.center)})")
        segs = bore_segments([(float(s[k]), float(s[k])) for k in on], 1e-3 * scale)
        geo = segment_bores(cfg, i, segs, c, u)
        e1, e2 = ring_frame(u)
        for g, (_, _, idx) in zip(geo, segs):
            ids = on[idx]
            if len(ids) != b.rolling_elements:
                raise ConfigError(f"housing.bores[{i}].rolling_elements", f"{file}: bore {g.name!r} has "
                                  f"{len(ids)} nodes on its ring, the config says {b.rolling_elements}")
            th = np.mod(np.arctan2(d[ids] @ e2, d[ids] @ e1), 2 * np.pi)
            ids = ids[np.argsort(th, kind="stable")]
            bores.append(g)
            rings.append(ids)
    B, P = len(bores), max((len(r) for r in rings), default=0)
    bp, bv = np.full((B, P, 3), np.nan), np.full((B, P, 3, freqs.size), np.nan)
    for j, ids in enumerate(rings):
        bp[j, :len(ids)] = X[ids] / LENGTH_UNITS[cfg.length_unit]
        bv[j, :len(ids)] = phi[ids]
    out = dict(freqs_hz=freqs, bore_values=bv, bore_points=bp, bore_n_points=np.array([len(r) for r in rings]),
               bore_names=[g.name for g in bores],
               bore_centers=np.array([g.center for g in bores]).reshape(-1, 3) / LENGTH_UNITS[cfg.length_unit],
               bore_axes=np.array([g.axis for g in bores]).reshape(-1, 3))
    if np.any(mm != 0.0):
        out["modal_mass"] = mm
    return out


def write_modes_csv(res: HousingModes, path: str | Path) -> Path:
    """The coupling data of ``res`` in the CSV layout this module reads (for exchange and tests)."""
    path = Path(path)
    m = res.n_modes
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["bore", "point", "x", "y", "z", "direction"] + [f"mode_{i + 1}" for i in range(m)])
        w.writerow(["frequency_hz", "", "", "", "", ""] + [repr(float(f)) for f in res.freqs_hz])
        for j, name in enumerate(res.bore_names):
            for p in range(res.bore_n_points[j]):
                xyz = [repr(float(v)) for v in res.bore_points[j, p]]
                for c, d in enumerate("xyz"):
                    w.writerow([name, p, *xyz, d] + [repr(float(v)) for v in res.bore_values[j, p, c]])
    return path
