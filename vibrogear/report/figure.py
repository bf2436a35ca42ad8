"""Figures without pyplot state: an Agg-backed Figure and saving in several formats."""
from __future__ import annotations

import re
from pathlib import Path

__all__ = ["new_figure", "save_figure", "write_figure", "plain_title", "mode_count_note"]

#: the reduced model's size in a study title, e.g. "two_stage: m = 146 (21+25+100)"
_MODE_COUNT = re.compile(r"[:,]?\s*m = (\d+) \(([\d+]+)\)")


def plain_title(title: str) -> str:
    """``title`` without the reduced model's mode count ``m = 146 (21+25+100)``: that
    count belongs in a figure's caption (:func:`mode_count_note`), not in its title."""
    return _MODE_COUNT.sub("", title or "").strip()


def mode_count_note(title: str) -> str:
    """The caption sentence for the mode count in a study title ("" without one)."""
    m = _MODE_COUNT.search(title or "")
    if m is None:
        return ""
    parts = m.group(2).split("+")
    return (f"Reduced model: m = {m.group(1)} master modes ({' + '.join(parts)}: those of "
            "each subsystem, the shafts first, then the housing where there is one).")


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
