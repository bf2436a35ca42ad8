"""Layout checks across sections: the one place for checks that join ``[gearbox]``,
``[housing]`` and the analysis options, run by :meth:`Scene.validate` (so ``vibrogear
check`` reports them before any output exists).

Housing frame as in :mod:`vibrogear.config.model.housing`: the box is ``0..length`` (x),
``0..width`` (y, along the shafts), ``0..height`` (z); the cavity is the box less one wall
thickness on every side.  A bore pair's front bore spans ``y = -boss_length .. wall`` and
its back bore ``y = width - wall .. width + boss_length``; an inner wall's bore spans the
wall (:mod:`~vibrogear.config.model.housing_walls`).
"""
from __future__ import annotations

import math

from ..base import ConfigError, ErrorList
from .housing_walls import bore_walls

__all__ = ["shaft_bore", "check_layout", "check_centre_distances", "working_centre_distance", "bore_spans", "gear_tip_radius", "time_response_bytes",
           "MAX_TIME_RESPONSE_BYTES", "BEARING_SLACK_WALLS"]

#: a bearing may sit this many wall thicknesses outside its bore's span (and no further)
BEARING_SLACK_WALLS = 1.0
#: largest time history a time response may hold (samples x states x 8 bytes)
MAX_TIME_RESPONSE_BYTES = 4 * 2**30


def bore_spans(housing, bore) -> dict[str, tuple[float, float]]:
    """The housing-frame y range of each bore of ``bore``: front, inner walls, back
    (:func:`~vibrogear.config.model.housing_walls.bore_walls`)."""
    return {side: span for side, span, _, _ in bore_walls(housing, bore)}


def gear_tip_radius(gear) -> float:
    """Tip radius of a standard gear: pitch radius + one normal module (addendum)."""
    return 0.5 * gear.pitch_diameter + gear.module


def check_layout(scene) -> None:
    """Every cross-section check that needs no model: bores, bearings, gears in the cavity,
    rolling elements, and the size of a time response."""
    errs = ErrorList()
    if scene.housing is not None:
        with errs.catch():
            _check_bore_names(scene.housing)
    moved: dict[str, tuple[float, float]] = {}
    if scene.gearbox is not None:
        moved, centre_errs = check_centre_distances(scene.gearbox, scene.housing)
        errs.errors += centre_errs.errors
        with errs.catch():
            if scene.housing is not None:
                _check_gearbox_in_housing(scene.gearbox, scene.housing, moved)
            else:
                _check_free_bearings(scene.gearbox)
        # the gear-mesh geometry needs the model layer: vibrogear.models.validate
    if scene.time_response is not None and "time_response" in scene.scene.analyses:
        with errs.catch():
            _check_time_response_size(scene)
    errs.raise_if()


def _check_bore_names(housing) -> None:
    seen: dict[str, int] = {}
    for i, b in enumerate(housing.bores):
        if b.name and b.name in seen:
            raise ConfigError(f"housing.bores[{i}].name", f"{b.name!r} used twice (also "
                              f"housing.bores[{seen[b.name]}]): bore names must be unique")
        seen[b.name] = i


def _check_free_bearings(cfg) -> None:
    for i, b in enumerate(cfg.bearings):
        if b.type != "spring" and b.elements is None and b.element_set() is None:
            raise ConfigError(f"gearbox.bearings[{i}].elements", f"a {b.type!r} bearing without "
                              "a housing needs its number of rolling elements (an integer 3..200)")


def shaft_bore(housing, name: str):
    """The ``[[housing.bores]]`` entry a shaft's ``bore = name`` refers to: the one so named,
    else (an imported housing given one bore per wall) the first named ``<name>/<wall>``;
    None where there is none."""
    exact = next((b for b in housing.bores if b.name == name), None)
    return exact or next((b for b in housing.bores if b.name.rpartition("/")[0] == name), None)


