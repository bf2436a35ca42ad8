"""The verdict of the findings in one sentence, and the speed ranges of a set of bands in
plain words."""
from __future__ import annotations

from ...config.sections.findings import PRIORITY, base_quantity, rank
from ...config.numbers import fmt, fmt_param, merged_ranges, range_text

__all__ = ["verdict_text", "ranges_text", "where_to_run"]


def ranges_text(bands: list[dict], unit: str) -> str:
    spans = merged_ranges(bands)
    return ", ".join(range_text(a, b, "") for a, b in spans) + (f" {unit}" if unit else "")


#: quantity -> (singular, plural) phrase of the places ({w}) where it happens
PHRASES = {"contact loss": ("{w} loses contact", "{w} lose contact"),
           "rattle": ("{w} rattles", "{w} rattle"),
           "double-sided impacts": ("{w} hits both flanks", "{w} hit both flanks"),
           "bearing unloading": ("bearing {w} unloads", "bearings {w} unload"),
           "hysteresis (up and down differ)": ("up and down sweeps differ (jumps)",) * 2,
           "radiated power": ("the housing radiates most",) * 2,
           "coexisting states": ("other states coexist",) * 2,
           "dynamic factor": ("{w}'s dynamic factor exceeds the limit",
                              "the dynamic factors of {w} exceed the limit"),
           "rattle above the limit": ("{w} rattles above the limit",
                                      "{w} rattle above the limit"),
           "impacts in a state": ("{w} hits the teeth in the states found",
                                  "{w} hit the teeth in the states found"),
           "dynamic factor in a state": ("a state of {w} exceeds the dynamic-factor limit",
                                         "states of {w} exceed the dynamic-factor limit"),
           "rattle in a state": ("a state of {w} rattles", "states of {w} rattle"),
           "ISO 6336 main resonance": ("{w} is in its ISO 6336 main resonance range",
                                       "{w} are in their ISO 6336 main resonance ranges")}
def _and(items: list[str]) -> str:
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def _reasons(bands: list[dict]) -> str:
    """The kinds of ``bands`` in one clause: 'G1 and G2 lose contact (also in the run-up),
    G2 rattles, chaotic and quasi-periodic motion'."""
    steady: dict[str, list[str]] = {}          # kind -> places, from sweeps and maps
    runs: dict[str, list[str]] = {}            # kind -> "run-up" / "run-down"
    for b in sorted(bands, key=lambda b: rank(b["quantity"])):
        base = base_quantity(b["quantity"])
        places = steady.setdefault(base, [])
        if base != b["quantity"]:
            run = b["quantity"][len(base) + len(" in the "):]
            if run not in runs.setdefault(base, []):
                runs[base].append(run)
            if not any(x["quantity"] == base for x in bands) and b["where"] not in places:
                places.append(b["where"])
        elif b["where"] not in places and b["where"] not in ("gearbox", "system"):
            places.append(b["where"])
    parts, motion = [], []
    for base, where in steady.items():
        if base.endswith(" motion"):
            motion.append(base[:-len(" motion")])
            continue
        single, plural = PHRASES.get(base, ("{w} " + base, "{w} " + base))
        if base == "bearing unloading":
            where = [w.removeprefix("bearing_") for w in where]
        text = (plural if len(where) > 1 else single).format(w=_and(where) if where else "")
        in_sweep = any(x["quantity"] == base for x in bands)
        if runs.get(base):
            text += f" (also in the {' and '.join(runs[base])})" if in_sweep else \
                f" in the {' and '.join(runs[base])}"
        parts.append(text.strip())
    if motion:
        n = sum(1 for p in steady if rank(p) < PRIORITY.index("chaotic motion"))
        parts.insert(min(n, len(parts)), f"{_and(motion)} motion")
    return _and(parts) if parts else ""


def _where(bands: list[dict], unit: str) -> str:
    spans = merged_ranges(bands)
    if len(spans) <= 3:
        return "at " + ranges_text(bands, unit)
    u = f" {unit}" if unit else ""
    return f"in {len(spans)} bands between {fmt_param(spans[0][0])} and {fmt_param(spans[-1][1])}{u}"


