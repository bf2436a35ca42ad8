"""The findings as the engineer meets them: the console's last lines, the speed-band chart
(``findings.png``) and the first section of ``report.html``.

The findings themselves are derived in :mod:`vibrogear.analyses.findings.findings`; this module only
writes them.
"""
from __future__ import annotations

import html
from pathlib import Path

from ...config.sections.findings import base_quantity, rank
from ...config.numbers import fmt, fmt_param, merged_ranges, range_text

__all__ = ["console_lines", "plot_band_chart", "findings_html", "BAND_CHART"]

BAND_CHART = "findings.png"
#: severity -> colour of the chart and the page (colour-blind safe: red / amber / green-grey)
COLOURS = {"avoid": "#c0392b", "caution": "#e6a817", "fine": "#9bbf9b"}
_MAX_CONSOLE_BANDS = 6


def _group(bands: list[dict], severities=("avoid", "caution")) -> list[tuple[str, str, str,
                                                                             list[dict]]]:
    """(severity, where, kind, bands) per kind of band and place, most severe and most
    telling first; a run-up's or run-down's contact loss joins its mesh's contact loss."""
    groups: dict[tuple[str, str, str], list[dict]] = {}
    for b in bands:
        if b["severity"] in severities:
            key = (b["severity"], b["where"], base_quantity(b["quantity"]))
            groups.setdefault(key, []).append(b)
    order = {s: i for i, s in enumerate(("avoid", "caution", "fine"))}
    return [(s, w, q, bs) for (s, w, q), bs in
            sorted(groups.items(), key=lambda kv: (order[kv[0][0]], -_worst(kv[1]),
                                                   rank(kv[0][2]), kv[0][1]))]


def _worst(bands: list[dict]) -> float:
    """The largest margin of ``bands`` (0 for bands without one)."""
    return max((float(b.get("margin", 0.0)) for b in bands), default=0.0)


def margin_text(bands: list[dict]) -> str:
    """'up to 57 % past 1.3' / 'up to 4.2 dB past 118 dB' of the worst of ``bands``; "" where
    the bands carry no margin (motion classes, coexistence, the ISO range)."""
    have = [b for b in bands if "margin_unit" in b and b.get("op") not in ("==", "in")
            and float(b.get("margin", 0.0)) > 0]
    if not have:
        return ""
    b = max(have, key=lambda x: float(x["margin"]))
    if b["margin_unit"] == "dB":
        return f"up to {fmt(b['margin'], 2)} dB past {fmt(b['threshold'], 4)} dB"
    return f"up to {fmt(100 * b['margin'], 2)} % past {_num(b['threshold'])}"


def _label(where: str, quantity: str) -> str:
    if where in ("gearbox", "system"):
        return quantity
    if quantity == "bearing unloading":
        return f"bearing {where.removeprefix('bearing_')} unloading"
    return f"{where} {quantity}"


def _one_way(band: dict) -> bool:
    """Seen in one sweep direction only (a run-up's band has its run's direction)."""
    return band["direction"] != "both" and band["source"] != "runup.npz"


def _spans_text(bands: list[dict], unit: str) -> str:
    """The merged ranges of ``bands``, each tagged "(up)" / "(down)" where every band in it
    was seen in that sweep direction only."""
    out = []
    for lo, hi in merged_ranges(bands):
        dirs = {b["direction"] for b in bands if b["from"] >= lo and b["to"] <= hi}
        tag = f" ({dirs.pop()} only)" if len(dirs) == 1 and "both" not in dirs else ""
        out.append(range_text(lo, hi, "") + tag)
    return ", ".join(out) + (f" {unit}" if unit else "")