def _check_gearbox_in_housing(cfg, housing, moved=None) -> None:
    bores = {b.name: b for b in housing.bores}
    for sh in cfg.shafts:
        if sh.bore not in bores and shaft_bore(housing, sh.bore) is not None:
            bores[sh.bore] = shaft_bore(housing, sh.bore)
    names = ", ".join(repr(b.name) for b in housing.bores)
    for i, sh in enumerate(cfg.shafts):
        if sh.bore not in bores:
            raise ConfigError(f"gearbox.shafts[{i}].bore", f"unknown bore {sh.bore!r}; housing "
                              f"bores are {names}")
        if sh.x is not None or sh.z is not None:
            raise ConfigError(f"gearbox.shafts[{i}].x", "with a housing the axis is the bore's: "
                              "leave x and z out")
    if housing.source != "parametric":   # imported: no box; its bores are found in its file
        for i, sh in enumerate(cfg.shafts):
            if bores[sh.bore].x is None:
                k = next(j for j, b in enumerate(housing.bores) if b is bores[sh.bore])
                raise ConfigError(f"housing.bores[{k}].axis", f"bore {sh.bore!r} carries "
                                  f"gearbox.shafts[{i}]: its axis must be parallel to the housing "
                                  "y axis (shafts run along y)")
            for k, b in enumerate(housing.bores):     # one bore per wall: all on the shaft's line
                if b.name.rpartition("/")[0] == sh.bore and b.x is not None and (
                        abs(b.x - bores[sh.bore].x) > 1e-9 or abs(b.z - bores[sh.bore].z) > 1e-9):
                    raise ConfigError(f"housing.bores[{k}].center", f"bore {b.name!r} carries "
                                      f"the axis {sh.bore!r} of gearbox.shafts[{i}] at x, z = "
                                      f"{b.x:g}, {b.z:g} m, but {bores[sh.bore].name!r} at "
                                      f"{bores[sh.bore].x:g}, {bores[sh.bore].z:g} m: the bores of "
                                      "one shaft axis must lie on one line")
        return
    t = housing.wall_thickness
    errs = ErrorList()
    used: dict[tuple[str, str], int] = {}
    for i, b in enumerate(cfg.bearings):
        p = f"gearbox.bearings[{i}]"
        if b.outer_shaft:                 # between two shafts: no bore
            continue
        sh = cfg.shafts[cfg.shaft_index(b.shaft, f"{p}.shaft")]
        bore = bores[sh.bore]
        y = sh.y0 + b.position
        spans = bore_spans(housing, bore)
        side = min(spans, key=lambda s: _outside(y, spans[s]))
        lo, hi = spans[side]
        if _outside(y, spans[side]) > BEARING_SLACK_WALLS * t:
            centre = 0.5 * (lo + hi)
            errs.add(ConfigError(f"{p}.position", f"bearing at housing y = {y:.6g} m (shaft y0 "
                                 f"{sh.y0!r} + position {b.position!r}) is "
                                 f"{_outside(y, spans[side]):.3g} m from the nearest bore of "
                                 f"{sh.bore!r} ({side}, y = {lo:.6g}..{hi:.6g} m); it must lie "
                                 f"within one wall thickness ({t!r} m) of a bore: set position = "
                                 f"{centre - sh.y0:.6g} (the {side} bore's middle) or move the "
                                 "shaft's y0"))
            continue
        if (sh.bore, side) in used:
            errs.add(ConfigError(f"{p}.position", f"the {side} bore of {sh.bore!r} already "
                                 f"carries gearbox.bearings[{used[(sh.bore, side)]}]: one "
                                 "bearing per bore"))
            continue
        used[(sh.bore, side)] = i
        points = {w: n for w, _, _, n in bore_walls(housing, bore)}[side]
        if b.elements is not None and b.elements != points:
            errs.add(ConfigError(f"{p}.elements", f"the {side} bore of {sh.bore!r} has "
                                 f"{points} coupling points (housing.bores rolling_elements); "
                                 f"give {points} or leave elements out, got {b.elements}"))
    L, W, H = housing.length, housing.width, housing.height
    for k, g in enumerate(cfg.gears):
        p = f"gearbox.gears[{k}]"
        s = cfg.shaft_index(g.shaft, f"{p}.shaft")
        bore = bores[cfg.shafts[s].bore]
        ra, y = gear_tip_radius(g), cfg.shafts[s].y0 + g.position
        planned = (moved or {}).get(bore.name, (bore.x, bore.z))
        for axis, centre, top, size, goal in (("x", bore.x, L, "length", planned[0]),
                                              ("z", bore.z, H, "height", planned[1])):
            low, high = ra + t - 1e-9, top - t - ra + 1e-9     # where the axis may lie [m]
            if goal != centre and not low <= goal <= high:
                errs.add(ConfigError(f"{p}.teeth", f"with bore {bore.name!r} moved to {axis} = "
                                     f"{goal:.6g} m (the centre distance), the gear tip (radius "
                                     f"{ra:.6g} m) needs housing.{size} >= "
                                     f"{max(goal + ra + t, 2 * (ra + t)):.6g} m"))
            elif centre < low or centre > high:
                into = low - centre if centre < low else centre - high
                where = ("the wall at x = 0" if axis == "x" else "the housing floor") \
                    if centre < low else (f"the wall at x = {L!r}" if axis == "x"
                                          else "the housing top")
                fix = (f"move bore {bore.name!r} to {axis} = {low:.6g} m or more"
                       if centre < low else f"move bore {bore.name!r} to {axis} = "
                       f"{high:.6g} m or less, or make housing.{size} >= "
                       f"{centre + ra + t:.6g} m")
                if low > high:
                    fix = (f"make housing.{size} >= {2 * (ra + t):.6g} m (tip diameter + two "
                           f"walls) and move bore {bore.name!r} to {axis} >= {ra + t:.6g} m")
                errs.add(ConfigError(f"{p}.teeth", f"gear tip (radius {ra:.6g} m = pitch "
                                     f"radius + module, axis at {axis} = {centre!r} m) reaches "
                                     f"{into:.3g} m into {where} (cavity {axis} = {t!r}.."
                                     f"{top - t:.6g} m): {fix}"))
        half = 0.5 * g.width
        if y - half < t or y + half > W - t:
            errs.add(ConfigError(f"{p}.position", f"gear face (housing y = {y - half:.6g}.."
                                 f"{y + half:.6g} m) is not inside the cavity (y = {t!r}.."
                                 f"{W - t:.6g} m): set position between "
                                 f"{t + half - cfg.shafts[s].y0:.6g} and "
                                 f"{W - t - half - cfg.shafts[s].y0:.6g} m or move the shaft's "
                                 "y0"))
        for w, yw in enumerate(housing.inner_walls):
            if y - half < yw + 0.5 * t and y + half > yw - 0.5 * t:
                errs.add(ConfigError(f"{p}.position", f"gear face (housing y = {y - half:.6g}.."
                                     f"{y + half:.6g} m) cuts housing.inner_walls[{w}] (y = "
                                     f"{yw - 0.5 * t:.6g}..{yw + 0.5 * t:.6g} m): move the gear "
                                     "or the wall"))
    errs.raise_if()


