"""A gear mesh's stiffness law: the user's value (a mean with Fourier harmonics, or the two
levels of single and double contact), or ISO 6336-1 method B's k_normal with its
contact-wave harmonics (:mod:`.iso6336`), with the record the summary reports."""
from __future__ import annotations

import logging
import math

import numpy as np

from ...config.base import ConfigError
from ...config.model.gearbox_meshes import stiffness_wave_minimum
from .iso6336 import MeshStiffness, mesh_stiffness

__all__ = ["iso_mesh_stiffness", "mesh_law", "level_harmonics"]

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


def level_harmonics(k_single: float, k_double: float, share: float, terms: int):
    """(k_mean, harmonics_cos, harmonics_sin, peak error) of the square wave of two levels:
    k_double over the fraction ``share`` of the mesh period from t = 0 (a new pair enters, as
    ISO 6336's wave), k_single elsewhere.  Its Fourier series relative to the mean,
    a_h = D sin(2 pi h s) / (pi h), b_h = D (1 - cos(2 pi h s)) / (pi h), D = (k_double -
    k_single) / k_mean, is truncated after ``terms`` harmonics with Fejer weights (1 - h /
    (terms + 1)): a plain truncation overshoots each step by 9 % of the step whatever the
    number of terms (Gibbs), so its peak force never reaches the two-level value; the Fejer
    sum stays within [k_single, k_double] and its peak approaches k_double as 1/terms.  The
    peak error is (k_double - max of the series) / k_double (>= 0)."""
    k_mean = k_single + share * (k_double - k_single)
    D = (k_double - k_single) / k_mean
    h = np.arange(1, terms + 1, dtype=float)
    w = 1.0 - h / (terms + 1.0)
    a = w * D * np.sin(2 * np.pi * h * share) / (np.pi * h)
    b = w * D * (1.0 - np.cos(2 * np.pi * h * share)) / (np.pi * h)
    theta = np.linspace(0.0, 2 * np.pi, 64 * terms + 64, endpoint=False)
    k = k_mean * (1.0 + np.cos(np.outer(theta, h)) @ a + np.sin(np.outer(theta, h)) @ b)
    peak = float(k.max())
    return k_mean, tuple(float(v) for v in a), tuple(float(v) for v in b), \
        max(0.0, (k_double - peak) / k_double)


def mesh_law(cfg, i) -> tuple[float, tuple, tuple, dict]:
    """(stiffness along the normal [N/m], stiffness_cos, stiffness_sin, summary record) of
    ``meshes[i]``: the user's value (mean and harmonics, or the square wave of
    ``stiffness_levels``), or ISO 6336-1's k_normal with its contact harmonics (every mesh,
    unless the user gives harmonics); harmonics of the mesh's own mesh frequency, none with
    ``excite = false``.  ISO is reported next to a user value whenever the gear data are in
    its range."""
    m, path = cfg.meshes[i], f"gearbox.meshes[{i}]"
    try:
        iso = iso_mesh_stiffness(cfg, i)
    except ConfigError as exc:
        if m.iso6336:
            raise
        iso, note = None, str(exc)
    k, hc, hs = (iso.k_normal if m.iso6336 else m.stiffness), m.stiffness_cos, m.stiffness_sin
    levels = None
    if m.stiffness_levels:
        share = m.double_contact_share
        if share is None:
            if iso is None or not 1.0 < iso.eps_alpha < 2.0 or iso.eps_beta > 0.0:
                why = (f"ISO 6336's contact ratio is not available ({note})" if iso is None
                       else f"eps_alpha = {iso.eps_alpha:.4g} is not between 1 and 2"
                       if not 1.0 < iso.eps_alpha < 2.0 else
                       f"the pair is helical (eps_beta = {iso.eps_beta:.4g}): the contact "
                       f"lines sweep the face and no single share follows from eps_alpha "
                       f"(eps_alpha - 1 = {iso.eps_alpha - 1.0:.4g})")
                raise ConfigError(f"{path}.double_contact_share", f"missing: the default "
                                  f"share eps_alpha - 1 needs a contact ratio between 1 and "
                                  f"2; {why}; give the share of the mesh period with two "
                                  "pairs in contact (0 < share < 1)")
            share = iso.eps_alpha - 1.0
        k1, k2 = m.stiffness_levels
        k, hc, hs, err = level_harmonics(k1, k2, share, m.level_terms)
        levels = {"k_single_N_per_m": k1, "k_double_N_per_m": k2, "double_contact_share": share,
                  "share_source": "given" if m.double_contact_share is not None
                  else "eps_alpha - 1 (ISO 6336-1)", "terms": m.level_terms,
                  "weights": "Fejer (1 - h / (terms + 1))", "peak_stiffness_error": err}
        log.info("mesh %s: stiffness levels %.4g / %.4g N/m, double contact %.3f of the mesh "
                 "period -> mean %.4g N/m, %d Fejer terms (peak %.2g %% below k_double)",
                 m.name, k1, k2, share, k, m.level_terms, 100 * err)
    elif m.iso6336 and not (hc or hs):
        hc, hs = iso.harmonics_cos, iso.harmonics_sin
        low, _ = stiffness_wave_minimum(hc, hs)
        if low <= 0.0:
            raise ConfigError(f"{path}.iso_harmonics", f"the truncated contact wave goes "
                              f"negative (min k/k_mean = {low:.3g}); use fewer harmonics")
    if not m.excite:
        hc, hs = (), ()
    rec = {"mesh": m.name, "source": "iso6336" if m.iso6336 else
           ("levels" if levels else "user"),
           "stiffness_used_N_per_m": float(k), "harmonics_cos": list(hc),
           "harmonics_sin": list(hs), "excite": m.excite,
           "user_N_per_m": None if m.iso6336 else float(k),
           "iso6336": None if iso is None else iso.as_dict()}
    if levels:
        rec["levels"] = levels
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