def _runs_text(bands: list[dict], unit: str) -> str:
    """The speeds of a kind of band: the sweep's (or map's), then the run-up's and
    run-down's."""
    steady = [b for b in bands if not b["quantity"].endswith(("run-up", "run-down"))]
    parts = [_spans_text(steady, unit)] if steady else []
    for run in ("run-up", "run-down"):
        these = [b for b in bands if b["quantity"].endswith(run)]
        if these:
            parts.append(f"{run} " + _spans_text(these, unit).replace(
                " (up only)", "").replace(" (down only)", ""))
    return "; ".join(parts)


def console_lines(findings: dict, report_path: str | None = None, *, quiet: bool = False) -> list[str]:
    """At most ~10 lines: the verdict, the avoid / caution bands by kind, the report."""
    unit = findings.get("param_unit", "rpm")
    if quiet:
        return [findings["verdict"]]
    lines = [f"findings: {findings['verdict']}"]
    groups = _group(findings.get("bands", []))
    for severity, where, quantity, bands in groups[:_MAX_CONSOLE_BANDS]:
        past = margin_text(bands)
        lines.append(f"  {severity:<7s} {_label(where, quantity)}: {_runs_text(bands, unit)}"
                     + (f" ({past})" if past else ""))
    if len(groups) > _MAX_CONSOLE_BANDS:
        lines.append(f"  ... {len(groups) - _MAX_CONSOLE_BANDS} more kinds of band in the report")
    if report_path:
        lines.append(f"open {report_path}")
    return lines


def plot_band_chart(findings: dict, path) -> Path | None:
    """The speed-band chart: the speed axis, one row per (where, quantity) with a band,
    bars coloured by severity, hatched where only one sweep direction shows it; events
    (jumps, folds, resonances, the ERP peak) as ticks on their own row."""
    bands = [b for b in findings.get("bands", []) if b["severity"] != "fine"]
    span = findings.get("range")
    if not bands and not findings.get("events"):
        return None
    from ..figure import new_figure, save_figure
    rows = []
    for b in bands:
        key = _label(b["where"], b["quantity"])
        if key not in rows:
            rows.append(key)
    events = [e for e in findings.get("events", []) if e["kind"] in
              ("jump", "LP", "PD", "NS", "resonance", "erp_peak")]
    n = len(rows) + (1 if events else 0)
    fig = new_figure(figsize=(10, 1.3 + 0.42 * max(n, 1)))
    ax = fig.add_subplot(111)
    margins = []
    for b in bands:
        y = rows.index(_label(b["where"], b["quantity"]))
        half = 0.5 * b.get("edge_err", 0.0)
        left, width = b["from"] - half, b["to"] - b["from"] + 2 * half
        ax.barh(y, width, left=left, height=0.62, color=COLOURS[b["severity"]],
                hatch="///" if _one_way(b) else None, edgecolor="white",
                linewidth=0.3)
        past = margin_text([b])
        if past:                       # the margin: how far past the threshold
            margins.append((float(b["margin"]), y, left + 0.5 * width,
                            past.replace("up to ", "+").split(" past")[0]))
    marker_handles = []
    if events:
        y = len(rows)
        marks = {"jump": ("v", "k"), "LP": ("D", "#6c3483"), "PD": ("s", "#1f618d"),
                 "NS": ("o", "#117864"), "resonance": ("|", "#555555"),
                 "erp_peak": ("*", "#c0392b")}
        for kind, (m, c) in marks.items():
            at = [e["at"] for e in events if e["kind"] == kind]
            if at:
                marker_handles += ax.plot(at, [y] * len(at), m, color=c, ms=8, mew=2,
                                          label=kind.replace("_", " "), ls="none")
        rows.append("events")
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(rows, fontsize=9)
    ax.invert_yaxis()
    if span:
        pad = 0.02 * (span[1] - span[0] or 1.0)
        ax.set_xlim(span[0] - pad, span[1] + pad)
    unit = findings.get("param_unit", "rpm")
    ax.set_xlabel(f"driving speed [{unit}]" if unit else "excitation frequency Omega")
    ax.grid(axis="x", alpha=0.3)
    from matplotlib.patches import Patch
    handles = [Patch(color=COLOURS[s], label=s) for s in ("avoid", "caution")
               if any(b["severity"] == s for b in bands)]
    if any(_one_way(b) for b in bands):
        handles.append(Patch(facecolor="white", edgecolor="k", hatch="///",
                             label="one sweep direction only"))
    handles += marker_handles
    if handles:
        fig.legend(handles=handles, loc="lower center", fontsize=8, ncol=min(len(handles), 9),
                   frameon=False)
    ax.set_title("Where to avoid or watch the gearbox" if unit == "rpm" else
                 "Where to avoid or watch the system", loc="left", fontsize=11)
    height = fig.get_size_inches()[1]
    fig.tight_layout(rect=(0, 0.35 / height if handles else 0, 1, 1))
    _place_margins(fig, ax, margins)
    return save_figure(fig, path, formats=("png",), tight=False)[0]


