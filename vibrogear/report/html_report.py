"""``report.html``: one self-contained page per run folder, written at the end of every run
(also a failed or interrupted one) from the run's summary dict and the folder's contents.

The page needs no server, no script and nothing from the network: the style sheet is inline,
figures are ``<img>`` links to the PNGs beside it and every other file in the folder is a
relative link.  It shows the run's status, versions and wall times, and per analysis its
status and message, warnings, error estimates, the scalar entries of its summary (and its
lists of records) as tables, its figures and its files.
"""
from __future__ import annotations

import html
import math
import os
from pathlib import Path
from typing import Any, Iterable
from urllib.parse import quote

from ..pipeline.files import atomic_write_text
from ..pipeline.outcome import is_root_process

__all__ = ["REPORT_NAME", "write_html_report", "render_html_report"]

REPORT_NAME = "report.html"
FIGURE_SUFFIX = ".png"
#: summary entries shown in their own places, not in an analysis's table of values
_OWN_PLACE = ("status", "message", "warnings", "files", "error_estimate")
_MAX_LIST = 12          # lists of numbers up to this length are shown whole
_MAX_ROWS = 60          # rows of a table of records
_MAX_DEPTH = 4          # nested dicts are flattened to this depth
_MAX_FILES = 5000       # files listed from the folder

