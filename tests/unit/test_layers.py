"""The package's layers, checked on every module's imports.

The layer order is written once, in ``LAYERS`` below, and ``docs/architecture.md`` states the
same table (checked here too).  A module may import modules of its own layer and of any lower
layer, never of a higher one.  Every ``import`` statement counts, also those inside functions
(lazy imports) and under ``TYPE_CHECKING``.  Imports that break the order today are listed in
``KNOWN_EXCEPTIONS`` with their reason; an exception that no longer occurs fails the test too,
so the list (and the doc) stays true.  No two modules may import each other, directly or
through others (no import circles), whatever their layers.

Inside the packages built of wings (analyses/, config/, report/: ``WINGS``), an import from
one wing to another goes to a lower floor; and no module imports another module's private
(``_name``) names.
"""
from __future__ import annotations

import ast
import re
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PKG = ROOT / "vibrogear"
ARCH = ROOT / "docs" / "architecture.md"

#: layer of each part of the package (a folder ``name/`` or a top-level ``name.py``), lowest
#: first.  Equal numbers share a layer.  docs/architecture.md, section "Layers", has this table.
LAYERS = {
    "version.py": 0,        # the version
    "lazy.py": 0,           # lazy_exports: first-use re-export of a package's names
    "status.py": 0,         # the one status enumeration and Outcome (solvers, analyses, runner)
    "verification/": 0,     # exact references: share no code with what they check
    "config/": 1,
    "cache.py": 2,
    "geometry/": 3,
    "models/": 4,
    "pipeline/": 5,
    "solvers/": 6,
    "analyses/": 7,
    "report/": 8,
    "runner.py": 9,
    "api.py": 10,           # the Python API (load, replace, run): the CLI's layer, below it
    "cli.py": 10,
    "cli_import.py": 10,    # the `vibrogear import` command (REXS -> checked scene TOML)
    "__init__.py": 11,      # the package: the version and the API, re-exported on first use
}

#: floors inside the packages that are built of wings (a sub-package, or a module directly
#: under the package), lowest first.  An import from one part to another of the same package
#: goes to a lower floor, never sideways or up: in analyses/ the helpers every verb shares,
#: then the sweep (whose branches a continuation and the census start from), then the verbs;
#: in config/ the loader, the solvers' options, the machine (model/), the verbs' options
#: (sections/) and the REXS import, the scene that joins them; in report/ the figure base and
#: the file formats, the figures (plots/), the writers, the page.  docs/architecture.md,
#: section "Wings", has this table.
WINGS = {
    "analyses": {
        "static_load.py": 0, "mesh_loads.py": 0,
        "study.py": 1, "invoke.py": 1,
        "sweep/": 2,
        "continuation.py": 3, "critical_damping.py": 3, "gearbox_modes.py": 3, "nnm.py": 3,
        "precision.py": 3, "reduction_accuracy.py": 3, "rotor.py": 3, "time_response.py": 3,
        "findings/": 3, "housing/": 3, "map/": 3, "nvh/": 3, "optimize/": 3, "runup/": 3,
        "states/": 3,
    },
    "config": {
        "errors.py": 0, "numbers.py": 0, "verbs.py": 0,
        "base.py": 1, "overrides.py": 1,
        "options.py": 2,
        "model/": 3,
        "sections/": 4, "rexs/": 4,
        "scene.py": 5,
        "reference.py": 6,
    },
    "report": {
        "figure.py": 0, "sweep_files.py": 0, "branch_files.py": 0,
        "plots/": 1,
        "writers/": 2,
        "page/": 3,
    },
}

#: (importing module, imported module): why the import is allowed.  Empty: the 9 upward
#: imports (analyses -> report) that existed went away when every analysis got its report
#: writer.  An entry here must name its reason and appear in docs/architecture.md.
KNOWN_EXCEPTIONS: dict[tuple[str, str], str] = {}