def _place_margins(fig, ax, margins) -> None:
    """Each band's margin written on it, the largest of a row first, the others only where
    they do not overlap one already written and fit inside the axes (a row of short bands
    had its labels printed over one another)."""
    renderer = fig.canvas.get_renderer()
    inside = ax.get_window_extent(renderer)
    placed: dict[int, list] = {}
    for _m, y, x, text in sorted(margins, key=lambda m: -m[0]):
        t = ax.text(x, y, text, ha="center", va="center", fontsize=7, color="black",
                    clip_on=True)
        box = t.get_window_extent(renderer).expanded(1.0, 1.0).padded(3)
        if box.x0 < inside.x0 or box.x1 > inside.x1 or any(
                box.overlaps(other) for other in placed.get(y, [])):
            t.remove()
            continue
        placed.setdefault(y, []).append(box)


def _esc(x) -> str:
    return html.escape(str(x), quote=True)


#: events listed openly (the others are folded)
_KEY_EVENTS = ("LP", "jump", "resonance", "erp_peak", "coexisting")


def _num(x) -> str:
    x = float(x)
    return str(int(x)) if x.is_integer() else fmt(x, 3)


def _event(e: dict, unit: str) -> str:
    return (f"<li><strong>{_esc(e['kind'])}</strong> at {_esc(fmt_param(e['at']))} "
            f"{_esc(unit)} ({_esc(e['where'])}): {_esc(e['evidence'])}</li>")


def _all_bands(findings: dict) -> str:
    unit = findings.get("param_unit", "rpm")
    rows = []
    for b in findings.get("bands", []):
        span = fmt_param(b["from"]) if b["from"] == b["to"] else \
            f"{fmt_param(b['from'])}–{fmt_param(b['to'])}"
        rows.append(f"<tr><td>{_esc(b['severity'])}</td><td>{_esc(span)} {_esc(unit)}</td>"
                    f"<td>{_esc(_label(b['where'], b['quantity']))}</td>"
                    f"<td>{_esc(b['direction'])}</td><td>{_esc(b['evidence'])}</td>"
                    f"<td><code>{_esc(b['metric'])} {_esc(b['op'])} {_esc(_num(b['threshold']))}"
                    f"</code></td></tr>")
    return ('<div class="scroll"><table><tr><th>severity</th><th>speeds</th><th>what</th>'
            "<th>sweep</th><th>evidence</th><th>rule</th></tr>" + "".join(rows)
            + "</table></div>")


