"""Shaded pictures of the housing surface: deformed mode shapes and the operating deflection
shape (surface velocity) at the ERP peak.

Takes plain arrays (the boundary surface carried by
:class:`~vibrogear.models.housing.result.HousingModes`, the outer surface of the ERP) and
draws them with matplotlib's ``Poly3DCollection``: each triangle coloured by a scalar
(displacement magnitude, velocity level), shaded by a fixed light (Lambert), faces turned
away from the camera left out (the surface is closed, so they are hidden anyway and the
painter's sort has less to get wrong), the undeformed feature edges as a thin wireframe on
top, the bores ringed and numbered, the supported faces hatched.  The camera looks along
the outward normal of the region that moves most, turned 25 degrees sideways and raised
22 degrees so that the box reads as a solid.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from ...models.housing.surface_mesh import outer_skin
from ..figure import new_figure

__all__ = ["view_angles", "feature_edges", "face_normals", "draw_surface", "plot_mode_shapes",
           "plot_surface_field", "mode_panel_data", "DEFAULT_FRACTION", "vertex_normal_field",
           "ods_drawing"]

#: the largest displacement of a drawn mode, as a fraction of the box's largest edge
DEFAULT_FRACTION = 0.06
_LIGHT = np.array([-0.4, -0.5, 0.77])


def agg_pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def view_angles(normal) -> tuple[float, float]:
    """(elev, azim) in degrees of a camera that looks at a face with outward ``normal``:
    from the normal's side, turned 25 degrees and raised 22 (from above or below for a
    horizontal face)."""
    n = np.asarray(normal, float)
    n = n / max(np.linalg.norm(n), 1e-300)
    if abs(n[2]) > 0.8:
        return (55.0 if n[2] > 0 else -35.0), -60.0
    return 22.0, float(np.degrees(np.arctan2(n[1], n[0]))) + 25.0


def camera_direction(elev: float, azim: float) -> np.ndarray:
    """Unit vector from the scene towards matplotlib's camera at (elev, azim)."""
    e, a = np.radians(elev), np.radians(azim)
    return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