def _inverse_involute(inv: float) -> float:
    a = (3.0 * inv) ** (1.0 / 3.0)
    for _ in range(50):
        a -= (math.tan(a) - a - inv) / math.tan(a) ** 2
    return a


def working_centre_distance(ga, gb, mesh) -> float:
    """a_w of an external pair [m]: m_n (z_a + z_b) / (2 cos beta), scaled by cos(alpha_t) /
    cos(alpha_wt) when the pair is profile-shifted (ISO 21771)."""
    beta = math.radians(ga.helix_angle)
    a = ga.module * (ga.teeth + gb.teeth) / (2.0 * math.cos(beta))
    shift = mesh.profile_shift_a + mesh.profile_shift_b
    if shift:
        an = math.radians(mesh.pressure_angle)
        at = math.atan(math.tan(an) / math.cos(beta))
        inv = math.tan(at) - at + 2.0 * math.tan(an) * shift / (ga.teeth + gb.teeth)
        a *= math.cos(at) / math.cos(_inverse_involute(inv))
    return a


def check_centre_distances(cfg, housing) -> tuple[dict, ErrorList]:
    """Each mesh's shaft axes must lie its centre distance apart.  The fix moves the axis of
    gear_b's shaft along the line between the axes.  Returns ({bore name: (x, z)} of the
    bores the fixes move, for the fixes of the checks that follow; the errors)."""
    bores = {b.name: b for b in housing.bores} if housing is not None else {}
    errs, moved = ErrorList(), {}
    for i, m in enumerate(cfg.meshes):
        try:
            ga = cfg.gears[cfg.gear_index(m.gear_a, "")]
            gb = cfg.gears[cfg.gear_index(m.gear_b, "")]
            sa = cfg.shafts[cfg.shaft_index(ga.shaft, "")]
            sb = cfg.shafts[cfg.shaft_index(gb.shaft, "")]
        except ConfigError:
            continue                      # reported by [gearbox]'s own checks
        if housing is not None:
            if sa.bore not in bores or sb.bore not in bores or bores[sa.bore].x is None \
                    or bores[sb.bore].x is None:
                continue
            A, B = (bores[sa.bore].x, bores[sa.bore].z), (bores[sb.bore].x, bores[sb.bore].z)
        else:
            if None in (sa.x, sa.z, sb.x, sb.z):
                continue
            A, B = (sa.x, sa.z), (sb.x, sb.z)
        a = working_centre_distance(ga, gb, m)
        d = math.hypot(B[0] - A[0], B[1] - A[1])
        if d == 0.0 or abs(d - a) <= 1e-3 * a:
            continue
        new = (A[0] + (B[0] - A[0]) * a / d, A[1] + (B[1] - A[1]) * a / d)
        what = (f"move bore {sb.bore!r} to x = {new[0]:.6g} m, z = {new[1]:.6g} m"
                if housing is not None else f"set the x, z of shaft {sb.name!r} to "
                f"{new[0]:.6g}, {new[1]:.6g} m")
        if housing is not None:
            moved[sb.bore] = new
        errs.add(ConfigError(f"gearbox.meshes[{i}]", f"{ga.name!r} ({ga.teeth} teeth) and "
                             f"{gb.name!r} ({gb.teeth} teeth) at module {ga.module!r} need "
                             f"their axes {a:.6g} m apart (centre distance m_n (z_a + z_b) / "
                             f"(2 cos beta){'; profile-shifted: on the working pitch circles, a cos(alpha_t) / cos(alpha_wt)' if m.profile_shift_a or m.profile_shift_b else ''}), "
                             f"they are {d:.6g} m apart: {what}"))
    return moved, errs


