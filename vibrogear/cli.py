"""Command line: ``vibrogear run|check|sweep|continue|report|modes|time SCENE``."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["main"]

SINGLE = {"sweep": "sweep", "continue": "continuation", "report": "report",
          "modes": "modes", "campbell": "campbell", "time": "time_response"}


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vibrogear", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True)
    for name, helptext in [("run", "run the scene's analyses"), ("check", "validate the scene only"),
                           *[(k, f"run only the {v} analysis") for k, v in SINGLE.items()]]:
        sp = sub.add_parser(name, help=helptext)
        sp.add_argument("scene", help="scene TOML file")
        sp.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="SECTION.KEY=VALUE", help="override a config value (repeatable)")
        sp.add_argument("--out", default=None, help="output folder (default out/<scene name>)")
        sp.add_argument("--quiet", action="store_true", help="no progress bars")
    cache = sub.add_parser("cache", help="manage the on-disk cache")
    cache.add_argument("action", choices=["clear", "info"])
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    from .config import ConfigError, load_scene

    if args.command == "cache":
        from .cache import cache_dir, clear_cache
        if args.action == "clear":
            n = clear_cache()
            print(f"removed {n} cache entries from {cache_dir()}")
        else:
            print(cache_dir())
        return 0
    try:
        scene = load_scene(args.scene, tuple(args.overrides))
        if args.command in SINGLE:
            from .config.base import as_data, build
            from .config.scene import Scene
            data = as_data(scene)
            data["scene"]["analyses"] = [SINGLE[args.command]]
            scene = build(Scene, data)
    except ConfigError as exc:
        print(f"vibrogear: invalid input: {exc}", file=sys.stderr)
        return 2
    if args.command == "check":
        print(f"{args.scene}: ok ({scene.model_kind}; analyses: {', '.join(scene.scene.analyses)})")
        return 0
    from .runner import NumericalFailure, RunContext, run_scene

    out = Path(args.out) if args.out else Path("out") / scene.scene.name
    ctx = RunContext(out=out, quiet=args.quiet)
    try:
        summary = run_scene(scene, ctx, source=str(args.scene))
    except NumericalFailure as exc:
        print(f"vibrogear: numerical failure: {exc}", file=sys.stderr)
        return 1
    except (NotImplementedError, ConfigError) as exc:   # ConfigError: found building the model
        print(f"vibrogear: invalid input: {exc}", file=sys.stderr)
        return 2
    if not args.quiet:
        print(f"wrote {out}/ ({', '.join(summary['analyses'])}; "
              f"{summary['wall_time_s']['total']:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
