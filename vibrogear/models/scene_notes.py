"""What a scene derives from what its author wrote, in words: the static twist of each
coupling loaded by ``torque`` or ``power``, and the Hertz contact constant of each bearing
given by designation, boundary dimensions or element set (with the element set and the
formula).  ``vibrogear check`` and ``vibrogear import`` print these lines."""
from __future__ import annotations

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
                       f"{c.stiffness:g} N m/rad -> twist {c.static_twist:.6g} rad")
        elif c.load_given == "power":
            out.append(f"gearbox.couplings[{i}] {c.name!r}: power {c.power:g} kW at {c.rpm:g} "
                       f"rpm -> torque {c.static_torque:.6g} N m -> twist "
                       f"{c.static_twist:.6g} rad")
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
