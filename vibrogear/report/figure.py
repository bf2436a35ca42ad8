"""Figures without pyplot state: an Agg-backed Figure and saving in several formats."""
from __future__ import annotations

from pathlib import Path

__all__ = ["new_figure", "save_figure", "write_figure"]


def new_figure(figsize=(8.0, 5.0)):
    """A matplotlib Figure on its own Agg canvas (no global pyplot state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path, formats=("png", "svg"), dpi: int = 150, *,
                tight: bool = True) -> list[Path]:
    """Write ``fig`` as ``path`` with each suffix in ``formats``; returns the paths."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if tight:
        fig.tight_layout()
    return [write_figure(fig, path.with_suffix("." + fmt), dpi=dpi) for fmt in formats]


def write_figure(fig, path, dpi: int = 150) -> Path:
    """``fig.savefig`` into memory, then written atomically (pipeline/files.py): a figure is
    whole or absent, also on a full disk."""
    import io

    from ..pipeline.files import atomic_write_bytes

    path = Path(path)
    buf = io.BytesIO()
    fig.savefig(buf, dpi=dpi, format=path.suffix.lstrip(".") or "png")
    return atomic_write_bytes(path, buf.getvalue())
