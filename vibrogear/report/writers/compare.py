"""``vibrogear compare``: the console lines and ``compare.html`` of two runs' findings
(:func:`vibrogear.analyses.findings.compare.compare_findings`)."""
from __future__ import annotations

import html
from pathlib import Path

from ...config.numbers import fmt, range_text
from ...pipeline.files import atomic_write_bytes

__all__ = ["compare_lines", "write_compare_html", "COMPARE_HTML"]

COMPARE_HTML = "compare.html"


def _span(b: dict, unit: str) -> str:
    return range_text(b["from"], b["to"], unit)


def _what(b: dict) -> str:
    where = "" if b["where"] in ("gearbox", "system") else f"{b['where']} "
    return f"{b['severity']} {where}{b['quantity']}"


def _margin(b: dict) -> str:
    """How far past its threshold ("" for a band without a margin: a motion class)."""
    m = float(b.get("margin", 0.0))
    if b.get("op") in ("==", "in") or "margin_unit" not in b:
        return ""
    return f"{fmt(m, 2)} dB" if b.get("margin_unit") == "dB" else f"{fmt(100 * m, 2)} %"


def _pair(v, digits=3, unit="") -> str:
    a, b = (None if x is None else float(x) for x in v)
    txt = lambda x: "–" if x is None else fmt(x, digits)  # noqa: E731
    change = f" ({'+' if b - a >= 0 else ''}{fmt(b - a, 2)}{unit})" if a is not None and \
        b is not None else ""
    return f"{txt(a)} -> {txt(b)}{unit and ' ' + unit.strip()}{change}"


def _mesh_lines(c: dict) -> list[str]:
    out = []
    for m in c["meshes"]:
        role = " / ".join(sorted({str(r) for r in m["role"] if r}))
        parts = []
        if "kv_peak" in m:
            parts.append(f"kv peak {_pair(m['kv_peak'])}")
        if "n_E1_rpm" in m:
            parts.append(f"ISO n_E1 {_pair(m['n_E1_rpm'], 4)} rpm")
        if "rattle_db_max" in m:
            parts.append(f"loudest rattle {_pair(m['rattle_db_max'], 3)} dB")
        if "rattle_db_min" in m:
            parts.append(f"quietest {_pair(m['rattle_db_min'], 3)} dB")
        out.append(f"  {m['name']} ({role}): " + ("; ".join(parts) or "no metric"))
    return out


def compare_lines(c: dict) -> list[str]:
    """The console: both verdicts, the bands added / removed / moved, the meshes."""
    unit = c["param_unit"]
    a, b = c["runs"]
    lines = [f"compare: A = {a}, B = {b}", f"A: {c['verdicts'][0]}", f"B: {c['verdicts'][1]}"]
    bands = c["bands"]
    for x in bands["added"]:
        past = f" ({_margin(x)} past its threshold)" if _margin(x) else ""
        lines.append(f"  added   {_what(x)}: {_span(x, unit)}{past}")
    for x in bands["removed"]:
        lines.append(f"  removed {_what(x)}: {_span(x, unit)}")
    for p in bands["moved"]:
        lines.append(f"  moved   {_what(p['b'])}: {_span(p['a'], unit)} -> {_span(p['b'], unit)}")
    if not (bands["added"] or bands["removed"] or bands["moved"]):
        lines.append(f"  the same bands ({len(bands['kept'])}) in both runs")
    lines += _mesh_lines(c)
    return lines


def _esc(x) -> str:
    return html.escape(str(x), quote=True)


def _band_rows(rows) -> str:
    return "".join(f"<tr>{''.join(f'<td>{_esc(v)}</td>' for v in r)}</tr>" for r in rows)


def write_compare_html(c: dict, path) -> Path:
    """``compare.html``: the verdicts, windows, band changes and meshes of the two runs."""
    unit = c["param_unit"]
    bands = c["bands"]
    rows = [("added", _what(x), "–", _span(x, unit), _margin(x), x["evidence"])
            for x in bands["added"]]
    rows += [("removed", _what(x), _span(x, unit), "–", _margin(x), x["evidence"])
             for x in bands["removed"]]
    rows += [("moved", _what(p["b"]), _span(p["a"], unit), _span(p["b"], unit),
              f"{_margin(p['a'])} -> {_margin(p['b'])}", p["b"]["evidence"])
             for p in bands["moved"]]
    rows += [("kept", _what(p["b"]), _span(p["a"], unit), _span(p["b"], unit),
              f"{_margin(p['a'])} -> {_margin(p['b'])}", p["b"]["evidence"])
             for p in bands["kept"]]

    def win(ws):
        return "; ".join(f"{range_text(w['from'], w['to'], unit)} ({w['status']}"
                         + (f": {', '.join(w['limits'])}" if w["limits"] else "") + ")"
                         for w in ws) or "none"
    parts = ["<!doctype html><html><head><meta charset='utf-8'><title>vibrogear compare"
             "</title><style>body{font-family:sans-serif;max-width:70em;margin:1em auto}"
             "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:.2em .5em;"
             "vertical-align:top}th{background:#eee}</style></head><body>",
             "<h1>Findings compared</h1>",
             _table(["", "A", "B"], [("run", *c["runs"]), ("scene", *c["scenes"]),
                                     ("verdict", *c["verdicts"]),
                                     ("windows", win(c["windows"][0]), win(c["windows"][1]))]),
             "<h2>Bands</h2>",
             _table(["change", "band", "A", "B", "margin past the threshold", "evidence (B, "
                     "or A where removed)"], rows),
             "<h2>Meshes</h2><ul>" + "".join(f"<li>{_esc(line.strip())}</li>"
                                            for line in _mesh_lines(c)) + "</ul>",
             "<p>Two bands are the same where kind, place, severity and sweep direction agree "
             "and their speeds overlap; moved: an edge changed by more than a grid step.</p>",
             "</body></html>"]
    return atomic_write_bytes(Path(path), "\n".join(parts).encode())


def _table(header, rows) -> str:
    return ("<table><tr>" + "".join(f"<th>{_esc(h)}</th>" for h in header) + "</tr>"
            + _band_rows(rows) + "</table>")
