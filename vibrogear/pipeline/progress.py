"""A small progress bar with rate and ETA, silent when not on a terminal or when quiet."""
from __future__ import annotations

import sys
import time

__all__ = ["Progress", "null_progress"]


class Progress:
    """``with Progress(total, label) as bar: bar.update(1)``; draws only on a TTY."""

    def __init__(self, total: int, label: str = "", *, quiet: bool = False, stream=None):
        self.total = max(int(total), 1)
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = (not quiet) and hasattr(self.stream, "isatty") and self.stream.isatty()
        self.done = 0
        self._t0 = time.perf_counter()
        self._last = 0.0

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def update(self, n: int = 1, info: str = "") -> None:
        self.done += n
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last < 0.1 and self.done < self.total:
            return
        self._last = now
        elapsed = now - self._t0
        rate = self.done / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else float("inf")
        frac = min(self.done / self.total, 1.0)
        width = 28
        bar = "#" * int(frac * width) + "-" * (width - int(frac * width))
        eta_s = f"{eta:5.0f}s" if eta != float("inf") else "    ?"
        self.stream.write(f"\r{self.label:<14} [{bar}] {self.done}/{self.total} "
                          f"{rate:6.1f}/s ETA {eta_s} {info[:30]:<30}")
        self.stream.flush()

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()
            self.enabled = False


def null_progress(total: int, label: str = "") -> Progress:
    return Progress(total, label, quiet=True)
