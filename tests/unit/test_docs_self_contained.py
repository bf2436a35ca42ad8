"""The project's files stand alone: none cites a file outside the repository (a design note
or seed material next to the checkout), and every repository path the docs cite exists."""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: what the project consists of (paths relative to the repository root)
PROJECT = ["README.md", "Makefile", "pyproject.toml", "docs", "configs", "vibrogear", "tests",
           "benchmarks", "scripts"]
#: the prose that cites paths: README, docs, scene files, Makefile
DOCS = ["README.md", "Makefile", "docs", "configs"]

# built from pieces so that this file does not match itself
OUTSIDE = re.compile("|".join([
    r"\.\./" + "shared",                 # the folder next to the checkout
    r"(?<![\w.-])" + "shared" + r"/",    # its seed paths
    r"\bDESIGN" + r"(\.md)?\b",          # a design note that is not in the repository
]))
SKIP_DIRS = {"__pycache__", ".pytest_cache"}


def _files(entries):
    for entry in entries:
        path = ROOT / entry
        if path.is_file():
            yield path
        elif path.is_dir():
            for p in sorted(path.rglob("*")):
                if p.is_file() and not SKIP_DIRS & set(p.relative_to(ROOT).parts):
                    yield p


def _text(path: Path) -> str | None:
    data = path.read_bytes()
    if b"\0" in data[:8192]:
        return None                      # binary (meshes, STEP solids, figures)
    return data.decode("utf-8", errors="replace")


def _lines(paths):
    """(path, line number, line) of every text file among ``paths``."""
    for path in paths:
        text = _text(path)
        if text is not None:
            for i, line in enumerate(text.splitlines(), 1):
                yield path, i, line


def test_no_project_file_cites_outside_the_repository():
    hits = [f"{path.relative_to(ROOT)}:{i}: {line.strip()[:100]}"
            for path, i, line in _lines(_files(PROJECT)) if OUTSIDE.search(line)]
    assert not hits, "cites outside the repository:\n" + "\n".join(hits)


# a repository path with a file extension: from a top folder, or relative to vibrogear/
_PATH = re.compile(r"(?<![\w/.<-])((?:vibrogear|tests|benchmarks|configs|docs|scripts|config|"
                   r"geometry|models|pipeline|solvers|analyses|report|verification)"
                   r"/[\w/.*-]*\.(?:py|toml|md|json|sh|step|npz|csv))\b")


def test_cited_repository_paths_exist():
    missing = []
    for path, i, line in _lines(_files(DOCS)):
        for m in _PATH.finditer(line):
            cited = m.group(1)
            found = any(any(base.glob(cited)) if "*" in cited else (base / cited).exists()
                        for base in (ROOT, ROOT / "vibrogear"))
            if not found:
                missing.append(f"{path.relative_to(ROOT)}:{i}: {cited}")
    assert not missing, "cited paths that do not exist:\n" + "\n".join(missing)
