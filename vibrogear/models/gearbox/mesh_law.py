"""A gear mesh's stiffness law: the user's value, or ISO 6336-1 method B's k_normal with its
contact-wave harmonics (:mod:`.iso6336`), with the record the summary reports."""
from __future__ import annotations

import logging
import math

import numpy as np

from ...config.base import ConfigError
from .iso6336 import MeshStiffness, mesh_stiffness

__all__ = ["iso_mesh_stiffness", "mesh_law"]

log = logging.getLogger(__name__)


def iso_mesh_stiffness(cfg, i: int) -> MeshStiffness:
    """ISO 6336-1 method B values of ``meshes[i]`` (:mod:`vibrogear.models.gearbox.iso6336`); a
    ConfigError naming the mesh where the gear data lie outside the method's range."""
    m, path = cfg.meshes[i], f"gearbox.meshes[{i}]"
    ga = cfg.gears[cfg.gear_index(m.gear_a, f"{path}.gear_a")]
    gb = cfg.gears[cfg.gear_index(m.gear_b, f"{path}.gear_b")]
    try:
        return mesh_stiffness(ga.teeth, gb.teeth, ga.module,
                              m.face_width or min(ga.width, gb.width),
                              alpha_n=math.radians(m.pressure_angle),
                              beta=math.radians(ga.helix_angle), x1=m.profile_shift_a,
                              x2=m.profile_shift_b, addendum=m.addendum, dedendum=m.dedendum,
                              web_ratio=m.web_ratio, rim_ratio=m.rim_ratio,
                              line_load=m.line_load, harmonics=m.iso_harmonics)
    except ValueError as exc:
        raise ConfigError(f"{path}.stiffness", f"ISO 6336-1 mesh stiffness: {exc}") from None


def mesh_law(cfg, i) -> tuple[float, tuple, tuple, dict]:
    """(stiffness along the normal [N/m], stiffness_cos, stiffness_sin, summary record) of
    ``meshes[i]``: the user's value, or ISO 6336-1's k_normal with its contact harmonics
    (on meshes[0], unless the user gives harmonics).  ISO is reported next to a user value
    whenever the gear data are in its range."""
    m, path = cfg.meshes[i], f"gearbox.meshes[{i}]"
    try:
        iso = iso_mesh_stiffness(cfg, i)
    except ConfigError as exc:
        if m.iso6336:
            raise
        iso, note = None, str(exc)
    k, hc, hs = (iso.k_normal if m.iso6336 else m.stiffness), m.stiffness_cos, m.stiffness_sin
    if m.iso6336 and i == 0 and not (hc or hs):
        hc, hs = iso.harmonics_cos, iso.harmonics_sin
        t = np.linspace(0.0, 2 * np.pi, 64 * max(len(hc), 1), endpoint=False)
        h = np.arange(1, len(hc) + 1)
        low = 1.0 + np.min(np.cos(np.outer(t, h)) @ np.asarray(hc, float)
                           + np.sin(np.outer(t, h)) @ np.asarray(hs, float)) if hc else 1.0
        if low <= 0.0:
            raise ConfigError(f"{path}.iso_harmonics", f"the truncated contact wave goes "
                              f"negative (min k/k_mean = {low:.3g}); use fewer harmonics")
    rec = {"mesh": m.name, "source": "iso6336" if m.iso6336 else "user",
           "stiffness_used_N_per_m": float(k), "harmonics_cos": list(hc),
           "harmonics_sin": list(hs),
           "user_N_per_m": None if m.iso6336 else float(m.stiffness),
           "iso6336": None if iso is None else iso.as_dict()}
    if iso is None:
        rec["iso6336_note"] = note
    elif iso.eps_alpha < 1.2:
        rec["iso6336_note"] = (f"eps_alpha = {iso.eps_alpha:.3f} < 1.2: ISO's c_gamma_alpha "
                               "may be up to 10 % too high")
        log.warning("mesh %s: %s", m.name, rec["iso6336_note"])
    log.info("mesh %s: stiffness %.4g N/m (%s)%s", m.name, k, rec["source"],
             "" if iso is None else f"; ISO 6336-1: {iso.k_normal:.4g} N/m along the normal, "
             f"c' = {iso.c_prime / 1e9:.3f} N/(mm um), eps_alpha = {iso.eps_alpha:.3f}, "
             f"eps_beta = {iso.eps_beta:.3f}")
    return float(k), tuple(hc), tuple(hs), rec
