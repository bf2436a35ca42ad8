"""Command line: ``vibrogear COMMAND SCENE`` (``run`` the scene's analyses, ``check`` it, or
one verb alone: ``time``, ``sweep``, ``continue``, ... as the verb registry names them),
``vibrogear import MODEL.rexs [-o SCENE.toml]``, ``vibrogear compare RUN_A RUN_B`` and
``vibrogear cache clear|info``.  ``vibrogear --help`` lists every command (the list is read
from the parser, so it stays whole).

Exit codes: 0 done; 1 a numerical failure (the message says where and why) or an analysis
that produced nothing; 2 invalid input (a scene, an option, an output folder, the cache
folder), found before anything is written; 130 interrupted (Ctrl-C): what finished is kept
and the same command resumes.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .config.verbs import VERBS

__all__ = ["main", "EXIT_OK", "EXIT_FAILED", "EXIT_INPUT", "EXIT_INTERRUPTED"]

EXIT_OK, EXIT_FAILED, EXIT_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130

#: ``vibrogear COMMAND SCENE`` -> the one analysis it runs (from the verb registry)
SINGLE = {v.command: v.name for v in VERBS.values() if v.command}


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vibrogear", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    for name, helptext in [("run", "run the scene's analyses"), ("check", "validate the scene "
                            "(and the output folder) only"),
                           *[(k, f"run only the {v} analysis: {VERBS[v].help}") for k, v in SINGLE.items()]]:
        sp = sub.add_parser(name, help=helptext)
        sp.add_argument("scene", help="scene TOML file (or a REXS model, .rexs / .rexsj)")
        sp.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="SECTION.KEY=VALUE", help="override a config value (repeatable); "
                        "list entries as printed, e.g. gearbox.gears[0].teeth=30")
        sp.add_argument("--out", default=None, help="output folder (default out/<scene name>)")
        sp.add_argument("--quiet", action="store_true", help="no progress bars")
        sp.add_argument("--wait", action="store_true", help="if another run holds the output "
                        "folder, wait for it to end (default: exit 2 naming it)")
    imp = sub.add_parser("import", help="a REXS gearbox model (.rexs XML, .rexsj JSON) as "
                         "an editable scene TOML, with its mapping report")
    imp.add_argument("model", help="REXS file (.rexs or .rexsj)")
    imp.add_argument("-o", "--output", default=None, metavar="SCENE.toml",
                     help="scene file to write (default: the scene on stdout)")
    imp.add_argument("--housing", default=None, metavar="box|CASING.step",
                     help="'box': generate a parametric box housing around the shafts; a STEP "
                     "file: the casing from CAD, in the box's housing frame (default: the "
                     "casing is rigid ground)")
    imp.add_argument("--fixed-region", default=None, metavar="XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX",
                     help="with a STEP casing (required): the box around its clamped faces "
                     "(e.g. the undersides of the feet), housing frame")
    imp.add_argument("--length-unit", default="m", choices=["m", "mm"],
                     help="unit of the --fixed-region numbers (default m)")
    imp.add_argument("--load-case", default=None, type=int, metavar="N",
                     help="the load case of the file's load spectrum to take as the operating "
                     "point (1-based; default: the one with the largest duration share)")
    cmp = sub.add_parser("compare", help="two runs' findings side by side (bands added, "
                         "removed, moved; kv peaks; rattle levels; verdicts) and compare.html")
    cmp.add_argument("run_a", help="the first run's output folder (its summary.json)")
    cmp.add_argument("run_b", help="the second run's output folder")
    cmp.add_argument("--out", default=None, help="folder for compare.html (default RUN_B)")
    cache = sub.add_parser("cache", help="manage the on-disk cache")
    cache.add_argument("action", choices=["clear", "info"])
    p.description = _description(list(sub.choices))
    return p


def _description(commands: list[str]) -> str:
    """The help's first lines: every command by name, then the exit codes."""
    _, _, codes = (__doc__ or "").partition("\n\nExit codes")
    import textwrap
    listed = textwrap.fill(f"{len(commands)} commands: {', '.join(commands)}.", 79)
    return (f"{listed}\nRun `vibrogear COMMAND --help` for one command's options.\n\n"
            f"Exit codes{codes}")


