"""The shafts' reduction level (paper II.B): master modes by count, or by the paper's
frequency criterion with the static contribution of the truncated modes kept.

``[gearbox] master_modes = "frequency"``: shaft s keeps all its free modes up to
``frequency_factor`` x its highest excitation frequency, the largest of (mesh frequency x
harmonics) over the meshes whose gears it carries, at the scene's highest speed
(:func:`highest_speed`); every mesh counts the harmonics of its own mesh frequency it
excites (stiffness / transmission-error harmonics, ISO 6336's ``iso_harmonics`` or the
square wave's ``level_terms``; none with ``excite = false``), at least its tooth-pass
frequency.  ``static_correction`` (default on with "frequency") adds the static deflection
shapes under the shaft's coupling forces (:func:`~vibrogear.models.rotor.model.static_correction`),
so the coupling stiffness stays the full shaft's; with "frequency" their pseudo-modes are
capped at the cutoff (mass scaling: their static flexibility unchanged), so no master mode
is faster than the criterion.  The housing keeps its own count ([housing.modes]; its
residual flexibility would need a solve with the full housing matrices).
"""
from __future__ import annotations

import numpy as np

from ...config.base import ConfigError
from ..rotor.model import MasterModes, RotorModel, master_modes, static_correction

__all__ = ["highest_speed", "excitation_frequencies_hz", "coupling_loads", "shaft_master_modes"]


def highest_speed(scene) -> float:
    """The highest driving speed [rpm] any analysis of the scene reaches ([sweep] and
    [continuation] rpm_max, [time_response] rpm, [reduction_accuracy] rpm, gearbox.modes_rpm)."""
    vals = [getattr(getattr(scene, sec, None), "param_max", None)
            for sec in ("sweep", "continuation")]
    vals += [getattr(getattr(scene, "time_response", None), "param", None),
             getattr(getattr(scene, "reduction_accuracy", None), "rpm", None),
             scene.gearbox.modes_rpm]
    vals = [float(v) for v in vals if v is not None]
    if not vals or max(vals) <= 0.0:
        raise ConfigError("gearbox.master_modes", "\"frequency\" needs the scene's speed "
                          "range: give [sweep], [continuation] or [time_response] (or "
                          "gearbox.modes_rpm)")
    return max(vals)


def _harmonics(m) -> int:
    """The highest harmonic of its own mesh frequency a mesh excites (at least 1: its
    tooth-pass frequency)."""
    return max(m.excitation_harmonics, 1)


def excitation_frequencies_hz(cfg, rpm: float) -> np.ndarray:
    """Per shaft: the highest excitation frequency [Hz] it carries at driving speed ``rpm``."""
    shaft_p, gear_p = cfg.speed_ratios()
    out = np.zeros(len(cfg.shafts))
    for i, m in enumerate(cfg.meshes):
        ka, kb = cfg.gear_index(m.gear_a, ""), cfg.gear_index(m.gear_b, "")
        ga = cfg.gears[ka]
        f = ga.teeth * abs(gear_p[ka]) * rpm / 60.0 * _harmonics(m)
        for k in (ka, kb):
            s = cfg.shaft_index(cfg.gears[k].shaft, "")
            out[s] = max(out[s], f)
    return out


def coupling_loads(s: int, n_dofs: int, vectors) -> np.ndarray:
    """(n_dofs, r): the force patterns on shaft ``s`` of the coupling functionals
    (PhysicalVector: contacts, links, block rows, the static load), one column each."""
    cols = []
    for vec in vectors:
        for k, idx, val in vec.parts:
            if k == s and np.any(val):
                c = np.zeros(n_dofs)
                np.add.at(c, idx, val)
                cols.append(c)
    return np.array(cols).T if cols else np.zeros((n_dofs, 0))


def shaft_master_modes(sh, rotor: RotorModel, *, count, cutoff_hz=None, loads=None,
                       cap_hz=None) -> MasterModes:
    """The shaft's master modes: ``count`` / ``cutoff_hz`` (the shaft's own keys or the
    frequency criterion's cutoff), plus the static correction for ``loads`` when given."""
    if cutoff_hz is not None:
        mm = master_modes(rotor, cutoff_hz=cutoff_hz)
    else:
        mm = master_modes(rotor, count=count if sh.master_cutoff_hz is None else None,
                          cutoff_hz=sh.master_cutoff_hz)
    if loads is not None and loads.shape[1]:
        mm = static_correction(rotor, mm, loads, cap_hz=cap_hz)
    return mm
