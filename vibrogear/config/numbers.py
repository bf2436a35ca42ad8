"""How numbers, speeds and speed ranges are written for people: significant digits,
plain notation, ranges joined where they touch.  One place for the findings, the console and
the report."""
from __future__ import annotations

import math

__all__ = ["fmt", "fmt_param", "range_text", "merged_ranges"]


def fmt(x: float, digits: int = 2) -> str:
    """``x`` to ``digits`` significant digits, plainly (no exponent for ordinary sizes)."""
    x = float(x)
    if not math.isfinite(x):
        return str(x)
    if x == 0:
        return "0"
    mag = int(math.floor(math.log10(abs(x))))
    if -3 <= mag < 6:
        decimals = max(digits - 1 - mag, 0)
        return f"{x:.{decimals}f}"
    return f"{x:.{digits - 1}e}"


def fmt_param(x: float) -> str:
    """A speed (or Omega) as a reader writes it: 4 significant digits, whole numbers from
    1000 up (4883 rpm, 0.872)."""
    x = float(x)
    return f"{x:.0f}" if abs(x) >= 1000 else f"{x:.4g}"


def range_text(lo: float, hi: float, unit: str) -> str:
    u = f" {unit}" if unit else ""
    if fmt_param(lo) == fmt_param(hi):
        return f"{fmt_param(lo)}{u}"
    return f"{fmt_param(lo)}–{fmt_param(hi)}{u}"


def merged_ranges(bands: list[dict]) -> list[tuple[float, float]]:
    """The union of the bands' [from, to] ranges, merged where they touch or overlap
    (within one grid step)."""
    spans = sorted((b["from"], b["to"], b.get("edge_err", 0.0)) for b in bands)
    out: list[list[float]] = []
    for lo, hi, step in spans:
        if out and lo <= out[-1][1] + 1.01 * step:
            out[-1][1] = max(out[-1][1], hi)
        else:
            out.append([lo, hi])
    return [(a, b) for a, b in out]
