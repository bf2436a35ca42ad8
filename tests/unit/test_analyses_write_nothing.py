"""Analyses compute, report/ writes (issue 19, item 1): no module in vibrogear/analyses/
imports matplotlib or vibrogear.report, at module level or inside a function."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ANALYSES = Path(__file__).resolve().parents[2] / "vibrogear" / "analyses"

#: modules allowed, for now, to import matplotlib or report/ (module name -> why); empty:
#: every analysis returns an AnalysisOutcome and its report writer writes the files
EXCEPTIONS: dict[str, str] = {}


def _imported(path: Path) -> list[tuple[str, int]]:
    """(absolute module name, line) of every import in ``path`` (relative imports resolved
    against vibrogear.analyses)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = ["vibrogear", "analyses"][:max(2 - (node.level - 1), 0)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out.append((mod, node.lineno))
            out += [(f"{mod}.{a.name}", node.lineno) for a in node.names]
    return out


def _forbidden(name: str) -> bool:
    return name.split(".")[0] == "matplotlib" or name == "vibrogear.report" \
        or name.startswith("vibrogear.report.")


MODULES = sorted(ANALYSES.glob("*.py"))


def test_analyses_found():
    assert len(MODULES) > 10


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.stem)
def test_analysis_imports_neither_matplotlib_nor_report(path):
    if path.stem in EXCEPTIONS:
        pytest.skip(EXCEPTIONS[path.stem])
    bad = sorted({(n, line) for n, line in _imported(path) if _forbidden(n)},
                 key=lambda x: x[1])
    assert not bad, f"{path.name} imports {bad}: move the file writing to a report writer"


def test_the_check_sees_a_forbidden_import(tmp_path):
    p = tmp_path / "x.py"
    p.write_text("def f():\n    from ..report.figure import new_figure\n"
                 "import matplotlib.pyplot as plt\n")
    names = [n for n, _ in _imported(p) if _forbidden(n)]
    assert "vibrogear.report.figure" in names and "matplotlib.pyplot" in names
