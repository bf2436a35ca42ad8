"""The pieces of ``report.html``: the folder's files and the links to them, tables, numbers
to their meaningful digits, escaping (:mod:`.html_report` composes the page from them)."""
from __future__ import annotations

import html
import math
import os
from pathlib import Path
from urllib.parse import quote

from ...pipeline.files import listed_paths

__all__ = ["REPORT_NAME", "folder_files", "record_files", "table", "records_table",
           "list_text", "status_badge", "link", "url", "anchor", "size", "fmt", "esc",
           "is_scalar"]

REPORT_NAME = "report.html"
_MAX_LIST = 12          # lists of numbers up to this length are shown whole
_MAX_ROWS = 60          # rows of a table of records
_MAX_FILES = 5000       # files listed from the folder
_DIGITS = 4             # significant digits of the numbers in tables


def list_text(values) -> str:
    if not values:
        return "[]"
    if len(values) <= _MAX_LIST and all(is_scalar(v) for v in values):
        return ", ".join(fmt(v) for v in values)
    if all(is_scalar(v) for v in values):
        first, second, last = (fmt(values[i]) for i in (0, 1, -1))
        return f"{len(values)} values: {first}, {second}, ..., {last}"
    if all(isinstance(v, dict) for v in values):
        shown = "; ".join(", ".join(f"{k} = {fmt(x)}" for k, x in v.items()
                                    if is_scalar(x)) for v in values[:6])
        return shown + (f"; ... ({len(values)} in all, see summary.json)"
                        if len(values) > 6 else "")
    return f"{len(values)} entries (see summary.json)"


def records_table(items: list[dict]) -> str:
    columns: list[str] = []
    for item in items:
        for k, v in item.items():
            if k not in columns and (is_scalar(v) or isinstance(v, (list, tuple))):
                columns.append(k)
    rows = [[_fmt_cell(item.get(c)) for c in columns] for item in items[:_MAX_ROWS]]
    text = table(columns, rows)
    if len(items) > _MAX_ROWS:
        text += f"<p>{len(items) - _MAX_ROWS} more rows in summary.json.</p>"
    return text


def _fmt_cell(value):
    return list_text(value) if isinstance(value, (list, tuple)) else value


# ------------------------------------------------------------------ files

def folder_files(out: Path) -> dict[str, int]:
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


def record_files(out: Path, files) -> list[str]:
    """The paths in an analysis's ``files`` entry (any nesting of dicts and lists of
    strings), relative to ``out``; paths outside the folder are left out."""
    rels: list[str] = []
    for text in listed_paths(files):
        rel = _relative(out, Path(text))
        if rel is not None and rel not in rels:
            rels.append(rel)
    return rels


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

def table(header: list[str], rows, raw: bool = False) -> str:
    """An HTML table; cells are formatted and escaped unless ``raw`` (already HTML)."""
    if not rows:
        return "<p>None.</p>"
    out = ['<div class="scroll"><table>',
           "<tr>" + "".join(f"<th>{esc(h)}</th>" for h in header) + "</tr>"]
    for row in rows:
        cells = []
        for cell in row:
            if raw:
                cells.append(f"<td>{cell}</td>")
            elif _is_number(cell):
                cells.append(f'<td class="num">{esc(fmt(cell))}</td>')
            else:
                cells.append(f"<td>{esc(fmt(cell))}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</table></div>")
    return "\n".join(out)


def status_badge(status: str) -> str:
    css = "status-" + "".join(c if c.isalnum() else "-" for c in status.lower())
    return f'<span class="status {css}">{esc(status)}</span>'


def link(rel: str) -> str:
    return f'<a href="{url(rel)}">{esc(rel)}</a>'


def url(rel: str) -> str:
    return esc(quote(rel))


def anchor(name: str) -> str:
    return "a-" + "".join(c if c.isalnum() or c in "-_" else "-" for c in str(name))


def size(n: int) -> str:
    for unit in ("B", "kB", "MB", "GB"):
        if n < 1024 or unit == "GB":
            return f"{n} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n} B"


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) or \
        (hasattr(value, "dtype") and hasattr(value, "item"))


def is_scalar(value) -> bool:
    return value is None or isinstance(value, (str, bool, int, float)) or _is_number(value)


def fmt(value, digits: int = _DIGITS) -> str:
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
        return f"{value:.{digits}g}" if math.isfinite(value) else str(value)
    if isinstance(value, (list, tuple)):
        return list_text(value)
    return str(value)


def esc(value) -> str:
    return html.escape(str(value), quote=True)
