"""``report.html``: one self-contained page per run folder, written at the end of every run
(also a failed or interrupted one) from the run's summary dict and the folder's contents.

The page needs no server, no script and nothing from the network: the style sheet is inline,
figures are ``<img>`` links to the PNGs beside it and every other file in the folder is a
relative link.  It opens on the findings (:mod:`..writers.findings`) and a drawing of the
gearbox, then gives per analysis its key figure with a caption that says what to look at,
its numerical status, warnings and, folded, its error estimates, values, other figures and
files; a glossary, the run's details and the folder's files close it.  Nothing is wider than
the page: wide tables scroll inside their own box.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from ...config.verbs import VERBS
from ...pipeline.files import atomic_write_text
from ...pipeline.outcome import is_root_process
from .captions import caption
from .glossary import GLOSSARY, PAPER, SECTION_TITLES
from .html_parts import REPORT_NAME
from .html_parts import anchor as _anchor, esc as _esc, fmt as _fmt, folder_files as _folder_files
from .html_parts import link as _link, list_text as _list_text
from .html_parts import record_files as _record_files, records_table as _records_table
from .html_parts import size as _size, status_badge as _status_badge, table as _table
from .html_parts import url as _url
from .load_path import load_path_html

__all__ = ["REPORT_NAME", "write_html_report", "render_html_report"]

FIGURE_SUFFIX = ".png"
#: the drawing of the gearbox and the speed-band chart (written by the runner)
OVERVIEW_FIGURES = ("findings.png", "gearbox.png")
#: summary entries shown in their own places, not in an analysis's table of values
_OWN_PLACE = ("status", "message", "warnings", "files", "error_estimate")
_MAX_DEPTH = 4          # nested dicts are flattened to this depth

_STYLE = """
body { font-family: sans-serif; margin: 1.5em auto; max-width: 1100px; padding: 0 1em;
       color: #222; line-height: 1.4; }
h1 { font-size: 1.5em; } h2 { margin-top: 1.6em; border-bottom: 1px solid #ccc; }
h3 { font-size: 1.05em; margin-bottom: .3em; }
nav { font-size: .9em; } nav a { margin-right: .8em; }
.scroll { max-width: 100%; overflow-x: auto; }
table { border-collapse: collapse; margin: .4em 0 1em; font-size: .88em; }
th, td { border: 1px solid #ccc; padding: .2em .6em; text-align: left; vertical-align: top;
         overflow-wrap: anywhere; }
th { background: #f3f3f3; } td.num { text-align: right; font-family: monospace; }
.status { font-weight: bold; padding: .1em .5em; border-radius: .3em; }
.status-ok { background: #d8f0d8; } .status-partial { background: #fff1c2; }
.status-failed, .status-interrupted { background: #f6d0d0; }
.status-not-run { background: #e6e6e6; }
.verdict { font-size: 1.15em; padding: .6em .8em; border-left: .4em solid; }
.verdict-avoid { border-color: #c0392b; background: #fbeaea; }
.verdict-caution { border-color: #e6a817; background: #fdf5e0; }
.verdict-fine { border-color: #5b8c5b; background: #edf5ed; }
.sev { font-weight: bold; padding: 0 .4em; border-radius: .3em; color: #fff; }
.sev-avoid { background: #c0392b; } .sev-caution { background: #b7830d; }
.sev-fine { background: #5b8c5b; }
figure { display: inline-block; margin: .5em; max-width: 100%; vertical-align: top; }
figure.key, figure.wide { display: block; margin: .5em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: .88em; max-width: 60em; }
details { margin: .4em 0; } summary { cursor: pointer; color: #1f4e79; }
ul.warnings li { color: #8a5a00; }
dl.glossary dt { font-weight: bold; } dl.glossary dd { margin: 0 0 .5em 1.5em; }
code { overflow-wrap: anywhere; } td.nw, .nw { white-space: nowrap; }
"""


def write_html_report(out, summary: dict) -> Path | None:
    """Write ``out/report.html`` for the run whose summary is ``summary`` (atomically; only
    on rank 0 under MPI); return its path, or None on the other ranks."""
    if not is_root_process():
        return None
    out = Path(out)
    return atomic_write_text(out / REPORT_NAME, render_html_report(out, summary))


def render_html_report(out, summary: dict) -> str:
    """The page for the run folder ``out`` whose summary is ``summary``, as a string."""
    from ..writers.findings import findings_html
    out = Path(out)
    folder = _folder_files(out)
    results = summary.get("results") or {}
    claimed: dict[str, str] = {}            # relative file path -> analysis that wrote it
    for name, record in results.items():
        if isinstance(record, dict):
            for rel in _record_files(out, record.get("files")):
                claimed.setdefault(rel, str(name))
    names = list(summary.get("analyses") or [])
    names += [n for n in results if n not in names]

    status = str(summary.get("status", "unknown"))
    title = f"{summary.get('scene', '')}: vibration report"
    findings = summary.get("findings")
    parts = [
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{_esc(title)}</title>", f"<style>{_STYLE}</style>", "</head>", "<body>",
        f"<h1>{_esc(title)}</h1>",
        f"<p>Computation: {_status_badge(status)} &middot; scene "
        f"<code>{_esc(summary.get('source', ''))}</code> &middot; "
        f"{_esc(_wall((summary.get('wall_time_s') or {}).get('total')))}</p>",
        _nav(names, findings is not None, "gearbox.png" in folder),
    ]
    parts += _failure_notes(results)
    if findings is not None:
        parts += findings_html(findings, "findings.png" if "findings.png" in folder else None)
        if "housing_ods.png" in folder:          # where the housing radiates, at the ERP peak
            parts.append("<h3>Where the housing radiates (at the ERP peak)</h3>")
            parts += [_figure(rel) for rel in ("housing_ods.png", "housing_ods_anim.png")
                      if rel in folder]
    notes = summary.get("notes") or []
    if notes:
        parts.append("<h3>Notes on the model</h3><ul>")
        parts += [f"<li>{_esc(n)}</li>" for n in notes]
        parts.append("</ul>")
    if "gearbox.png" in folder:
        parts.append('<h2 id="gearbox">The gearbox</h2>')
        parts.append(_figure("gearbox.png", key=True))
    parts += load_path_html(summary.get("load_path"))

    for name in names:
        record = results.get(name)
        wall = (summary.get("wall_time_s") or {}).get(name)
        parts += _analysis_section(out, name, record, wall, folder,
                                   str(summary.get("reduced_model", "")))

    unclaimed_figures = [rel for rel in folder if rel.lower().endswith(FIGURE_SUFFIX)
                         and rel not in claimed and rel not in OVERVIEW_FIGURES]
    if unclaimed_figures:
        parts.append("<h2>Other figures</h2>")
        parts += [_figure(rel) for rel in unclaimed_figures]
    parts += _glossary()
    parts += _run_details(summary, names, status)
    parts.append('<h2 id="files">Files in this folder</h2>')
    if folder:
        rows = [(_link(rel), _size(folder[rel]), _esc(claimed.get(rel, "")))
                for rel in folder]
        parts.append(f"<details><summary>{len(folder)} files</summary>"
                     + _table(["file", "size", "analysis"], rows, raw=True) + "</details>")
    else:
        parts.append("<p>No files.</p>")
    parts += ["</body>", "</html>", ""]
    return "\n".join(parts)


def _wall(seconds) -> str:
    """A run's wall time as people say it: 38 s, 4 min 12 s."""
    if not isinstance(seconds, (int, float)) or not math.isfinite(seconds):
        return "n/a"
    if seconds < 100:
        return f"{seconds:.3g} s"
    return f"{int(seconds // 60)} min {int(round(seconds % 60))} s"


def _nav(names, findings: bool, drawing: bool) -> str:
    links = (['<a href="#findings">Findings</a>'] if findings else []) + \
        (['<a href="#gearbox">Gearbox</a>'] if drawing else []) + \
        [f'<a href="#{_anchor(n)}">{_esc(SECTION_TITLES.get(n, n))}</a>' for n in names] + \
        ['<a href="#glossary">Glossary</a>', '<a href="#run">Run details</a>',
         '<a href="#files">Files</a>']
    return "<nav>" + " ".join(links) + "</nav>"


def _glossary() -> list[str]:
    parts = ['<h2 id="glossary">Glossary</h2>', '<dl class="glossary">']
    parts += [f"<dt>{_esc(term)}</dt><dd>{_esc(text)}</dd>" for term, text in GLOSSARY]
    parts.append("</dl>")
    parts.append(f"<p>Method: {_esc(PAPER)}</p>")
    return parts


def _run_details(summary: dict, names, status: str) -> list[str]:
    walls = [(k, _fmt(v, 3)) for k, v in (summary.get("wall_time_s") or {}).items()]
    return ['<h2 id="run">Run details</h2>', "<details><summary>scene, versions, wall "
            "times</summary>",
            _table(["entry", "value"], [
                ("scene", summary.get("scene")), ("source", summary.get("source")),
                ("model", summary.get("model")), ("analyses", ", ".join(map(str, names))),
                ("computation status", status)]
                + [("derived from the scene", line) for line in summary.get("derived") or ()]),
            "<h3>Versions</h3>",
            _table(["package", "version"], list((summary.get("versions") or {}).items())),
            "<h3>Wall times [s]</h3>", _table(["stage", "wall time [s]"], walls),
            "</details>"]


# ------------------------------------------------------------------ sections

def _failure_notes(results: dict) -> list[str]:
    notes = []
    for name, record in results.items():
        if isinstance(record, dict) and record.get("status") in ("failed", "interrupted"):
            notes.append(f"<p><strong>{_esc(name)}</strong> {_esc(record['status'])}: "
                         f"{_esc(record.get('message', ''))}</p>")
    return notes


def _key_figure(name: str, figures: list[str]) -> str | None:
    """The analysis's key figure: the first PNG its verb lists among its outputs."""
    verb = VERBS.get(name)
    wanted = [f for run in (verb.runs.values() if verb else ()) for f in run.outputs
              if f.endswith(FIGURE_SUFFIX)]
    for f in wanted:
        for rel in figures:
            if rel.rsplit("/", 1)[-1] == f:
                return rel
    return figures[0] if figures else None


def _analysis_section(out: Path, name: str, record, wall, folder: dict[str, int],
                      title: str = "") -> list[str]:
    parts = [f'<h2 id="{_anchor(name)}">{_esc(SECTION_TITLES.get(name, name))}</h2>']
    if not isinstance(record, dict):
        parts.append(f"<p>Computation: {_status_badge('not run')}</p>")
        return parts
    status = str(record.get("status", "ok"))
    line = f"Computation: {_status_badge(status)}"
    if record.get("message") and record.get("message") != status:
        line += f" &mdash; {_esc(record['message'])}"
    if wall is not None:
        line += f" &middot; {_esc(_fmt(wall, 3))} s"
    parts.append(f"<p>{line}</p>")
    warnings = record.get("warnings") or []
    if warnings:
        parts.append("<h3>Warnings</h3><ul class=\"warnings\">")
        parts += [f"<li>{_esc(w)}</li>" for w in warnings]
        parts.append("</ul>")
    files = [rel for rel in _record_files(out, record.get("files")) if rel in folder]
    figures = [rel for rel in files if rel.lower().endswith(FIGURE_SUFFIX)]
    key = _key_figure(name, figures)
    if key is not None:
        parts.append(_figure(key, key=True, title=title))
    others = [rel for rel in figures if rel != key]
    if others:
        parts.append(f"<details><summary>{len(others)} more figures</summary>")
        parts += [_figure(rel, title=title) for rel in others]
        parts.append("</details>")
    if "error_estimate" in record:
        estimate = record["error_estimate"]
        if isinstance(estimate, dict) and estimate:
            rows = [row for k, v in estimate.items() for row in _flatten(v, str(k))]
        else:
            rows = _flatten(estimate, "error_estimate")
        parts.append("<details><summary>Error estimates</summary>"
                     + _table(["estimate", "value"], rows) + "</details>")
    values, record_lists = _key_values(record)
    if values or record_lists:
        parts.append("<details><summary>All values of this analysis</summary>")
        if values:
            parts.append(_table(["entry", "value"], values))
        for key_name, items in record_lists:
            parts.append(f"<h3>{_esc(key_name)}</h3>")
            parts.append(_records_table(items))
        parts.append("</details>")
    data = [rel for rel in files if rel not in figures]
    if data:
        parts.append("<p>Data: " + ", ".join(f"{_link(rel)} ({_size(folder[rel])})"
                                             for rel in data) + "</p>")
    return parts


def _key_values(record: dict) -> tuple[list[tuple[str, Any]], list[tuple[str, list]]]:
    """The scalar entries of an analysis's summary (nested dicts flattened to dotted keys,
    short lists of numbers joined) and its lists of records (shown as tables)."""
    values: list[tuple[str, Any]] = []
    record_lists: list[tuple[str, list]] = []
    for key, value in record.items():
        if key in _OWN_PLACE:
            continue
        if isinstance(value, (list, tuple)) and value and all(isinstance(v, dict) for v in value):
            record_lists.append((str(key), list(value)))
        else:
            values += _flatten(value, str(key))
    return values, record_lists


def _flatten(value, key: str, depth: int = 0) -> list[tuple[str, Any]]:
    if isinstance(value, dict):
        if depth >= _MAX_DEPTH:
            return [(key, f"{{{len(value)} entries}}")]
        rows = []
        for k, v in value.items():
            rows += _flatten(v, f"{key}.{k}", depth + 1)
        return rows or [(key, "{}")]
    if isinstance(value, (list, tuple)):
        return [(key, _list_text(value))]
    return [(key, value)]


def _figure(rel: str, key: bool = False, title: str = "") -> str:
    """A figure with its caption; ``title``: the reduced model's study title, whose mode
    count (m = a+b+c) the caption states."""
    url = _url(rel)
    text = caption(rel, title)
    text = f"{_esc(text)} <small>({_esc(rel)})</small>" if text else _esc(rel)
    css = ' class="key"' if key else ""
    return (f'<figure{css}><a href="{url}"><img src="{url}" alt="{_esc(rel)}"></a>'
            f"<figcaption>{text}</figcaption></figure>")