def _error(kind: str, exc: BaseException) -> None:
    print(f"vibrogear: {kind}: {exc}", file=sys.stderr)


def _cache(action: str) -> int:
    from .cache import cache_dir, cache_info, clear_cache
    from .config import ConfigError
    try:
        if action == "clear":
            n, kept = clear_cache()
            print(f"removed {n} cache entries from {cache_dir()}"
                  + (f" (left {kept} files it did not write)" if kept else ""))
        else:
            info = cache_info()
            print(f"{cache_dir()}: {info['entries']} entries, {info['bytes'] / 2**20:.1f} MiB")
    except ConfigError as exc:
        _error("invalid input", exc)
        return EXIT_INPUT
    return EXIT_OK


def _compare(run_a: str, run_b: str, out: str | None) -> int:
    """``vibrogear compare``: both runs' findings on the console and in compare.html."""
    from .analyses.findings.compare import compare_findings, read_findings
    from .report.writers.compare import COMPARE_HTML, compare_lines, write_compare_html
    try:
        a, b = read_findings(run_a), read_findings(run_b)
    except ValueError as exc:
        _error("invalid input", exc)
        return EXIT_INPUT
    c = compare_findings(a, b)
    path = write_compare_html(c, __import__("pathlib").Path(out or run_b) / COMPARE_HTML)
    print("\n".join(compare_lines(c) + [f"open {path}"]))
    return EXIT_OK


def main(argv: list[str] | None = None) -> int:
    try:
        return _main(argv)
    except KeyboardInterrupt as exc:
        print("\nvibrogear: interrupted", file=sys.stderr)
        return _interrupted_code(exc)


def _interrupted_code(exc: BaseException) -> int:
    """130 for Ctrl-C, 128 + the signal number for SIGTERM (143) and SIGHUP (129)."""
    return 128 + exc.signum if hasattr(exc, "signum") else EXIT_INTERRUPTED


def _handle_stop_signals() -> None:
    """SIGTERM and SIGHUP behave as Ctrl-C: they raise :class:`Terminated` (a
    KeyboardInterrupt) in the main thread, so every interrupt path keeps what finished."""
    import signal
    import threading

    from .pipeline.units_base import Terminated, request_stop, stop_deferred

    if threading.current_thread() is not threading.main_thread():
        return

    def stop(signum, _frame):
        # worker processes (run_units) get the signal too, as a terminal's Ctrl-C reaches
        # the whole process group; the pool then ends instead of finishing its units
        # the signal can arrive while multiprocessing is being imported (its first use, in
        # run_units): a module not yet initialised has no children to stop
        active = getattr(sys.modules.get("multiprocessing"), "active_children", None)
        for child in active() if active is not None else ():
            child.terminate()
        if stop_deferred():                     # the pool's wait loop raises it
            request_stop(signum)
        else:
            raise Terminated(signum)
    for sig in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, stop)


