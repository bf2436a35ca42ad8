"""``vibrogear import MODEL.rexs|.rexsj [-o SCENE.toml]``: the REXS model as a scene TOML.

The model is read and mapped (:mod:`vibrogear.config.rexs`), the scene validated exactly as
``vibrogear check`` validates it, and only then written (atomically), so a bad file writes
nothing and exits 2 naming the component and attribute.  The mapping report goes to stderr
and into the TOML header; without ``-o`` the scene goes to stdout.
"""
from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["import_command"]


def import_command(model: str, output: str | None, argv=None, housing: str | None = None) -> int:
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
        imp = import_rexs(model, housing=housing)
        scene = scene_from_dict(imp.data)
        validate_scene(scene)
        notes = derived_lines(scene)
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
