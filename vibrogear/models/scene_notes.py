"""What a scene derives from what its author wrote, in words: the static twist of each
coupling loaded by ``torque`` or ``power``, its torque orders as fractions of the mesh
frequency, each mesh's mesh frequency over meshes[0]'s (and the period of the whole
excitation), and the Hertz contact constant of each bearing
given by designation, boundary dimensions or element set (with the element set and the
formula).  ``vibrogear check`` and ``vibrogear import`` print these lines."""
from __future__ import annotations

from ..config.model.gearbox_supports import torque_order_ratios

__all__ = ["derived_lines"]


def derived_lines(scene) -> list[str]:
    cfg = getattr(scene, "gearbox", None)
    if cfg is None:
        return []
    from .gearbox.bearing_hertz import contact_constant
    out = []
    for i, c in enumerate(cfg.couplings):
        if c.load_given == "torque":
            out.append(f"gearbox.couplings[{i}] {c.name!r}: torque {c.torque:g} N m / stiffness "
                       f"{c.stiffness:g} N m/rad -> twist {c.static_twist:.6g} rad on a rigid "
                       "train (the load path solves the twist the elastic train needs)")
        elif c.load_given == "power":
            out.append(f"gearbox.couplings[{i}] {c.name!r}: power {c.power:g} kW at {c.rpm:g} "
                       f"rpm -> torque {c.static_torque:.6g} N m -> twist "
                       f"{c.static_twist:.6g} rad on a rigid train (the load path solves the "
                       "twist the elastic train needs)")
    out += _order_lines(cfg)
    out += _level_lines(cfg)
    for i, b in enumerate(cfg.bearings):
        es = b.element_set(f"gearbox.bearings[{i}]")
        if es is None or b.stiffness is not None:
            continue
        k = contact_constant(es)
        unit = "N/m^1.5" if k.exponent == 1.5 else "N/m^(10/9)"
        src = f"designation {b.designation!r}" if b.designation else "its geometry"
        out.append(f"gearbox.bearings[{i}] {b.name!r}: {src} -> {es.kind}, {es.count} elements, "
                   f"D_w = {es.element_diameter * 1e3:.4g} mm, d_m = "
                   f"{es.pitch_diameter * 1e3:.4g} mm"
                   + (f", l = {es.element_length * 1e3:.4g} mm" if es.element_length else "")
                   + f" -> contact constant {k.stiffness:.4g} {unit} per element ({k.method})"
                   + (f"; assumed by the element-set rule: {', '.join(es.assumed)}"
                      if es.assumed else ""))
    return out


def _order_lines(cfg) -> list[str]:
    """Each coupling's torque orders and each exciting mesh as fractions of the mesh
    frequency of meshes[0], and the period after which the whole excitation repeats (what
    the sweep and shooting then span, or per mesh period beyond the period limit)."""
    terms = torque_order_ratios(cfg)
    out = []
    for i in sorted({t[0] for t in terms}):
        c = cfg.couplings[i]
        parts = [f"order {float(o):g} ({a:g} N m" + (f", {ph:g} deg" if ph else "")
                 + f") = {n.numerator}/{n.denominator} of the mesh frequency"
                 for j, o, a, ph, n in terms if j == i]
        out.append(f"gearbox.couplings[{i}] {c.name!r}: torque " + "; ".join(parts))
    ratios = cfg.mesh_frequency_ratios()
    for i, (m, r) in enumerate(zip(cfg.meshes, ratios)):
        if i == 0 and len(cfg.meshes) == 1:
            break
        za = cfg.gears[cfg.gear_index(m.gear_a, "")].teeth
        zb = cfg.gears[cfg.gear_index(m.gear_b, "")].teeth
        state = (f"excites {m.excitation_harmonics} harmonic"
                 f"{'s' if m.excitation_harmonics > 1 else ''}" if m.excitation_harmonics
                 else "no excitation" + ("" if m.excite else " (excite = false)"))
        out.append(f"gearbox.meshes[{i}] {m.name!r} ({za}/{zb} teeth): mesh frequency "
                   f"{r.numerator}/{r.denominator} of meshes[0]'s; {state}")
    P = cfg.common_period()
    if cfg.multi_frequency:
        out.append(f"excitation: the sources ({cfg.period_sources()}) repeat together only "
                   f"every {P} mesh periods of meshes[0] (period limit "
                   f"{cfg.period_limit()}): sweep, states, map and nvh sample per mesh period "
                   "(the response is multi-frequency forced); continuation is refused; "
                   "time response and run-up count mesh periods")
    elif P > 1:
        out.append(f"excitation: repeats every {P} mesh periods of meshes[0] "
                   f"({cfg.period_sources()}); a sweep, states and continuation period is "
                   f"that whole period (their transient and record periods cost {P}x), time "
                   "response and run-up count mesh periods")
    return out


def _level_lines(cfg) -> list[str]:
    """Each mesh given by stiffness_levels: its square wave, the mean and the Fourier terms
    the model uses, with the peak stiffness (= peak force of a stiff-driven pair) error."""
    from .gearbox.mesh_law import mesh_law
    out = []
    for i, m in enumerate(cfg.meshes):
        if not m.stiffness_levels:
            continue
        lv = mesh_law(cfg, i)[3]["levels"]
        out.append(f"gearbox.meshes[{i}] {m.name!r}: stiffness levels "
                   f"{lv['k_single_N_per_m']:.4g} / {lv['k_double_N_per_m']:.4g} N/m, double "
                   f"contact over {lv['double_contact_share']:.4g} of the mesh period "
                   f"({lv['share_source']}) -> mean {mesh_law(cfg, i)[0]:.4g} N/m, "
                   f"{lv['terms']} Fejer-weighted Fourier terms: peak stiffness "
                   f"{100 * lv['peak_stiffness_error']:.2g} % below k_double (no overshoot)")
    return out