def _main(argv: list[str] | None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "cache":
        return _cache(args.action)
    if args.command == "compare":
        return _compare(args.run_a, args.run_b, args.out)
    if args.command == "import":
        from .cli_import import import_command
        return import_command(args.model, args.output, argv, housing=args.housing,
                              fixed_region=args.fixed_region, length_unit=args.length_unit,
                              load_case=args.load_case)
    from . import api
    from .config import ConfigError
    from .pipeline.files import check_output_dir

    from .config import load_scene

    try:
        # read and overridden here, checked below for the analyses this command runs (a
        # verb on a scene that lists continuation beyond the period limit still runs)
        scene = load_scene(args.scene, tuple(args.overrides))
        if args.command in SINGLE:
            scene = api.with_analyses(scene, [SINGLE[args.command]])
        out = (check_output_dir(args.out) if args.out is not None else
               check_output_dir(Path("out") / scene.scene.name, "scene.name"))
        api.check(scene, files=args.command == "check")
    except (ConfigError, NotImplementedError) as exc:
        _error("invalid input", exc)
        return EXIT_INPUT
    if args.command == "check":
        from .models.scene_notes import derived_lines
        for line in derived_lines(scene):
            print(f"  {line}")
        if scene.gearbox is not None and scene.gearbox.couplings:
            from .analyses.static_load import rigid_housing, static_load
            try:      # check builds no housing FE model: the housing rigid here
                lp = static_load(rigid_housing(scene), source=str(args.scene)).load_path
            except ConfigError as exc:
                _error("invalid input", exc)
                return EXIT_INPUT
            for line in lp.table_lines():
                print(f"  {line}")
            if scene.housing is not None:
                print("  (the housing rigid in `check`; `run` reports the load path with its "
                      "modes)")
        print(f"{args.scene}: ok ({scene.model_kind}; analyses: {', '.join(scene.scene.analyses)};"
              f" output folder {out}/)")
        return EXIT_OK
    from .runner import NumericalFailure, WriteFailure

    from .pipeline.outcome import LostUnits
    from .pipeline.run_lock import FolderInUse

    _handle_stop_signals()
    try:
        # the API's run: the folder's lock, the compile notice, every file the run writes
        summary = api.run(scene, out=out, quiet=args.quiet, wait=args.wait,
                          source=str(args.scene)).summary
    except FolderInUse as exc:
        _error("invalid input", exc)
        return EXIT_INPUT
    except KeyboardInterrupt as exc:
        by = f" by {exc.name}" if hasattr(exc, "signum") else ""
        print(f"\nvibrogear: interrupted{by}; finished results and partial files are kept in "
              f"{out}/. Run the same command again to resume: points computed with the same "
              "physics, grid, options and version are reused.", file=sys.stderr)
        return _interrupted_code(exc)
    except LostUnits as exc:                   # an MPI rank died; the others finished
        _error("lost MPI rank", exc)
        return EXIT_FAILED
    except NumericalFailure as exc:
        _error("numerical failure", exc)
        return EXIT_FAILED
    except WriteFailure as exc:
        _error("write failed", exc)
        return EXIT_FAILED
    except (NotImplementedError, ConfigError) as exc:   # ConfigError: found building the model
        _error("invalid input", exc)
        return EXIT_INPUT
    _print_end(summary, out, args.quiet)
    return EXIT_FAILED if summary.get("status") == "failed" else EXIT_OK


def _print_end(summary: dict, out: Path, quiet: bool) -> None:
    """The run's last lines: what was written, optimize's best point, then the findings (at
    most ~10 lines) and where the report is; ``--quiet``: the verdict alone."""
    from .pipeline.outcome import is_root_process
    findings = summary.get("findings")
    if not quiet:
        print(f"wrote {out}/ ({', '.join(summary['analyses'])}; computation "
              f"{summary.get('status', 'ok')}; {summary['wall_time_s']['total']:.3g} s)")
        if "best" in summary["results"].get("optimize", {}):
            print(_optimize_line(summary["results"]["optimize"]))
    if findings is not None and is_root_process() and (findings["checked"] or quiet):
        from .report.writers.findings import console_lines
        for line in console_lines(findings, f"{out}/report.html", quiet=quiet):
            print(line)
    elif not quiet:                  # nothing over speed to judge (modes, optimize, ...)
        print(f"open {out}/report.html")


def _optimize_line(res: dict) -> str:
    """``optimize``'s answer in one line: the best point, its objective, how it ended."""
    b, o = res["best"], res["objective"]
    point = ", ".join(f"{k} = {v:.6g}" for k, v in b["values"].items())
    what = o["metric"] if o["analysis"] is None else f"{o['reduce']} {o['metric']}"
    head = "best" if b["feasible"] else "no feasible point; least infeasible"
    return (f"{head}: {point} ({o['sense']} {what} = {b['objective']:.6g}; "
            f"evaluation {b['evaluation']} of {res['evaluations']}; {res['stop']})")


if __name__ == "__main__":
    sys.exit(main())
