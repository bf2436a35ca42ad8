"""The verdict of the findings in one sentence, and the speed ranges of a set of bands in
plain words."""
from __future__ import annotations

from ..config.numbers import fmt_param, merged_ranges, range_text

__all__ = ["verdict_text", "ranges_text"]


def ranges_text(bands: list[dict], unit: str) -> str:
    spans = merged_ranges(bands)
    return ", ".join(range_text(a, b, "") for a, b in spans) + (f" {unit}" if unit else "")


#: quantity -> what it says in a sentence ({w}: where)
PHRASES = {"contact loss": "{w} loses contact", "rattle": "{w} rattles",
           "double-sided impacts": "{w} hits both flanks",
           "bearing unloading": "bearing {w} unloads",
           "chaotic motion": "chaotic motion", "quasi-periodic motion": "quasi-periodic motion",
           "subharmonic motion": "subharmonic motion", "motion not settled":
           "motion that did not settle", "aperiodic motion": "aperiodic motion",
           "hysteresis (up and down differ)": "up and down sweeps differ (jumps)",
           "radiated power": "the housing radiates most",
           "coexisting states": "other states coexist"}


def _reasons(bands: list[dict]) -> str:
    seen: list[str] = []
    for b in bands:
        text = PHRASES.get(b["quantity"], "{w} " + b["quantity"]).format(w=b["where"])
        if text not in seen:
            seen.append(text)
    if len(seen) > 1:
        return ", ".join(seen[:-1]) + " and " + seen[-1]
    return seen[0] if seen else ""


def _where(bands: list[dict], unit: str) -> str:
    spans = merged_ranges(bands)
    if len(spans) <= 3:
        return "at " + ranges_text(bands, unit)
    u = f" {unit}" if unit else ""
    return f"in {len(spans)} bands between {fmt_param(spans[0][0])} and {fmt_param(spans[-1][1])}{u}"


def verdict_text(bands: list[dict], checked: list[str], span, partial: list[str],
                 unit: str) -> str:
    """A few sentences: the speeds to avoid and why, then those to watch, else what was
    checked and found fine.  A partial run says so."""
    tail = f" Partial results: {'; '.join(partial)}." if partial else ""
    if not checked:
        return ("No speed verdict: this run computed no response over speed (run a sweep, "
                "map, run-up or states)." + tail)
    avoid = [b for b in bands if b["severity"] == "avoid"]
    caution = [b for b in bands if b["severity"] == "caution"]
    where = f" in {range_text(span[0], span[1], unit)}" if span else ""
    text = f"Avoid {_where(avoid, unit)[3:]}: {_reasons(avoid)}." if avoid and \
        len(merged_ranges(avoid)) <= 3 else f"Avoid {_where(avoid, unit)}: " \
        f"{_reasons(avoid)}." if avoid else \
        f"No speed to avoid{where}."
    if caution:
        text += f" Caution {_where(caution, unit)}: {_reasons(caution)}."
    elif not avoid:
        text = f"No speed to avoid or watch{where} by the rules checked."
        if not any(c.startswith("coexisting states") for c in checked):
            text += (" The sweep follows one state up and one down: other states may "
                     "coexist (vibrogear states finds them).")
    return text + tail