def face_normals(verts: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Unit normals (nt, 3) of the triangles (b - a) x (c - a)."""
    p = verts[tris]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def feature_edges(verts: np.ndarray, tris: np.ndarray, *, angle_deg: float = 30.0,
                  faces: np.ndarray | None = None) -> np.ndarray:
    """Segments (ne, 2, 3) of the edges where the surface folds by more than ``angle_deg``
    (and open boundary edges); with ``faces`` (bool mask) only edges next to such a face."""
    tris = np.asarray(tris)
    nrm = face_normals(verts, tris)
    e = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    owner = np.tile(np.arange(len(tris)), 3)
    key, inv, count = np.unique(e, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    first = np.full(len(key), -1)
    second = np.full(len(key), -1)
    order = np.argsort(inv, kind="stable")
    starts = np.searchsorted(inv[order], np.arange(len(key)))
    first[:] = owner[order[starts]]
    has2 = count >= 2
    second[has2] = owner[order[starts[has2] + 1]]
    cosang = np.where(has2, np.einsum("ij,ij->i", nrm[first], nrm[np.maximum(second, 0)]), -1.0)
    sel = cosang < np.cos(np.radians(angle_deg))
    if faces is not None:
        sel &= faces[first] | (has2 & faces[np.maximum(second, 0)])
    return verts[key[sel]]


def _shade(rgba: np.ndarray, normals: np.ndarray, cam: np.ndarray) -> np.ndarray:
    light = _LIGHT + 0.6 * cam
    light = light / np.linalg.norm(light)
    k = 0.55 + 0.45 * np.clip(normals @ light, -1.0, 1.0)     # wrapped: no two sides alike
    out = rgba.copy()
    out[:, :3] *= k[:, None]
    return out


def draw_surface(ax, verts, tris, face_value, *, displacement=None, cmap="viridis", norm=None,
                 view=(22.0, -65.0), shade: bool = True, cull: bool = True, hatch=None,
                 outline: bool = True, tags=None):
    """Draw the triangles ``tris`` of ``verts`` (+ ``displacement``) on the 3D axes ``ax``
    coloured by ``face_value`` (nt,) through ``cmap`` / ``norm``; returns the
    Poly3DCollection of the coloured faces (its face count: the faces drawn)."""
    import matplotlib
    from matplotlib import colors
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    verts = np.asarray(verts, float)
    tris = np.asarray(tris)
    moved = verts + (0.0 if displacement is None else np.asarray(displacement, float))
    cam = camera_direction(*view)
    nrm = face_normals(moved, tris)
    front = (nrm @ cam > 0.0) if cull else np.ones(len(tris), bool)
    norm = norm or colors.Normalize(float(np.min(face_value)), float(np.max(face_value)))
    rgba = matplotlib.colormaps[cmap](norm(np.asarray(face_value, float)))
    if shade:
        rgba = _shade(rgba, nrm, cam)
    ax.computed_zorder = False
    if hatch is not None:                                   # supported faces: light grey
        rgba[hatch] = _shade(np.tile([0.82, 0.82, 0.82, 1.0], (int(hatch.sum()), 1)), nrm[hatch], cam) \
            if shade else (0.82, 0.82, 0.82, 1.0)
    # edges in the face colour hide the seams of antialiased neighbours
    coll = Poly3DCollection(moved[tris[front]], facecolors=rgba[front], edgecolors=rgba[front],
                            linewidths=0.25, zorder=1)
    ax.add_collection3d(coll)
    if hatch is not None and np.any(hatch & front):
        hc = Poly3DCollection(moved[tris[hatch & front]], facecolors=(0, 0, 0, 0),
                              edgecolors="0.3", linewidths=0.0, hatch="//////", zorder=2)
        ax.add_collection3d(hc)
    if outline:
        outer = outer_skin(verts, tris, tags)
        seg = feature_edges(verts, tris, faces=(face_normals(verts, tris) @ cam > 0.0) & outer)
        ax.add_collection3d(Line3DCollection(seg, colors="0.15", linewidths=0.35, alpha=0.7,
                                             zorder=3))
    lo, hi = np.minimum(verts.min(0), moved.min(0)), np.maximum(verts.max(0), moved.max(0))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(np.maximum(hi - lo, 1e-9 * float(np.max(hi - lo))))
    ax.view_init(*view)
    ax.set_axis_off()
    return coll


def _bore_rings(ax, verts, tris, tags, n_bores: int, cam) -> None:
    """A black ring at the outer end of each bore (tag 2 + b) that faces the camera ``cam``
    (unit vector towards it), and its number."""
    for b in range(n_bores):
        sel = np.unique(tris[tags == 2 + b])
        if sel.size < 3:
            continue
        p = verts[sel]
        c = p.mean(axis=0)
        _, _, vt = np.linalg.svd(p - c, full_matrices=False)
        ax_dir = vt[2]                                     # the bore axis: least spread
        s = (p - c) @ ax_dir
        r = float(np.median(np.linalg.norm((p - c) - np.outer(s, ax_dir), axis=1)))
        # the outer end: the one farther from the centre of the whole surface
        outward = (c - verts.mean(axis=0)) @ ax_dir >= 0
        out_end = s.max() if outward else s.min()
        if (ax_dir if outward else -ax_dir) @ cam <= 0.0:       # on the far side: hidden
            continue
        th = np.linspace(0, 2 * np.pi, 49)
        ring = c + out_end * ax_dir + r * (np.outer(np.cos(th), vt[0]) + np.outer(np.sin(th), vt[1]))
        ax.plot(ring[:, 0], ring[:, 1], ring[:, 2], color="k", lw=1.1, zorder=4)
        tip = c + out_end * ax_dir + 1.3 * r * vt[0]
        ax.text(*tip, str(b + 1), fontsize=7, color="k", zorder=5)


def mode_panel_data(res, i: int, fraction: float = DEFAULT_FRACTION, motion=None):
    """(displacement (nv, 3) scaled so its largest vertex value is ``fraction`` of the box's
    largest edge, face colour value (nt,): mean vertex |u| / max |u|, view, title) of mode
    ``i``; ``motion``: ``res.mode_motion()`` (labels, regions), computed when not given."""
    verts, tris = res.shape_vertices, res.shape_triangles
    u = np.asarray(res.shape_values[:, :, i], float)
    mag = np.linalg.norm(u, axis=1)
    top = max(float(mag.max()), 1e-300)
    span = float(np.ptp(verts, axis=0).max())
    labels, regions = motion if motion is not None else res.mode_motion()
    view = view_angles(res.region_normals[int(regions[i])]) if len(res.region_normals) else (22.0, -65.0)
    title = f"mode {i + 1}: {res.freqs_hz[i]:.4g} Hz" + (f"\n{labels[i]}" if labels[i] else "")
    return fraction * span / top * u, mag[tris].mean(axis=1) / top, view, title


#: resolution the surface figures are saved at (:func:`~.figure.write_figure`)
DPI = 100


def plot_mode_shapes(res, modes: Sequence[int], *, fraction: float = DEFAULT_FRACTION,
                     title: str = ""):
    """One Figure of the 0-based ``modes`` (up to 6 panels, 3 per row): each deformed on the
    housing's boundary surface, coloured by |u| / max |u|, with one colour bar (the report
    writer saves it at :data:`DPI`)."""
    import mpl_toolkits.mplot3d  # noqa: F401  (the "3d" projection)
    from matplotlib import cm, colors

    modes = list(modes)
    cols = min(3, len(modes))
    rows = -(-len(modes) // cols)
    fig = new_figure((4.4 * cols + 0.8, 4.0 * rows + 0.7))
    hatch = hatched_faces(res.shape_triangles, res.shape_facet_tag)
    norm = colors.Normalize(0.0, 1.0)
    axes = []
    motion = res.mode_motion()
    for k, i in enumerate(modes):
        ax = fig.add_subplot(rows, cols, k + 1, projection="3d")
        disp, val, view, ttl = mode_panel_data(res, i, fraction, motion)
        draw_surface(ax, res.shape_vertices, res.shape_triangles, val, displacement=disp,
                     norm=norm, view=view, hatch=hatch, tags=res.shape_facet_tag)
        _bore_rings(ax, res.shape_vertices, res.shape_triangles, res.shape_facet_tag,
                    len(res.bore_names), camera_direction(*view))
        ax.set_title(ttl, fontsize=9)
        axes.append(ax)
    span = float(np.ptp(res.shape_vertices, axis=0).max())
    fig.colorbar(cm.ScalarMappable(norm=norm, cmap="viridis"), ax=axes, shrink=0.6, pad=0.02,
                 label="|u| / max |u| of the mode")
    fig.suptitle(title or (f"housing mode shapes (P{res.degree}, {res.n_dofs:,} DOF): largest "
                           f"displacement drawn as {100 * fraction:.0f} % of the box "
                           f"({span:.3g} m); numbered rings: bores; hatched: supported faces\n"
                           + _wall_key(res.region_normals, getattr(res, "region_names", ()))), fontsize=10)
    return fig


def _wall_key(normals, names=()) -> str:
    """Where the named walls are and which bores sit in them (an inner wall's bores, named
    ``.../inner<k>)``, and the inner-wall regions after the bores, in none of them)."""
    normals = np.asarray(normals, float)
    if len(normals) < 6:
        return ""
    owner = np.argmax(normals[6:] @ normals[:6].T, axis=1) if len(normals) > 6 else np.zeros(0, int)
    for j, n in enumerate(names[6:]):
        if not n.startswith("bore ") or "/inner" in n:
            owner[j] = -1
    parts = []
    for k, (name, where) in enumerate(zip(("left end", "right end", "front", "back"),
                                          ("x min", "x max", "y min", "y max"))):
        bores = ", ".join(str(b + 1) for b in np.flatnonzero(owner == k))
        parts.append(f"{name} wall at {where}" + (f" (bores {bores})" if bores else ""))
    return "; ".join(parts) + "; base at z min, top wall at z max"


def hatched_faces(tris, tags) -> np.ndarray:
    """The supported faces (tag 1) and the faces that touch them."""
    tags = np.asarray(tags)
    fixed_nodes = np.unique(tris[tags == 1])
    return (tags == 1) | np.isin(tris, fixed_nodes).any(axis=1)


def plot_surface_field(verts, tris, face_value, *, displacement=None, label: str,
                       title: str, view=(22.0, -65.0), cmap="inferno", vmin=None, vmax=None):
    """One shaded panel of a field per face (e.g. the velocity level, dB) with a colour bar,
    a Figure (the report writer saves it at :data:`DPI`)."""
    import mpl_toolkits.mplot3d  # noqa: F401  (the "3d" projection)
    from matplotlib import cm, colors

    fig = new_figure((7.5, 5.6))
    ax = fig.add_subplot(1, 1, 1, projection="3d")
    v = np.asarray(face_value, float)
    norm = colors.Normalize(float(np.min(v) if vmin is None else vmin),
                            float(np.max(v) if vmax is None else vmax))
    draw_surface(ax, verts, tris, v, displacement=displacement, cmap=cmap, norm=norm, view=view)
    fig.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, shrink=0.7, pad=0.02, label=label)
    ax.set_title(title, fontsize=9)
    return fig


def vertex_normal_field(verts, tris, mid_values) -> tuple[np.ndarray, np.ndarray]:
    """(value per vertex (nv, ...), unit vertex normals (nv, 3)) from values at the triangles'
    edge midpoints (nt, 3, ...) in the order (a, b), (b, c), (c, a): each vertex takes the mean
    of the midpoints on its edges; normals are area-weighted."""
    verts, tris = np.asarray(verts, float), np.asarray(tris)
    mid = np.asarray(mid_values)
    acc = np.zeros((len(verts),) + mid.shape[2:], dtype=mid.dtype)
    cnt = np.zeros(len(verts))
    for q, (i, j) in enumerate(((0, 1), (1, 2), (2, 0))):
        for corner in (i, j):
            np.add.at(acc, tris[:, corner], mid[:, q])
            np.add.at(cnt, tris[:, corner], 1.0)
    p = verts[tris]
    fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    vn = np.zeros_like(verts)
    for c in range(3):
        np.add.at(vn, tris[:, c], fn)
    vn /= np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-300)
    return acc / np.maximum(cnt, 1.0).reshape((-1,) + (1,) * (acc.ndim - 1)), vn


def ods_drawing(verts, tris, mid_values, modal_velocity, omega: float, *,
                fraction: float = DEFAULT_FRACTION):
    """(complex displacement (nv, 3) along the vertex normals, scaled so its largest amplitude
    is ``fraction`` of the box, view) of the harmonic whose modal velocity amplitudes are
    ``modal_velocity`` (m,) at ``omega`` [rad/s]; ``mid_values`` (nt, 3, m) the modes' normal
    displacement at the edge midpoints.  The camera faces the side whose faces carry the most
    area x |v|^2."""
    v_mid = np.asarray(mid_values) @ np.asarray(modal_velocity)          # (nt, 3) complex
    v_vert, vn = vertex_normal_field(verts, tris, v_mid)
    w = v_vert / (1j * omega)                                             # displacement
    top = max(float(np.abs(w).max()), 1e-300)
    span = float(np.ptp(np.asarray(verts), axis=0).max())
    disp = (fraction * span / top) * w[:, None] * vn
    fnrm = face_normals(np.asarray(verts, float), np.asarray(tris))
    p = np.asarray(verts)[tris]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    power = area * np.mean(np.abs(v_mid) ** 2, axis=1)
    dirs = np.vstack([np.eye(3), -np.eye(3)])
    side = int(np.argmax([(power * (fnrm @ d > 0.9)).sum() for d in dirs]))
    return disp, view_angles(dirs[side])
