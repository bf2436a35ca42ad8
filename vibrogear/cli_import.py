"""``vibrogear import MODEL.rexs|.rexsj [-o SCENE.toml] [--housing box|CASING.step]``: the REXS model as a scene TOML.

The model is read and mapped (:mod:`vibrogear.config.rexs`), the scene validated exactly as
``vibrogear check`` validates it, and only then written (atomically), so a bad file writes
nothing and exits 2 naming the component and attribute.  The mapping report goes to stderr
and into the TOML header; without ``-o`` the scene goes to stdout.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

__all__ = ["import_command"]


def import_command(model: str, output: str | None, argv=None, housing: str | None = None,
                   fixed_region: str | None = None, length_unit: str = "m") -> int:
    from .config import ConfigError, scene_from_dict
    from .config.rexs import import_rexs, is_rexs_path
    from .config.rexs.scene_toml import scene_toml
    from .pipeline.files import atomic_write_bytes
    from .models.scene_notes import derived_lines
    from .models.validate import validate_scene
    try:
        if not is_rexs_path(model):
            raise ConfigError(model, "expected a REXS file named *.rexs (XML) or *.rexsj (JSON)")
        if output is not None and Path(output).is_dir():
            raise ConfigError(output, "is a folder; give the scene file to write")
        step, region = _step_casing(housing, fixed_region, length_unit)
        imp = import_rexs(model, housing=step or housing, fixed_region=region)
        scene = scene_from_dict(imp.data)
        validate_scene(scene)
        notes = derived_lines(scene)
        if step is not None:        # the scene file names the STEP file relative to itself
            imp.data["housing"]["file"] = (os.path.relpath(step, Path(output).resolve().parent)
                                           if output is not None else step)
    except ConfigError as exc:
        print(f"vibrogear: invalid input: {exc}", file=sys.stderr)
        return 2
    text = scene_toml(imp, "vibrogear import " + " ".join(argv or [model]))
    text += "".join(f"\n# derived: {n}" for n in notes) + "\n"
    for line in imp.report.lines() + [f"derived: {n}" for n in notes]:
        print(line, file=sys.stderr)
    if output is None:
        sys.stdout.write(text)
    else:
        try:
            atomic_write_bytes(Path(output), text.encode("utf-8"))
        except OSError as exc:
            print(f"vibrogear: invalid input: {output}: cannot write: {exc.strerror or exc}",
                  file=sys.stderr)
            return 2
        print(f"wrote {output} (scene {scene.scene.name!r}; check it with `vibrogear check "
              f"{output}`)", file=sys.stderr)
    return 0


def _step_casing(housing: str | None, fixed_region: str | None, length_unit: str):
    """(absolute path of the STEP casing or None, fixed_region in m or None); ConfigError
    naming the flag for a missing or unreadable file, a missing or malformed
    --fixed-region, or --fixed-region without a STEP casing."""
    from .config import ConfigError
    from .config.housing import LENGTH_UNITS, check_file
    from .config.rexs.mapping_casing_step import parse_fixed_region
    if housing is None or housing == "box" or Path(housing).suffix.lower() not in (".step", ".stp"):
        if fixed_region is not None:
            raise ConfigError("--fixed-region", "only with --housing CASING.step (the box "
                              "housing is clamped on its base plate)")
        return None, None
    f = check_file(housing, "step", "--housing")
    return str(f.resolve()), parse_fixed_region(fixed_region, LENGTH_UNITS[length_unit])