def _outside(y: float, span: tuple[float, float]) -> float:
    return max(span[0] - y, y - span[1], 0.0)


def _state_count(scene) -> int:
    """An upper estimate of the reduced model's state count (2 per coordinate)."""
    if scene.impact_pair is not None:
        return 2
    n = 0
    if scene.gearbox is not None:
        n += sum(sh.master_count for sh in scene.gearbox.shafts)
        n += sum(1 for g in scene.gearbox.gears if g.free)
    if scene.housing is not None:
        m = scene.housing.modes
        n += m.max_count if m.cutoff_hz is not None else m.count
    return 2 * max(n, 1)


def time_response_bytes(scene) -> int:
    tr = scene.time_response
    samples = math.floor(tr.periods * tr.samples_per_period) + 1
    return samples * _state_count(scene) * 8


def _check_time_response_size(scene) -> None:
    tr = scene.time_response
    need = time_response_bytes(scene)
    if need > MAX_TIME_RESPONSE_BYTES:
        states = _state_count(scene)
        most = MAX_TIME_RESPONSE_BYTES // (8 * states * tr.samples_per_period)
        raise ConfigError("time_response.periods", f"{tr.periods:g} periods x "
                          f"{tr.samples_per_period} samples x ~{states} states need "
                          f"{need / 2**30:.3g} GiB; at most "
                          f"{MAX_TIME_RESPONSE_BYTES / 2**30:g} GiB: periods must be <= {most}")
