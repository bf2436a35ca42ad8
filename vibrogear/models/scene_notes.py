"""What a scene derives from what its author wrote, in words: the static twist of each
coupling loaded by ``torque`` or ``power``, its torque orders as fractions of the mesh
frequency (and the period of the whole excitation), and the Hertz contact constant of each bearing
given by designation, boundary dimensions or element set (with the element set and the
formula).  ``vibrogear check`` and ``vibrogear import`` print these lines."""
from __future__ import annotations

from ..config.gearbox_supports import order_period, torque_order_ratios

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
    """Each coupling's torque orders as fractions of the mesh frequency, and the period
    after which the whole excitation repeats (what the sweep and shooting then span)."""
    terms = torque_order_ratios(cfg)
    if not terms:
        return []
    out = []
    for i in sorted({t[0] for t in terms}):
        c = cfg.couplings[i]
        parts = [f"order {float(o):g} ({a:g} N m" + (f", {ph:g} deg" if ph else "")
                 + f") = {n.numerator}/{n.denominator} of the mesh frequency"
                 for j, o, a, ph, n in terms if j == i]
        out.append(f"gearbox.couplings[{i}] {c.name!r}: torque " + "; ".join(parts))
    P = order_period(terms)
    if P > 1:
        out.append(f"torque orders: the excitation repeats every {P} mesh periods; a sweep, "
                   f"states and continuation period is that whole period ({P} mesh periods: "
                   f"their transient and record periods cost {P}x), time response and run-up "
                   "count mesh periods")
    return out
