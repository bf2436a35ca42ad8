"""Light animations of the housing surface: one mode shape or the operating deflection shape
swinging through a period, as an animated PNG (APNG) or GIF written by matplotlib's Pillow
writer.  Frame k of ``n_frames`` draws the displacement Re(u exp(2 pi i k / n_frames)) (a
real mode shape: u cos(2 pi k / n_frames)); the colours stay those of the amplitude, so
only the shape moves.  Small on purpose (a 4.8 x 3.8 inch panel at 72 dpi, 16 frames, a
256-colour palette): :data:`MAX_BYTES` is the budget, checked before writing.  Pillow joins
the frames directly instead of matplotlib's ``PillowWriter``, which keeps RGBA frames (its
APNG of the same animation: 3.2x larger, measured on configs/housing_small.toml) and writes in
place; here the file is written atomically.
"""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..plots.housing_surface import agg_pyplot, draw_surface

__all__ = ["animate_surface", "MAX_BYTES"]

#: the size budget of one animation [bytes]
MAX_BYTES = 1_000_000


def animate_surface(path: Path, verts, tris, face_value, displacement, *, title: str,
                    view=(22.0, -65.0), cmap="viridis", norm=None, n_frames: int = 16,
                    fps: int = 10, tags=None, hatch=None) -> Path:
    """Write the animation of ``displacement`` (nv, 3), real or complex, already scaled for
    drawing, to ``path`` (.png: APNG, .gif: GIF); returns the path.  Raises ValueError when
    the file would exceed :data:`MAX_BYTES` (nothing is written then)."""
    from matplotlib import colors
    from PIL import Image

    from ...pipeline.files import atomic_write_bytes

    plt = agg_pyplot()
    disp = np.asarray(displacement)
    norm = norm or colors.Normalize(float(np.min(face_value)), float(np.max(face_value)))
    frames = []
    fig = plt.figure(figsize=(4.8, 3.8))
    for k in range(n_frames):
        fig.clf()
        ax = fig.add_subplot(1, 1, 1, projection="3d")
        phase = np.exp(2j * np.pi * k / n_frames)
        draw_surface(ax, verts, tris, face_value, displacement=np.real(disp * phase), cmap=cmap,
                     norm=norm, view=view, tags=tags, hatch=hatch)
        ax.set_title(title, fontsize=8)
        fig.subplots_adjust(left=0, right=1, bottom=0, top=0.88)
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=72)
        buf.seek(0)
        frames.append(Image.open(buf).convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT))
    plt.close(fig)
    out = io.BytesIO()
    path = Path(path)
    fmt = "GIF" if path.suffix.lower() == ".gif" else "PNG"
    frames[0].save(out, format=fmt, save_all=True, append_images=frames[1:],
                   duration=int(1000 / fps), loop=0, optimize=True)
    data = out.getvalue()
    if len(data) > MAX_BYTES:
        raise ValueError(f"animation {path.name}: {len(data):,} bytes exceed the budget of "
                         f"{MAX_BYTES:,}")
    return atomic_write_bytes(path, data)
