"""Progress bars (tqdm) with rate and ETA, silent when not on a terminal or when quiet.

Many totals are caps (a continuation's ``max_points``, an optimiser's ``budget``, an
estimate of a run-up's chunks): a bar that finishes (its ``with`` block ends without an
exception) ends at the count it reached, drawn full (``167/167``), so a finished run never
looks interrupted; an interrupted one keeps its cap (``167/300``)."""
from __future__ import annotations

import sys

__all__ = ["Progress", "null_progress"]


class Progress:
    """``with Progress(total, label) as bar: bar.update(1, info)``; draws only on a TTY.
    A thin wrapper of :class:`tqdm.tqdm` that keeps the analyses' interface (``update``
    with an info text, ``done``, ``close``)."""

    def __init__(self, total: int, label: str = "", *, quiet: bool = False, stream=None):
        self.total = max(int(total), 1)
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = (not quiet) and hasattr(self.stream, "isatty") and self.stream.isatty()
        self.done = 0
        self._bar = None
        if self.enabled:
            from tqdm import tqdm
            self._bar = tqdm(total=self.total, desc=f"{label:<14}", file=self.stream,
                             unit="pt", dynamic_ncols=True, mininterval=0.1, leave=True,
                             bar_format="{desc} {bar} {n_fmt}/{total_fmt} {rate_fmt} "
                                        "ETA {remaining}{postfix}")

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, exc_type, *exc) -> None:
        if exc_type is None:
            self.finish()
        self.close()

    def finish(self) -> None:
        """The work is done: the total becomes the count reached (the bar is drawn full)."""
        if self._bar is not None and self._bar.total != self.done:
            self._bar.total = self.done
            self._bar.refresh()

    def update(self, n: int = 1, info: str = "") -> None:
        self.done += n
        if self._bar is not None:
            if info:
                self._bar.set_postfix_str(info[:30], refresh=False)
            self._bar.update(n)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        self.enabled = False


def null_progress(total: int, label: str = "") -> Progress:
    return Progress(total, label, quiet=True)