#: the one upward import allowed by rule, not by pair: a result class's ``plot`` method (a
#: method named ``plot`` of a class in analyses/ or solvers/) may import its figure function
#: from report/ inside the method, so that a result draws itself (``run.results["sweep"]
#: .plot()``, docs/python.md) while the analyses still compute without matplotlib: the import
#: runs only when ``plot()`` is called.  The import-circle check still sees these imports.
PLOT_METHOD_FROM = ("vibrogear.analyses.", "vibrogear.solvers.")


def _plot_method_lines(path: Path) -> set[int]:
    """Lines of the import statements inside a ``plot`` method of a class."""
    lines = set()
    for cls in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if not isinstance(cls, ast.ClassDef):
            continue
        for fn in cls.body:
            if isinstance(fn, ast.FunctionDef) and fn.name == "plot":
                lines |= {n.lineno for n in ast.walk(fn)
                          if isinstance(n, (ast.Import, ast.ImportFrom))}
    return lines


def _plot_method_import(name: str, target: str, line: int, path: Path) -> bool:
    """Whether this import is a result's ``plot`` method importing its figure from report/."""
    return name.startswith(PLOT_METHOD_FROM) and target.startswith("vibrogear.report.") \
        and line in _plot_method_lines(path)


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PKG.rglob("*.py"))}


def _exists(name: str) -> bool:
    rel = Path(*name.split("."))
    return (ROOT / rel.with_suffix(".py")).is_file() or (ROOT / rel / "__init__.py").is_file()