def _margin_text(band: dict) -> str:
    m = float(band.get("margin", 0.0))
    if band.get("margin_unit") == "dB":
        return f"{fmt(m, 2)} dB past its threshold"
    return f"{fmt(100 * m, 2)} % past its threshold" if m else "at its threshold"


def where_to_run(windows: list[dict], bands: list[dict], span, unit: str) -> str:
    """The verdict's first sentence: the windows that are fine, else the least severe
    ones with what limits them, else that a loaded mesh fails over the whole range."""
    u = f" {unit}" if unit else ""
    fine = [w for w in windows if w["status"] == "fine"]
    if fine:
        spans = ", ".join(range_text(w["from"], w["to"], "") for w in fine)
        return f"Run at {spans}{u}: no band to avoid or watch there."
    if windows:
        best = windows[:3]
        parts = []
        for w in best:
            worst = w.get("worst")
            limit = f" (limited by {_and(w['limits'])}" + (
                f"; worst: {worst['what']} {_margin_text(worst)})" if worst else ")")
            parts.append(range_text(w["from"], w["to"], "") + u + limit)
        return ("No speed is free of findings; least severe: " + "; ".join(parts) + ".")
    where = f" {range_text(span[0], span[1], unit)}" if span else ""
    return f"No speed to run at: the whole range{where} is to be avoided."


def _label(b: dict) -> str:
    return b["quantity"] if b["where"] in ("gearbox", "system") else \
        f"{b['where']} {b['quantity']}"


def _quiet(bands: list[dict], unit: str) -> str:
    """'G2 rattles least at 1500–1600 rpm (60–62 dB re 1 pW).' per idle mesh."""
    out = []
    for w in sorted({b["where"] for b in bands if b["quantity"] == "quietest rattle"}):
        these = [b for b in bands if b["quantity"] == "quietest rattle" and b["where"] == w]
        lo = min(float(b["threshold"]) for b in these) - 3.0
        out.append(f"{w} rattles least at {ranges_text(these, unit)} (within 3 dB of its "
                   f"quietest, {fmt(lo, 3)} dB re 1 pW).")
    return (" " + " ".join(out)) if out else ""


def verdict_text(bands: list[dict], checked: list[str], span, partial: list[str],
                 unit: str, windows: list[dict] | None = None) -> str:
    """A few sentences: where to run (:func:`where_to_run`), then the speeds to avoid and
    why, then those to watch, else what was checked and found fine.  A partial run says
    so."""
    tail = f" Partial results: {'; '.join(partial)}." if partial else ""
    if not checked:
        return ("No speed verdict: this run computed no response over speed (run a sweep, "
                "map, run-up or states)." + tail)
    head = where_to_run(windows, bands, span, unit) + " " if windows is not None else ""
    rest = _avoid_caution(bands, checked, span, unit, bool(head)).strip()
    return (head + rest).strip() + _quiet(bands, unit) + tail


def _avoid_caution(bands, checked, span, unit, head: bool = False) -> str:
    avoid = [b for b in bands if b["severity"] == "avoid"]
    caution = [b for b in bands if b["severity"] == "caution"]
    where = f" in {range_text(span[0], span[1], unit)}" if span else ""
    text = f"Avoid {_where(avoid, unit)[3:]}: {_reasons(avoid)}." if avoid and \
        len(merged_ranges(avoid)) <= 3 else f"Avoid {_where(avoid, unit)}: " \
        f"{_reasons(avoid)}." if avoid else \
        ("" if head else f"No speed to avoid{where}.")
    if caution:
        text += f" Caution {_where(caution, unit)}: {_reasons(caution)}."
    elif not avoid:
        text = "" if head else f"No speed to avoid or watch{where} by the rules checked."
        if not any(c.startswith("coexisting states") for c in checked):
            text += (" The sweep follows one state up and one down: other states may "
                     "coexist (vibrogear states finds them).")
    return text
