"""Files of ``nnm`` (nonlinear normal modes, :mod:`vibrogear.analyses.nnm`).

* ``nnm.npz``, one entry per backbone point (all backbones concatenated):
  ``omega`` (impact pair: circular frequency in the unit of Omega) or ``frequency_hz``
  (gearbox); ``amplitude`` (max |delta| over the orbit of the monitored coordinate: the impact
  pair's q, a gearbox's monitored mesh deformation, in the monitor's display unit: um);
  ``qmin``, ``qmax`` (its extrema, display unit); ``excursion`` (max |delta - delta_s|);
  ``energy`` (above the loaded static state: J for a gearbox, model units for the impact
  pair); ``period`` (s for a gearbox, model time for the impact pair); ``stable`` (every
  nontrivial Floquet multiplier on the unit circle); ``max_abs_multiplier`` (over the
  nontrivial ones); ``trivial_multipliers`` (points x 2: the phase and energy pair); ``u0``
  (points x states: the orbit's state at t = 0, model units); ``branch`` (0: the start
  mode, 1: ``second_mode``); ``mode`` (its elastic-mode index); ``label`` ("" or "IR p:q"
  internal resonance, "LP" energy fold, "GR" grazing stepped over, "J" a step over a
  non-smooth point); ``residual``; and per backbone ``linear_<freq>`` (its linear frequency)
  and ``onset_energy`` (the contact-switch energy from the static state, inf where none);
  ``linear_frequencies`` (every elastic mode); with ``shape_energies`` also ``shape_t``,
  ``shape_x`` (shapes x samples x modes), ``shape_delta``, ``shape_energy``, ``shape_branch``.
* ``nnm.csv``: the per-point scalars.
* ``nnm_fep.png/.svg``: the frequency-energy plot (frequency against log energy; stable solid,
  unstable dashed, labels marked; the linear frequencies of the other modes at small rational
  ratios as dotted lines).
* ``nnm_backbone.png/.svg``: the backbone(s) in (frequency, amplitude) over the forced branches
  (``continuation`` of this run, or its ``branch.npz`` in the output folder) and the sweep
  points (``sweep``, or ``sweep.npz``), the forced parameter converted to the excitation
  frequency.
"""
from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from ...pipeline.files import atomic_write_bytes, atomic_write_npz
from ..figure import save_figure
from ..plots.nnm import plot_backbone, plot_fep

__all__ = ["write", "nnm_arrays", "CSV_COLUMNS"]

CSV_COLUMNS = ("branch", "mode", "energy", "period", "stable", "label", "amplitude", "qmin",
               "qmax", "excursion", "max_abs_multiplier", "residual")


def nnm_arrays(r) -> dict:
    """The arrays of ``nnm.npz`` from an :class:`~vibrogear.analyses.nnm.NnmStudyResult`."""
    scale = r.study.monitor.scale
    pts = [(b, br, p) for b, br in enumerate(r.branches) for p in br.points]
    n = pts[0][2].u0.size if pts else 0
    period_scale = r.conservative.time_unit_s if r.freq_key == "frequency_hz" else 1.0
    d_s = r.delta_static
    out = {
        r.freq_key: np.array([p.omega * r.freq_scale for _, _, p in pts]),
        "amplitude": np.array([p.amplitude * scale for _, _, p in pts]),
        "qmin": np.array([p.qmin * scale for _, _, p in pts]),
        "qmax": np.array([p.qmax * scale for _, _, p in pts]),
        "excursion": np.array([p.excursion(d_s) * scale for _, _, p in pts]),
        "energy": np.array([p.energy * r.energy_scale for _, _, p in pts]),
        "period": np.array([p.period * period_scale for _, _, p in pts]),
        "stable": np.array([p.stable for _, _, p in pts], dtype=bool),
        "max_abs_multiplier": np.array([p.max_abs_multiplier for _, _, p in pts]),
        "trivial_multipliers": np.array([p.trivial[:2] for _, _, p in pts],
                                        dtype=complex).reshape(len(pts), 2),
        "u0": np.array([p.u0 for _, _, p in pts]).reshape(len(pts), n),
        "branch": np.array([b for b, _, _ in pts], dtype=np.int64),
        "mode": np.array([br.mode for _, br, _ in pts], dtype=np.int64),
        "label": np.array([p.label for _, _, p in pts], dtype="<U8"),
        "residual": np.array([p.residual for _, _, p in pts]),
        f"linear_{r.freq_key}": np.array([br.omega_linear * r.freq_scale for br in r.branches]),
        "onset_energy": np.array(r.onset_energy, dtype=float),
        "linear_frequencies": np.asarray(r.linear_frequencies, dtype=float),
        "energy_unit": np.asarray(r.energy_unit),
    }
    if r.shapes:
        out["shape_t"] = np.array([s["t"] * period_scale for s in r.shapes])
        out["shape_x"] = np.array([s["x"] for s in r.shapes])
        out["shape_delta"] = np.array([s["delta"] * scale for s in r.shapes])
        out["shape_energy"] = np.array([s["energy"] * r.energy_scale for s in r.shapes])
        out["shape_branch"] = np.array([s["branch"] for s in r.shapes], dtype=np.int64)
    return out


def _cell(x) -> str:
    if isinstance(x, (float, np.floating)):
        return repr(float(x)) if math.isfinite(x) else ""
    return str(x)


def _forced(previous, out, study, name: str, file: str):
    """Arrays of the forced ``continuation`` / ``sweep`` of this run, else of its file in
    ``out``; None where neither exists."""
    got = (previous or {}).get(name)
    if got is not None and got.result is not None:
        if name == "continuation":
            return got.result.arrays()
        from ..sweep_files import sweep_arrays
        return sweep_arrays(got.result.sweep)
    path = Path(out) / file
    if path.is_file():
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        if "param_name" in data and str(data["param_name"]) != study.model.param_name:
            return None
        return data
    return None


def write(scene, outcome, out, previous=None) -> dict:
    r = outcome.result
    out = Path(out)
    arrays = nnm_arrays(r)
    npz = atomic_write_npz(out / "nnm.npz", arrays)
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow((r.freq_key,) + CSV_COLUMNS)
    for k in range(arrays["energy"].size):
        w.writerow([_cell(v) for v in (
            float(arrays[r.freq_key][k]), int(arrays["branch"][k]), int(arrays["mode"][k]),
            float(arrays["energy"][k]), float(arrays["period"][k]), bool(arrays["stable"][k]),
            str(arrays["label"][k]), float(arrays["amplitude"][k]), float(arrays["qmin"][k]),
            float(arrays["qmax"][k]), float(arrays["excursion"][k]),
            float(arrays["max_abs_multiplier"][k]), float(arrays["residual"][k]))])
    csv_path = atomic_write_bytes(out / "nnm.csv", text.getvalue().encode())
    files = {"npz": str(npz), "csv": str(csv_path)}
    files["fep_png"] = str(save_figure(plot_fep(r, arrays), out / "nnm_fep")[0])
    study = r.study
    forced = _forced(previous, out, study, "continuation", "branch.npz")
    sweep = _forced(previous, out, study, "sweep", "sweep.npz")
    # the forced parameter -> its excitation frequency in the backbone's unit
    to_freq = study.model.omega_per_param * r.freq_scale
    files["backbone_png"] = str(save_figure(plot_backbone(r, arrays, forced, sweep, to_freq),
                                            out / "nnm_backbone")[0])
    return files