def _from_target(name: str, path: Path, node: ast.ImportFrom) -> str:
    """The module a ``from ... import`` statement of module ``name`` names, relative ones
    resolved."""
    if not node.level:
        return node.module or ""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    base = package.split(".")
    base = base[:len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _all_imports(name: str, path: Path) -> list[tuple[str, int]]:
    """(imported module, line) for every import statement of the module, at module level or
    inside a function, the relative ones resolved; ``from pkg import sub`` counts as an
    import of ``pkg.sub`` where ``sub`` is a module of the package, else of ``pkg``."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            target = _from_target(name, path, node)
            for a in node.names:
                sub = f"{target}.{a.name}"
                out.append((sub if _exists(sub) else target, node.lineno))
    return out


def _imports(name: str, path: Path) -> list[tuple[str, int]]:
    """The imports of :func:`_all_imports` that are vibrogear modules."""
    return [(t, line) for t, line in _all_imports(name, path)
            if t == "vibrogear" or t.startswith("vibrogear.")]


def _part(module: str) -> str:
    """The LAYERS key of a module name."""
    parts = module.split(".")
    if len(parts) == 1:
        return "__init__.py"
    return f"{parts[1]}/" if (PKG / parts[1]).is_dir() else f"{parts[1]}.py"


def _edges() -> dict[tuple[str, str], list[int]]:
    edges: dict[tuple[str, str], list[int]] = defaultdict(list)
    for name, path in _modules().items():
        for target, line in _imports(name, path):
            if target != name:
                edges[(name, target)].append(line)
    return edges


def test_every_part_of_the_package_has_a_layer():
    parts = {_part(m) for m in _modules()}
    missing = sorted(parts - set(LAYERS))
    assert not missing, (f"{missing}: in no layer; add to LAYERS here and to the 'Layers' "
                         f"table of docs/architecture.md")
    stale = sorted(set(LAYERS) - parts)
    assert not stale, f"{stale}: in LAYERS but not in the package"


def test_imports_keep_the_layer_order():
    upward = {}
    mods = _modules()
    for (a, b), lines in _edges().items():
        lines = [n for n in lines if not _plot_method_import(a, b, n, mods[a])]
        if lines and LAYERS[_part(b)] > LAYERS[_part(a)]:
            upward[(a, b)] = lines
    new = {k: v for k, v in upward.items() if k not in KNOWN_EXCEPTIONS}
    assert not new, "imports from a higher layer (module -> imported, lines):\n" + "\n".join(
        f"  {a} -> {b} (line {', '.join(map(str, v))}): {_part(a)} is layer "
        f"{LAYERS[_part(a)]}, {_part(b)} is layer {LAYERS[_part(b)]}"
        for (a, b), v in sorted(new.items()))
    gone = sorted(set(KNOWN_EXCEPTIONS) - set(upward))
    assert not gone, (f"{gone}: no longer imported; remove from KNOWN_EXCEPTIONS and from "
                      f"docs/architecture.md")


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        found.append(sorted(comp))
    return found


def test_circle_finder_finds_a_circle():
    assert _circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _circles({"a": {"b"}, "b": set()}) == []


def test_no_import_circles():
    graph: dict[str, set[str]] = defaultdict(set)
    for a, b in _edges():
        graph[a].add(b)
        graph.setdefault(b, set())
    assert _circles(graph) == []


def _arch_section(title: str) -> str:
    text = ARCH.read_text()
    m = re.search(rf"^## {re.escape(title)}\n(.*?)(?=^## |\Z)", text, re.S | re.M)
    assert m, f"docs/architecture.md has no section '## {title}'"
    return m.group(1)


def test_architecture_doc_states_the_same_layers():
    stated = {}
    for line in _arch_section("Layers").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.lstrip().startswith("|") and cells[0].isdigit():
            for name in re.findall(r"`([^`]+)`", cells[1]):
                stated[name.removeprefix("vibrogear/")] = int(cells[0])
    assert stated == LAYERS


def test_architecture_doc_names_every_module():
    """Every module with code (empty package markers aside) has its line in the module list,
    and every module listed exists."""
    section = _arch_section("Modules")
    listed = re.findall(r"^- `([\w/]+\.py)`", section, re.M)
    assert len(listed) == len(set(listed)), "a module is listed twice"
    have = {str(p.relative_to(PKG)) for p in PKG.rglob("*.py")
            if p.name != "__init__.py" or p.read_text().strip()}
    assert sorted(have - set(listed)) == [], "modules missing from docs/architecture.md"
    assert sorted(set(listed) - have) == [], "docs/architecture.md lists modules that do not exist"


def _draws_or_writes(target: str) -> bool:
    return target.split(".")[0] == "matplotlib" or target == "vibrogear.report" \
        or target.startswith("vibrogear.report.")


def test_analyses_compute_and_report_writes():
    """No module in analyses/ imports matplotlib or report/ (inside functions included):
    an analysis returns an AnalysisOutcome and its report writer writes the files.  The one
    exception is a result's ``plot`` method (:data:`PLOT_METHOD_FROM`), which imports its
    figure function from report/ when called; never matplotlib itself."""
    analyses = {n: p for n, p in _modules().items() if n.startswith("vibrogear.analyses.")}
    assert len(analyses) > 10
    bad = {n: [(t, line) for t, line in _all_imports(n, p) if _draws_or_writes(t)
               and not _plot_method_import(n, t, line, p)]
           for n, p in analyses.items()}
    assert not {n: b for n, b in bad.items() if b}


def test_results_draw_themselves_through_report():
    """The result objects that ``vibrogear.api.run`` returns have a ``plot`` method that the
    rule above lets import report/; the rule sees no other function."""
    from vibrogear.analyses import gearbox_modes, time_response
    from vibrogear.analyses.states import states
    from vibrogear.analyses.sweep import sweep
    from vibrogear.analyses import continuation
    for cls in (time_response.TimeResponseResult, sweep.SweepStudyResult,
                continuation.ContinuationStudyResult, gearbox_modes.GearboxModesResult,
                states.StatesResult):
        assert callable(getattr(cls, "plot", None)) and callable(getattr(cls, "arrays", None))
    name = "vibrogear.analyses.time_response"
    p = _modules()[name]
    lines = _plot_method_lines(p)
    assert lines and all(_plot_method_import(name, "vibrogear.report.writers.time_response", n, p)
                         for n in lines)
    assert not _plot_method_import(name, "vibrogear.report.writers.time_response", 1, p)
    assert not _plot_method_import("vibrogear.report.x", "vibrogear.report.writers.time_response",
                                   min(lines), p)


def _verb_modules() -> dict[str, str]:
    """The analysis modules the verb registry runs (``Verb.runs``: ``module:function``), each
    with its registry target: a wing (``states:run``, a package under analyses/) counts as its
    package and its verb's module of the same name (``analyses/states/states.py``); the wing's
    helpers may serve other verbs."""
    from vibrogear.config.verbs import VERBS
    out = {}
    for verb in VERBS.values():
        for run in verb.runs.values():
            target = run.analysis.split(":")[0]
            name = f"vibrogear.analyses.{target}"
            out[name] = target
            if (PKG / "analyses" / Path(*target.split(".")) / "__init__.py").is_file():
                out[f"{name}.{target.split('.')[-1]}"] = target
    return out


def _imports_of_verbs(edges, verb_modules) -> dict[tuple[str, str], list[int]]:
    """The edges from a module under analyses/ to a verb's analysis module other than its own."""
    return {(a, b): lines for (a, b), lines in edges.items()
            if a.startswith("vibrogear.analyses.") and b in verb_modules
            and verb_modules.get(a) != verb_modules[b]}


def test_verbs_import_no_verbs():
    """No module under analyses/ (a verb's or a helper) imports a verb's analysis module,
    inside functions included: what verbs share lives in a helper, a lower layer or the
    config layer, and a verb that needs another's outcome declares it (``Verb.needs``,
    ``Verb.reads_saved``) instead of running it.  So no verb reaches another through a helper."""
    verbs = _verb_modules()
    assert len(verbs) > 10
    bad = _imports_of_verbs(_edges(), verbs)
    assert not bad, "a verb's analysis module imported by another analysis module:\n" + \
        "\n".join(f"  {a} -> {b} (line {', '.join(map(str, v))})" for (a, b), v in sorted(bad.items()))


def test_the_verb_rule_sees_a_verb_importing_a_verb():
    verbs = _verb_modules()
    assert {"vibrogear.analyses.sweep", "vibrogear.analyses.sweep.sweep",
            "vibrogear.analyses.gearbox_modes", "vibrogear.analyses.nvh.nvh",
            "vibrogear.analyses.continuation"} <= set(verbs)
    assert "vibrogear.analyses.sweep.branches" not in verbs
    edges = {("vibrogear.analyses.gearbox_modes", "vibrogear.analyses.sweep.sweep"): [19],
             ("vibrogear.analyses.continuation", "vibrogear.analyses.sweep"): [12],
             ("vibrogear.analyses.nvh.line_sources", "vibrogear.analyses.gearbox_modes"): [95],
             ("vibrogear.analyses.nvh.nvh", "vibrogear.analyses.nvh.line_sources"): [39],
             ("vibrogear.analyses.nvh", "vibrogear.analyses.nvh.nvh"): [30],
             ("vibrogear.analyses.continuation", "vibrogear.analyses.sweep.branches"): [5],
             ("vibrogear.analyses.sweep.sweep", "vibrogear.analyses.study"): [27],
             ("vibrogear.runner", "vibrogear.analyses.sweep.sweep"): [1]}
    assert sorted(_imports_of_verbs(edges, verbs)) == [
        ("vibrogear.analyses.continuation", "vibrogear.analyses.sweep"),
        ("vibrogear.analyses.gearbox_modes", "vibrogear.analyses.sweep.sweep"),
        ("vibrogear.analyses.nvh.line_sources", "vibrogear.analyses.gearbox_modes")]


def test_the_import_reader_sees_imports_inside_functions(tmp_path):
    p = tmp_path / "x.py"
    p.write_text("def f():\n    from ..report.figure import new_figure\n"
                 "import matplotlib.pyplot as plt\n")
    names = [t for t, _ in _all_imports("vibrogear.analyses.x", p) if _draws_or_writes(t)]
    assert "vibrogear.report.figure" in names and "matplotlib.pyplot" in names


def test_pipeline_imports_only_config():
    """pipeline/ (files, cache of runs, executors, progress, the outcome) imports config and
    the ground floor only: the scene checks that need a model live in models/validate.py."""
    allowed = ("vibrogear.config", "vibrogear.pipeline", "vibrogear.status", "vibrogear.version")
    bad = [(name, imported, line) for name, path in _modules().items()
           if name.startswith("vibrogear.pipeline")
           for imported, line in _all_imports(name, path)
           if imported.startswith("vibrogear") and not
           (imported in allowed or imported.startswith(tuple(a + "." for a in allowed[:3])))]
    assert not bad, bad


def _wing(module: str) -> tuple[str, str] | None:
    """(package, part) of a module inside a package of :data:`WINGS`, else None."""
    parts = module.split(".")
    if len(parts) < 3 or parts[1] not in WINGS:
        return None
    return parts[1], f"{parts[2]}/" if (PKG / parts[1] / parts[2]).is_dir() else f"{parts[2]}.py"


def test_every_wing_has_a_floor():
    have = {_wing(m) for m in _modules()} - {None}
    listed = {(pkg, part) for pkg, floors in WINGS.items() for part in floors}
    assert sorted(have - listed) == [], "parts of a winged package without a floor in WINGS"
    assert sorted(listed - have) == [], "WINGS names parts that do not exist"


def test_imports_between_wings_go_down():
    bad = []
    for (a, b), lines in _edges().items():
        wa, wb = _wing(a), _wing(b)
        if wa and wb and wa[0] == wb[0] and wa[1] != wb[1]:
            floors = WINGS[wa[0]]
            if floors[wb[1]] >= floors[wa[1]]:
                bad.append(f"  {a} -> {b} (line {', '.join(map(str, lines))}): {wa[1]} is on "
                           f"floor {floors[wa[1]]}, {wb[1]} on floor {floors[wb[1]]}")
    assert not bad, f"{wa[0] if bad else ''} imports sideways or up:\n" + "\n".join(sorted(bad))


def test_architecture_doc_states_the_same_wings():
    stated: dict = {}
    for line in _arch_section("Wings").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.lstrip().startswith("|") and len(cells) == 3 and cells[1].isdigit():
            pkg = cells[0].strip("`/")
            for name in re.findall(r"`([^`]+)`", cells[2]):
                stated.setdefault(pkg, {})[name] = int(cells[1])
    assert stated == WINGS


def _private_imports(name: str, path: Path) -> list[tuple[str, str, int]]:
    """(imported module, private name, line) for each ``from M import _x`` of a vibrogear
    module M other than the importing one (inside functions included)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.ImportFrom):
            target = _from_target(name, path, node)
            if target.split(".")[0] != "vibrogear" or target == name:
                continue
            out += [(target, a.name, node.lineno) for a in node.names
                    if a.name.startswith("_") and not a.name.startswith("__")]
    return out


def test_no_module_imports_another_modules_private_names():
    """A name that another module needs is public in the module that defines it (or the
    two modules are one); ``_name`` stays private to its module."""
    bad = [f"  {n}:{line} imports {t}.{x}" for n, p in _modules().items()
           for t, x, line in _private_imports(n, p)]
    assert not bad, "imports of private names:\n" + "\n".join(bad)


def test_the_private_name_rule_sees_a_private_import(tmp_path):
    p = tmp_path / "x.py"
    p.write_text("from .study import _helper, public\nfrom vibrogear.status import Outcome\n"
                 "def f():\n    from ..report.figure import _private\n")
    assert _private_imports("vibrogear.analyses.x", p) == [
        ("vibrogear.analyses.study", "_helper", 1), ("vibrogear.report.figure", "_private", 4)]