def findings_html(findings: dict, chart: str | None) -> list[str]:
    """The findings section of ``report.html`` (its first section)."""
    unit = findings.get("param_unit", "rpm")
    verdict = findings["verdict"]
    css = "avoid" if verdict.startswith(("Avoid", "No speed to run")) else "caution" \
        if "Caution" in verdict or verdict.startswith("No speed is free") else "fine"
    parts = ['<h2 id="findings">Findings</h2>',
             f'<p class="verdict verdict-{css}">{_esc(verdict)}</p>']
    wins = findings.get("windows") or []
    if wins:
        parts.append("<p>Where to run" + (" (no speed is free of findings: the least "
                     "severe first)" if wins[0]["status"] != "fine" else "") + ": "
                     + _esc("; ".join(f"{range_text(w['from'], w['to'], unit)}"
                                      + (f" (limited by {', '.join(w['limits'])})"
                                         if w["limits"] else "") for w in wins[:6]))
                     + "</p>")
    if chart:
        parts.append(f'<figure class="wide"><img src="{_esc(chart)}" alt="speed bands">'
                     "<figcaption>Each row is one contact or one kind of motion; a bar marks "
                     "the speeds where its rule holds (red: avoid, amber: caution; hatched: "
                     "seen in one sweep direction only). Bars extend half a grid step each "
                     "side: the true edge lies within one step. The label on a bar: how far its "
                     "worst point lies past the rule's threshold (the band's margin)."
                     "</figcaption></figure>")
    groups = _group(findings.get("bands", []))
    if groups:
        rows = []
        for severity, where, quantity, bands in groups:
            steady = [b for b in bands if b["source"] != "runup.npz"] or bands
            worst = max(steady, key=lambda b: b["points"])
            rule = f"{worst['metric']} {worst['op']} {_num(worst['threshold'])}"
            past = margin_text(bands)
            rows.append(f'<tr><td class="nw"><span class="sev sev-{severity}">{severity}</span>'
                        f"</td><td>{_esc(_label(where, quantity))}"
                        + (f"<br><small>{_esc(past)}</small>" if past else "") + "</td>"
                        f"<td>{_esc(_runs_text(bands, unit))} (edges ± "
                        f"{_esc(fmt(worst['edge_err'], 2))})</td>"
                        f"<td>{_esc(worst['evidence'])}"
                        + (f" <small>(widest of {len(steady)} bands)</small>" if len(steady) > 1
                           else "") +
                        f"</td><td><code>{_esc(rule)}</code> in {_esc(worst['source'])}</td>"
                        "</tr>")
        parts.append('<div class="scroll"><table class="findings"><tr><th>severity</th>'
                     "<th>what</th><th>speeds</th><th>evidence</th><th>rule (recompute from "
                     "the file)</th></tr>" + "".join(rows) + "</table></div>")
        parts.append("<details><summary>Every band, one row each</summary>"
                     + _all_bands(findings) + "</details>")
    fine = [b for b in findings.get("bands", []) if b["severity"] == "fine"]
    events = findings.get("events", [])
    key = [e for e in events if e["kind"] in _KEY_EVENTS]
    rest = [e for e in events if e["kind"] not in _KEY_EVENTS]
    if key:
        parts.append("<h3>Events</h3><ul class='events'>")
        parts += [_event(e, unit) for e in key[:30]]
        parts.append("</ul>")
    if rest or len(key) > 30:
        more = rest + key[30:]
        parts.append(f"<details><summary>{len(more)} more events (period doublings, tori, "
                     "...)</summary><ul class='events'>"
                     + "".join(_event(e, unit) for e in more[:200]) + "</ul></details>")
    checked = findings.get("checked") or []
    detail = ["<details><summary>What was checked, and the rules</summary>"]
    if checked:
        detail.append("<ul>" + "".join(f"<li>{_esc(c)}</li>" for c in checked) + "</ul>")
    if fine:
        detail.append("<p>Also found (severity fine): " + _esc("; ".join(
            f"{_label(b['where'], b['quantity'])} {fmt_param(b['from'])}–{fmt_param(b['to'])} "
            f"{unit} ({b['direction']})" for b in fine[:12])) + "</p>")
    detail.append("<p>Rules (section <code>[findings]</code>, docs/findings.md): " + _esc(
        ", ".join(f"{k} = {v}" for k, v in (findings.get("rules") or {}).items())) + "</p>")
    detail.append("</details>")
    parts += detail
    return parts
