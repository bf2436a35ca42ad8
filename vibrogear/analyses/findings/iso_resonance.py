"""The resonance speed of each gear pair by ISO 6336-1:2006 (6.5, method B) and its main
resonance range, as the standard computes them from the gear data.

For a pair with pinion (fewer teeth) 1 and wheel 2:

    m_red = J1 J2 / (J1 r_b2^2 + J2 r_b1^2)         reduced mass on the line of action [kg]
    n_E1  = 30 / (pi z1) sqrt(c_gamma_alpha b / m_red)   pinion resonance speed [rpm]

(SI units; the standard writes 30 000 for c in N/(mm um) and masses per mm of face width.)
J: the gear body's polar inertia (``Ip`` where given, else the pitch-diameter disc less its
bore with the gear's density, else its shaft's), r_b: base radius, c_gamma_alpha b: the mean
mesh stiffness along the transverse line of action (ISO 6336-1 method B where the mesh says
``stiffness = "iso6336"``, else the scene's normal stiffness times cos^2 beta_b).  The
resonance ratio is N = n1 / n_E1; the ranges: sub-critical N <= N_S, main resonance
N_S < N <= 1.15, intermediate 1.15 < N < 1.5, supercritical N >= 1.5, with N_S = 0.85
(line loads of 100 N/mm and above; the standard lowers N_S at lighter loads, which widens
the range: 0.85 is the narrower, stated choice).

The standard's pair is two rigid gear bodies on a spring: shafts, bearings, couplings and a
housing are left out, and its n_E1 is the one torsional mode of the pair.  The simulated
dynamic factor (``kv_<mesh>``) peaks where a mode of the whole gearbox with mesh strain
energy meets a mesh order, and it includes nonlinear contact loss: the two differ where the
shafts' torsional and bending compliance take part in the mode (the simulated peak then lies
below n_E1) and where contact loss bends the resonance (softening: the peak moves down).
"""
from __future__ import annotations

import math

from ...config.numbers import fmt

__all__ = ["iso_resonances", "iso_bands", "N_S", "N_MAIN_HI", "N_SUPER"]

N_S, N_MAIN_HI, N_SUPER = 0.85, 1.15, 1.5


def _inertia(cfg, gear) -> float:
    if gear.Ip is not None:
        return float(gear.Ip)
    shaft = cfg.shafts[cfg.shaft_index(gear.shaft, "")]
    rho = gear.density if gear.density is not None else shaft.material.rho
    D, d = gear.pitch_diameter, gear.inner_diameter
    return rho * math.pi * gear.width * (D ** 4 - d ** 4) / 32.0


def iso_resonances(cfg) -> dict:
    """{"meshes": [{name, z1, pinion, n_E1_pinion_rpm, n_E1_rpm (driving speed),
    main_range_rpm [lo, hi], m_red_kg, c_gamma_alpha_b_N_per_m}], "N_S": ...} of a
    :class:`~vibrogear.config.model.gearbox.GearboxConfig`."""
    from ...models.gearbox.mesh_law import iso_mesh_stiffness
    _, gear_p = cfg.speed_ratios()
    out = []
    for i, m in enumerate(cfg.meshes):
        ka, kb = cfg.gear_index(m.gear_a, ""), cfg.gear_index(m.gear_b, "")
        ga, gb = cfg.gears[ka], cfg.gears[kb]
        beta = math.radians(ga.helix_angle)
        alpha_t = math.atan(math.tan(math.radians(m.pressure_angle)) / math.cos(beta))
        beta_b = math.asin(abs(math.sin(beta)) * math.cos(math.radians(m.pressure_angle)))
        if m.iso6336:
            k = iso_mesh_stiffness(cfg, i).k_mean
        else:
            k = float(m.stiffness) * math.cos(beta_b) ** 2
        rb = [g.pitch_diameter / 2 * math.cos(alpha_t) for g in (ga, gb)]
        J = [_inertia(cfg, g) for g in (ga, gb)]
        m_red = J[0] * J[1] / (J[0] * rb[1] ** 2 + J[1] * rb[0] ** 2)
        p, kp = (ga, ka) if ga.teeth <= gb.teeth else (gb, kb)
        n_e1 = 30.0 / (math.pi * p.teeth) * math.sqrt(k / m_red)
        ratio = abs(gear_p[kp]) if gear_p[kp] else math.nan
        drive = n_e1 / ratio if ratio and math.isfinite(ratio) else math.nan
        out.append({"name": m.name, "pinion": p.name, "z1": int(p.teeth),
                    "m_red_kg": m_red, "c_gamma_alpha_b_N_per_m": k,
                    "n_E1_pinion_rpm": n_e1, "pinion_per_driving_speed": ratio,
                    "n_E1_rpm": drive,
                    "main_range_rpm": [N_S * drive, N_MAIN_HI * drive]})
    return {"meshes": out, "N_S": N_S, "N_main_hi": N_MAIN_HI, "N_supercritical": N_SUPER,
            "standard": "ISO 6336-1:2006 6.5 (method B)"}


def iso_bands(iso: dict, roles, rules, span) -> tuple[list, list[str]]:
    """A caution band per loaded mesh where the run's speed range meets its main resonance
    range (N_S < n / n_E1 <= 1.15; ``metric`` "N", source "iso6336": recompute as
    ``N_S < param / n_E1_rpm <= 1.15``), and what was checked."""
    from .band_rule import Band
    bands, names = [], []
    lo, hi = float(span[0]), float(span[1])
    for m in iso.get("meshes", []):
        key = m["name"]
        if roles is not None and roles.get(_key(key), "loaded") != "loaded":
            continue
        n = float(m["n_E1_rpm"])
        if not math.isfinite(n):
            continue
        names.append(f"{key} (n_E1 = {fmt(n, 4)} rpm)")
        a, b = max(lo, N_S * n), min(hi, N_MAIN_HI * n)
        if a > b:
            continue
        bands.append(Band("ISO 6336 main resonance", key, "both", a, b, rules.iso_resonance,
                          "N", "in", N_S,
                          f"{key}: ISO 6336-1 resonance speed n_E1 = {fmt(n, 4)} rpm driving "
                          f"({fmt(m['n_E1_pinion_rpm'], 4)} rpm of pinion {m['pinion']}); main "
                          f"resonance range {N_S} < N <= {N_MAIN_HI} = {fmt(N_S * n, 4)}–"
                          f"{fmt(N_MAIN_HI * n, 4)} rpm", source="iso6336", edge_err=0.0,
                          points=0,
                          extra={"compare": f"{N_S} < param / n_E1_rpm <= {N_MAIN_HI}",
                                 "n_E1_rpm": n, "margin": 0.0, "margin_unit": "relative"}))
    checked = [f"ISO 6336-1 main resonance range of {', '.join(names)}"] if names else []
    return bands, checked


def _key(name: str) -> str:
    import re
    return re.sub(r"[^0-9A-Za-z]+", "_", str(name)).strip("_") or "contact"