_STYLE = """
body { font-family: sans-serif; margin: 1.5em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.5em; } h2 { margin-top: 1.6em; border-bottom: 1px solid #ccc; }
h3 { font-size: 1.05em; margin-bottom: .3em; }
table { border-collapse: collapse; margin: .4em 0 1em; font-size: .9em; }
th, td { border: 1px solid #ccc; padding: .2em .6em; text-align: left; vertical-align: top; }
th { background: #f3f3f3; } td.num { text-align: right; font-family: monospace; }
.status { font-weight: bold; padding: .1em .5em; border-radius: .3em; }
.status-ok { background: #d8f0d8; } .status-partial { background: #fff1c2; }
.status-failed, .status-interrupted { background: #f6d0d0; }
.status-not-run { background: #e6e6e6; }
figure { display: inline-block; margin: .5em; max-width: 100%; }
figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: .85em; text-align: center; }
ul.warnings li { color: #8a5a00; }
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
    title = f"vibrogear run: {summary.get('scene', '')}"
    parts = [
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        f"<title>{_esc(title)}</title>", f"<style>{_STYLE}</style>", "</head>", "<body>",
        f"<h1>{_esc(title)}</h1>",
        f'<p>Status: {_status_badge(status)}</p>',
    ]
    parts += _failure_notes(results)
    notes = summary.get("notes") or []
    if notes:
        parts.append("<h3>Notes</h3><ul>")
        parts += [f"<li>{_esc(n)}</li>" for n in notes]
        parts.append("</ul>")
    parts.append("<h2>Run</h2>")
    parts.append(_table(["entry", "value"], [
        ("scene", summary.get("scene")), ("source", summary.get("source")),
        ("model", summary.get("model")), ("analyses", ", ".join(map(str, names))),
        ("status", status)]))
    parts.append("<h3>Versions</h3>")
    parts.append(_table(["package", "version"], list((summary.get("versions") or {}).items())))
    parts.append("<h3>Wall times [s]</h3>")
    parts.append(_table(["stage", "wall time [s]"],
                        list((summary.get("wall_time_s") or {}).items())))
    if names:
        parts.append("<h3>Contents</h3><ul>")
        parts += [f'<li><a href="#{_anchor(n)}">{_esc(n)}</a></li>' for n in names]
        parts.append('<li><a href="#files">files in this folder</a></li></ul>')

    for name in names:
        record = results.get(name)
        wall = (summary.get("wall_time_s") or {}).get(name)
        parts += _analysis_section(out, name, record, wall, folder)

    unclaimed_figures = [rel for rel in folder
                         if rel.lower().endswith(FIGURE_SUFFIX) and rel not in claimed]
    if unclaimed_figures:
        parts.append("<h2>Other figures</h2>")
        parts += [_figure(rel) for rel in unclaimed_figures]

    parts.append('<h2 id="files">Files in this folder</h2>')
    if folder:
        rows = [(_link(rel), _size(folder[rel]), _esc(claimed.get(rel, "")))
                for rel in folder]
        parts.append(_table(["file", "size", "analysis"], rows, raw=True))
    else:
        parts.append("<p>No files.</p>")
    parts += ["</body>", "</html>", ""]
    return "\n".join(parts)


# ------------------------------------------------------------------ sections

def _failure_notes(results: dict) -> list[str]:
    notes = []
    for name, record in results.items():
        if isinstance(record, dict) and record.get("status") in ("failed", "interrupted"):
            notes.append(f"<p><strong>{_esc(name)}</strong> {_esc(record['status'])}: "
                         f"{_esc(record.get('message', ''))}</p>")
    return notes


def _analysis_section(out: Path, name: str, record, wall, folder: dict[str, int]) -> list[str]:
    parts = [f'<h2 id="{_anchor(name)}">{_esc(name)}</h2>']
    if not isinstance(record, dict):
        parts.append(f"<p>Status: {_status_badge('not run')}</p>")
        return parts
    status = str(record.get("status", "ok"))
    line = f"Status: {_status_badge(status)}"
    if record.get("message") and record.get("message") != status:
        line += f" &mdash; {_esc(record['message'])}"
    if wall is not None:
        line += f" &middot; wall time {_esc(_fmt(wall))} s"
    parts.append(f"<p>{line}</p>")
    warnings = record.get("warnings") or []
    if warnings:
        parts.append("<h3>Warnings</h3><ul class=\"warnings\">")
        parts += [f"<li>{_esc(w)}</li>" for w in warnings]
        parts.append("</ul>")
    if "error_estimate" in record:
        parts.append("<h3>Error estimates</h3>")
        estimate = record["error_estimate"]
        if isinstance(estimate, dict) and estimate:
            rows = [row for k, v in estimate.items() for row in _flatten(v, str(k))]
        else:
            rows = _flatten(estimate, "error_estimate")
        parts.append(_table(["estimate", "value"], rows))
    values, record_lists = _key_values(record)
    if values:
        parts.append("<h3>Results</h3>")
        parts.append(_table(["entry", "value"], values))
    for key, items in record_lists:
        parts.append(f"<h3>{_esc(key)}</h3>")
        parts.append(_records_table(items))
    files = [rel for rel in _record_files(out, record.get("files")) if rel in folder]
    figures = [rel for rel in files if rel.lower().endswith(FIGURE_SUFFIX)]
    if figures:
        parts.append("<h3>Figures</h3>")
        parts += [_figure(rel) for rel in figures]
    if files:
        parts.append("<h3>Files</h3><ul>")
        parts += [f"<li>{_link(rel)} ({_size(folder[rel])})</li>" for rel in files]
        parts.append("</ul>")
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


def _list_text(values) -> str:
    if not values:
        return "[]"
    if len(values) <= _MAX_LIST and all(_is_scalar(v) for v in values):
        return ", ".join(_fmt(v) for v in values)
    if all(_is_scalar(v) for v in values):
        first, second, last = (_fmt(values[i]) for i in (0, 1, -1))
        return f"{len(values)} values: {first}, {second}, ..., {last}"
    return f"{len(values)} entries"


def _records_table(items: list[dict]) -> str:
    columns: list[str] = []
    for item in items:
        for k, v in item.items():
            if k not in columns and (_is_scalar(v) or isinstance(v, (list, tuple))):
                columns.append(k)
    rows = [[_fmt_cell(item.get(c)) for c in columns] for item in items[:_MAX_ROWS]]
    table = _table(columns, rows)
    if len(items) > _MAX_ROWS:
        table += f"<p>{len(items) - _MAX_ROWS} more rows in summary.json.</p>"
    return table


def _fmt_cell(value):
    return _list_text(value) if isinstance(value, (list, tuple)) else value


def _figure(rel: str) -> str:
    url = _url(rel)
    return (f'<figure><a href="{url}"><img src="{url}" alt="{_esc(rel)}"></a>'
            f"<figcaption>{_esc(rel)}</figcaption></figure>")


# ------------------------------------------------------------------ files

def _folder_files(out: Path) -> dict[str, int]:
    """Relative POSIX path -> size of every file under ``out`` (sorted; hidden and
    temporary files and the report itself left out)."""
    found: dict[str, int] = {}
    if not out.is_dir():
        return found
    for root, dirs, files in os.walk(out):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for fname in sorted(files):
            if fname.startswith(".") or fname.endswith(".tmp"):
                continue
            path = Path(root) / fname
            rel = path.relative_to(out).as_posix()
            if rel == REPORT_NAME or not path.is_file():
                continue
            found[rel] = path.stat().st_size
            if len(found) >= _MAX_FILES:
                return found
    return found


def _record_files(out: Path, files) -> list[str]:
    """The paths in an analysis's ``files`` entry (any nesting of dicts and lists of
    strings), relative to ``out``; paths outside the folder are left out."""
    rels: list[str] = []
    for text in _strings(files):
        rel = _relative(out, Path(text))
        if rel is not None and rel not in rels:
            rels.append(rel)
    return rels


def _strings(value) -> Iterable[str]:
    if isinstance(value, (str, os.PathLike)):
        yield os.fspath(value)
    elif isinstance(value, dict):
        for v in value.values():
            yield from _strings(v)
    elif isinstance(value, (list, tuple)):
        for v in value:
            yield from _strings(v)


def _relative(out: Path, path: Path) -> str | None:
    base = out.resolve()
    for candidate in (path, out / path):
        try:
            rel = candidate.resolve().relative_to(base)
        except (ValueError, OSError):
            continue
        if rel.parts:
            return rel.as_posix()
    return None


# ------------------------------------------------------------------ HTML pieces

def _table(header: list[str], rows, raw: bool = False) -> str:
    """An HTML table; cells are formatted and escaped unless ``raw`` (already HTML)."""
    if not rows:
        return "<p>None.</p>"
    out = ["<table>", "<tr>" + "".join(f"<th>{_esc(h)}</th>" for h in header) + "</tr>"]
    for row in rows:
        cells = []
        for cell in row:
            if raw:
                cells.append(f"<td>{cell}</td>")
            elif _is_number(cell):
                cells.append(f'<td class="num">{_esc(_fmt(cell))}</td>')
            else:
                cells.append(f"<td>{_esc(_fmt(cell))}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def _status_badge(status: str) -> str:
    css = "status-" + "".join(c if c.isalnum() else "-" for c in status.lower())
    return f'<span class="status {css}">{_esc(status)}</span>'


def _link(rel: str) -> str:
    return f'<a href="{_url(rel)}">{_esc(rel)}</a>'


def _url(rel: str) -> str:
    return _esc(quote(rel))


def _anchor(name: str) -> str:
    return "a-" + "".join(c if c.isalnum() or c in "-_" else "-" for c in str(name))


def _size(n: int) -> str:
    for unit in ("B", "kB", "MB", "GB"):
        if n < 1024 or unit == "GB":
            return f"{n} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n} B"


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) or \
        (hasattr(value, "dtype") and hasattr(value, "item"))


def _is_scalar(value) -> bool:
    return value is None or isinstance(value, (str, bool, int, float)) or _is_number(value)


def _fmt(value) -> str:
    if hasattr(value, "dtype") and hasattr(value, "item"):
        try:
            value = value.item()
        except (ValueError, TypeError):
            return str(value)
    if value is None:
        return "n/a"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.6g}" if math.isfinite(value) else str(value)
    if isinstance(value, (list, tuple)):
        return _list_text(value)
    return str(value)


def _esc(value) -> str:
    return html.escape(str(value), quote=True)
