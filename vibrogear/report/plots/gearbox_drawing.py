"""A to-scale drawing of a gearbox scene: ``gearbox.png`` (side view and end view, in mm).

Read from the scene's configuration alone (:mod:`vibrogear.config.model.gearbox`,
:mod:`vibrogear.config.model.housing`), nothing computed:

* **side view** (left): the shafts' axes run left to right (housing y, the front wall at
  y = 0); the vertical axis is the housing coordinate across the shafts in which their axes
  lie furthest apart (x: seen from above; z: seen from the side).  Each shaft section is a
  rectangle of its length and outer diameter; each gear a rectangle of its face width and
  pitch diameter (free gears hatched); each rolling bearing the usual crossed square, from
  the shaft's surface to the bore (without a housing: half the shaft diameter deep); each
  external coupling a box labelled motor or load.  A parametric housing is drawn as a
  section through the shaft axes: its walls, the bearing bosses and the bores.
* **end view** (right): a section at the housing's mid-width, seen along the shafts
  (x right, z up): the housing walls and base plate or feet, each bore and boss (dashed:
  they are in the walls in front of and behind the section), each gear's pitch circle and
  each shaft's largest section.

The drawing's shapes are computed first as plain numbers (:func:`gearbox_layout`), in
millimetres in the coordinates of each view, so that a test can compare them with the
configuration (a spur gear's pitch radius is teeth x module / 2); :func:`draw_gearbox`
draws exactly those shapes.  Bearing widths are not part of the scene, so a bearing's width
in the side view is a symbol's, not a dimension.  An imported housing (STEP, mesh or modal
file) has no outline in the scene: only its bores are drawn, and the drawing says so.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..figure import new_figure, save_figure

__all__ = ["Shape", "Layout", "gearbox_layout", "figure_of", "draw_gearbox"]

_MM = 1e3


@dataclass(frozen=True)
class Shape:
    """One drawn shape in millimetres: a rectangle [x0, x1] x [y0, y1] or a circle whose
    bounding box that is (centre and radius below)."""
    kind: str        # shaft, gear, bearing, coupling, housing, cavity, boss, bore, base
    name: str
    view: str        # "side" or "end"
    form: str        # "rect" or "circle"
    x0: float
    x1: float
    y0: float
    y1: float
    free: bool = False

    @property
    def centre(self) -> tuple[float, float]:
        return 0.5 * (self.x0 + self.x1), 0.5 * (self.y0 + self.y1)

    @property
    def radius(self) -> float:
        return 0.5 * (self.x1 - self.x0)


@dataclass(frozen=True)
class Layout:
    shapes: tuple[Shape, ...]
    across: str      # housing coordinate on the side view's vertical axis ("x" or "z")
    note: str        # what is not drawn, if anything

    def of(self, kind: str, view: str | None = None) -> list[Shape]:
        return [s for s in self.shapes if s.kind == kind and (view is None or s.view == view)]


def _rect(kind, name, view, x0, x1, y0, y1, free=False) -> Shape:
    return Shape(kind, name, view, "rect", _MM * min(x0, x1), _MM * max(x0, x1),
                 _MM * min(y0, y1), _MM * max(y0, y1), free)


def _circle(kind, name, cx, cy, r, free=False) -> Shape:
    return Shape(kind, name, "end", "circle", _MM * (cx - r), _MM * (cx + r), _MM * (cy - r),
                 _MM * (cy + r), free)


def _axes(scene) -> dict[str, tuple[float, float]]:
    """Housing-frame (x, z) of each shaft's axis: its bore's, or its own x, z."""
    bores = {b.name: b for b in (scene.housing.bores if scene.housing is not None else ())}
    out = {}
    for sh in scene.gearbox.shafts:
        b = bores.get(sh.bore) or next((v for k, v in bores.items()        # one bore per wall
                                        if k.rpartition("/")[0] == sh.bore), None)
        if b is not None and b.x is not None and b.z is not None:
            out[sh.name] = (b.x, b.z)
        elif sh.x is not None and sh.z is not None:
            out[sh.name] = (sh.x, sh.z)
        else:
            raise ValueError(f"gearbox.shafts: shaft {sh.name!r} has no axis (no bore with "
                             "x, z and no x, z of its own)")
    return out


def _housing_shapes(h, across: str) -> list[Shape]:
    """The parametric housing: side-view section through the shaft axes, end-view section
    at mid-width."""
    L, W, H, t = h.length, h.width, h.height, h.wall_thickness
    span = L if across == "x" else H
    s = [_rect("housing", "housing", "side", 0.0, W, 0.0, span),
         _rect("cavity", "cavity", "side", t, W - t, t, span - t),
         _rect("housing", "housing", "end", 0.0, L, 0.0, H),
         _rect("cavity", "cavity", "end", t, L - t, t, H - t)]
    tb, o = h.base_thickness, h.base_overhang
    if h.base == "plate":
        s.append(_rect("base", "base plate", "end", -o, L + o, -tb, 0.0))
        if across == "z":
            s.append(_rect("base", "base plate", "side", -o, W + o, -tb, 0.0))
    elif h.base == "feet":
        f = h.foot_size
        s += [_rect("base", "foot", "end", x, x + f, -tb, 0.0) for x in (0.0, L - f)]
        if across == "z":
            s += [_rect("base", "foot", "side", y, y + f, -tb, 0.0) for y in (0.0, W - f)]
    for b in h.bores:
        c = b.x if across == "x" else b.z
        R = b.boss_radius if b.boss_radius is not None else b.bore_radius
        lb = b.boss_length
        if lb > 0:
            s += [_rect("boss", b.name, "side", -lb, 0.0, c - R, c + R),
                  _rect("boss", b.name, "side", W, W + lb, c - R, c + R)]
        s.append(_rect("bore", b.name, "side", -lb, W + lb, c - b.bore_radius,
                       c + b.bore_radius))
        s += [_circle("boss", b.name, b.x, b.z, R),
              _circle("bore", b.name, b.x, b.z, b.bore_radius)]
    return s


def gearbox_layout(scene) -> Layout:
    """The shapes of the drawing (module docstring) of ``scene`` (a loaded Scene with a
    ``gearbox`` section), in millimetres."""
    gb = scene.gearbox
    if gb is None:
        raise ValueError("gearbox_layout: the scene has no [gearbox] section")
    axes = _axes(scene)
    xs = [a[0] for a in axes.values()]
    zs = [a[1] for a in axes.values()]
    across = "x" if max(xs) - min(xs) >= max(zs) - min(zs) else "z"
    c_of = {n: (a[0] if across == "x" else a[1]) for n, a in axes.items()}
    shafts = {sh.name: sh for sh in gb.shafts}
    h = scene.housing
    parametric = h is not None and h.source == "parametric"
    shapes: list[Shape] = _housing_shapes(h, across) if parametric else []
    note = ""
    if h is not None and not parametric:
        note = f"{h.source} housing: its outline is in its file and not drawn; bores only"
        for b in h.bores:
            if b.x is not None and b.z is not None:
                shapes.append(_circle("bore", b.name, b.x, b.z, b.bore_radius))
    bore_r = {b.name: b.bore_radius for b in (h.bores if h is not None else ())}
    for sh in gb.shafts:
        c, y = c_of[sh.name], sh.y0
        start = 0.0
        for k, sec in enumerate(sh.sections):
            end = start + sec.length
            r = 0.5 * sec.outer_diameter
            shapes.append(_rect("shaft", f"{sh.name}[{k}]", "side", y + start, y + end,
                                c - r, c + r))
            start = end
        r_max = 0.5 * max(sec.outer_diameter for sec in sh.sections)
        shapes.append(_circle("shaft", sh.name, *axes[sh.name], r_max))
    for g in gb.gears:
        sh = shafts[g.shaft]
        c, yc, rp = c_of[g.shaft], sh.y0 + g.position, 0.5 * g.pitch_diameter
        shapes.append(_rect("gear", g.name, "side", yc - 0.5 * g.width, yc + 0.5 * g.width,
                            c - rp, c + rp, g.free))
        shapes.append(_circle("gear", g.name, *axes[g.shaft], rp, g.free))
    for b in gb.bearings:
        sh = shafts[b.shaft]
        r_in = 0.5 * _diameter_at(sh, b.position)
        r_out = bore_r.get(sh.bore, 0.0)
        if not r_out > r_in:
            r_out = 1.5 * r_in
        d = r_out - r_in
        c, yb = c_of[b.shaft], sh.y0 + b.position
        shapes += [_rect("bearing", b.name, "side", yb - 0.5 * d, yb + 0.5 * d, c + r_in,
                         c + r_out),
                   _rect("bearing", b.name, "side", yb - 0.5 * d, yb + 0.5 * d, c - r_out,
                         c - r_in)]
    for cp in gb.couplings:
        sh = shafts[cp.shaft]
        r = 0.5 * _diameter_at(sh, cp.position)
        c, yc = c_of[cp.shaft], sh.y0 + cp.position
        name = cp.name if cp.name == cp.role else f"{cp.name} ({cp.role})"
        shapes.append(_rect("coupling", name, "side", yc - 1.2 * r,
                            yc + 1.2 * r, c - 1.6 * r, c + 1.6 * r))
    return Layout(tuple(shapes), across, note)


def _diameter_at(shaft, position: float) -> float:
    """Outer diameter of the section at ``position`` along the shaft (the larger one at a
    section boundary)."""
    start, best = 0.0, 0.0
    tol = 1e-9 * sum(s.length for s in shaft.sections)
    for sec in shaft.sections:
        end = start + sec.length
        if start - tol <= position <= end + tol:
            best = max(best, sec.outer_diameter)
        start = end
    return best or shaft.sections[-1].outer_diameter


_FILL = {"housing": "0.72", "base": "0.55", "boss": "0.72", "cavity": "white", "bore": "white",
         "shaft": "#8fa8c8", "gear": "#e3b04b", "bearing": "white", "coupling": "#9ccc9c"}
_Z = {"base": 1, "boss": 1, "housing": 1, "cavity": 2, "bore": 3, "shaft": 4, "gear": 5,
      "bearing": 6, "coupling": 6}


def _patch(s: Shape, view: str):
    from matplotlib.patches import Circle, Rectangle

    gid = f"{s.kind}:{s.name}:{view}"
    if s.form == "circle":
        dashed = s.kind in ("bore", "boss")
        return Circle(s.centre, s.radius, fill=s.kind in ("gear", "shaft"),
                      fc=_FILL[s.kind], ec="k", lw=0.8, ls="--" if dashed else "-",
                      alpha=0.55 if s.kind == "gear" else 1.0, zorder=_Z[s.kind], gid=gid,
                      hatch="//" if s.free else None)
    return Rectangle((s.x0, s.y0), s.x1 - s.x0, s.y1 - s.y0, fc=_FILL[s.kind],
                     ec="none" if s.kind in ("cavity", "bore") else "k", lw=0.7,
                     zorder=_Z[s.kind], gid=gid, hatch="//" if s.free else None)


def _bearing_cross(ax, s: Shape) -> None:
    ax.plot([s.x0, s.x1], [s.y0, s.y1], "k", lw=0.6, zorder=7)
    ax.plot([s.x0, s.x1], [s.y1, s.y0], "k", lw=0.6, zorder=7)


def _label(ax, text, x, y, **kw) -> None:
    ax.annotate(text, (x, y), fontsize=7, ha="center", zorder=9,
                bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8), **kw)


def _scale_bar(ax, length_mm: float) -> None:
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    x, y = x0 + 0.04 * (x1 - x0), y0 + 0.04 * (y1 - y0)
    ax.plot([x, x + length_mm], [y, y], "k", lw=2.0, zorder=9)
    ax.annotate(f"{length_mm:g} mm", (x + 0.5 * length_mm, y), xytext=(0, 3),
                textcoords="offset points", ha="center", fontsize=7)


def figure_of(scene, load_path: dict | None = None):
    """The matplotlib Figure of the drawing (each patch's gid: ``kind:name:view``);
    ``load_path``: ``summary["load_path"]``, drawn on the side view as the power flow (each
    mesh a line between its gears' centres at its axial position, with its tooth force and
    power; idle meshes dashed)."""
    lay = gearbox_layout(scene)
    views = {v: [s for s in lay.shapes if s.view == v] for v in ("side", "end")}
    box = {}
    for v, shapes in views.items():
        x0, x1 = min(s.x0 for s in shapes), max(s.x1 for s in shapes)
        y0, y1 = min(s.y0 for s in shapes), max(s.y1 for s in shapes)
        pad = 0.08 * max(x1 - x0, y1 - y0)
        box[v] = (x0 - pad, x1 + pad, y0 - pad, y1 + pad)
    height = max(b[3] - b[2] for b in box.values())
    widths = [box[v][1] - box[v][0] for v in ("side", "end")]
    fig = new_figure((11.0, max(3.5, 10.0 * height / sum(widths)) + 0.8))
    axs = fig.subplots(1, 2, gridspec_kw={"width_ratios": widths})
    for ax, v in zip(axs, ("side", "end")):
        x0, x1, y0, y1 = box[v]
        mid = 0.5 * (y0 + y1)
        ax.set_xlim(x0, x1)
        ax.set_ylim(mid - 0.5 * height, mid + 0.5 * height)    # one scale for both views
        ax.set_aspect("equal")
        for s in views[v]:
            ax.add_patch(_patch(s, v))
            if s.kind == "bearing":
                _bearing_cross(ax, s)
        ax.tick_params(labelsize=7)
        _scale_bar(ax, 50.0)
    side, end = axs
    seen = set()
    for s in views["side"]:
        cx, _ = s.centre
        if s.kind == "gear":
            txt = f"{s.name}" + (" (free)" if s.free else "")
            _label(side, txt, cx, s.y1, xytext=(0, 3), textcoords="offset points")
        elif s.kind == "bearing" and s.name not in seen:
            seen.add(s.name)
            _label(side, s.name, cx, s.y1, xytext=(0, 3), textcoords="offset points")
        elif s.kind == "coupling":
            _label(side, s.name, cx, s.y0, xytext=(0, -9), textcoords="offset points")
    gears = {g.name: g for g in scene.gearbox.gears}
    for s in views["end"]:
        if s.kind == "gear":
            g = gears[s.name]
            cx, cy = s.centre
            # inside its own circle's top (a free gear: bottom), so coaxial gears'
            # labels sit at their own radii
            helix = f", helix {g.helix_angle:g}\u00b0" if g.helix_angle else ""
            _label(end, f"{g.name}: {g.teeth} teeth, m {g.module * _MM:g} mm{helix}", cx,
                   cy - s.radius if g.free else cy + s.radius, xytext=(0, 3 if g.free else -10),
                   textcoords="offset points")
    if load_path:
        _power_flow(side, views["side"], scene, load_path)
    side.set_xlabel("y along the shafts [mm] (front wall at 0)", fontsize=8)
    seen_from = "from above" if lay.across == "x" else "from the side"
    side.set_ylabel(f"{lay.across} [mm] (seen {seen_from})", fontsize=8)
    side.set_title("side view: section through the shaft axes" if scene.housing is not None
                   else "side view: the plane of the shaft axes", fontsize=9)
    end.set_xlabel("x [mm]", fontsize=8)
    end.set_ylabel("z (up) [mm]", fontsize=8)
    end.set_title("end view: section at mid-width (bores dashed)" if scene.housing is not None
                  else "end view: along the shafts", fontsize=9)
    name = getattr(getattr(scene, "scene", None), "name", "") or scene.gearbox.name
    fig.suptitle(f"{name}: the gearbox to scale (shafts, gears at their pitch diameter, "
                 "bearings, couplings" + (", housing)" if scene.housing is not None else ")")
                 + (f"\n{lay.note}" if lay.note else ""), fontsize=9)
    return fig


def _power_flow(ax, shapes, scene, load_path: dict) -> None:
    """Per mesh of the load path: a line between the two gears' centres in the side view
    (across the shafts at the mesh's axial position), labelled with the static tooth force
    and the power (loaded, solid) or "idle" (dashed)."""
    centre = {s.name: s.centre for s in shapes if s.kind == "gear"}
    gears = {m.name: (m.gear_a, m.gear_b) for m in scene.gearbox.meshes}
    for m in load_path.get("meshes", []) or []:
        a, b = gears.get(m.get("name"), (None, None))
        if a not in centre or b not in centre:
            continue
        (xa, ya), (xb, yb) = centre[a], centre[b]
        idle = m.get("role") == "idle"
        ax.plot([xa, xb], [ya, yb], color="tab:red", lw=1.2, ls="--" if idle else "-",
                zorder=8, gid=f"power:{m['name']}")
        force, power = m.get("normal_force_N"), m.get("power_kW")
        text = f"{m['name']}: idle" if idle else f"{m['name']}: " + ", ".join(
            t for t in (f"F_n {force / 1e3:.3g} kN" if force is not None else "",
                        f"{power:.3g} kW" if power is not None else "") if t)
        ax.annotate(text, (0.5 * (xa + xb), 0.5 * (ya + yb)), xytext=(4, 0),
                    textcoords="offset points", fontsize=7, ha="left", va="center",
                    zorder=8.5, color="tab:red", rotation=90,
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))


def draw_gearbox(scene_config, path, load_path: dict | None = None) -> Path:
    """Draw ``scene_config`` (a loaded scene with a ``[gearbox]``) to scale as a PNG at
    ``path`` (suffix .png added when missing), with the power flow of ``load_path``
    (``summary["load_path"]``) where given; returns the path written."""
    path = Path(path)
    fig = figure_of(scene_config, load_path)
    return save_figure(fig, path.with_suffix(".png"), formats=("png",))[0]
