"""``vibrogear import MODEL.rexs|.rexsj [-o SCENE.toml] [--housing box|CASING.step ...]``: the
REXS model as a scene TOML.

The model is read and mapped (:mod:`vibrogear.config.rexs`), the scene validated exactly as
``vibrogear check`` validates it, and only then written (atomically), so a bad file writes
nothing and exits 2 naming the component and attribute.  The mapping report goes to stderr
and into the TOML header; without ``-o`` the scene goes to stdout.  With a STEP casing the
file is read here too (:func:`_seat_radii_from_step`, :func:`_check_step_faces`: the same face
selection the housing run makes), so a casing without a bearing's seat or a fixed region that
clamps nothing exits 2 before anything is written.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

__all__ = ["import_command"]


def import_command(model: str, output: str | None, argv=None, housing: str | None = None,
                   fixed_region: str | None = None, length_unit: str = "m",
                   load_case: int | None = None) -> int:
    from .config import ConfigError, scene_from_dict
    from .config.rexs import import_rexs, is_rexs_path
    from .config.rexs.mapping import MappingStopped
    from .config.rexs.scene_toml import scene_toml
    from .pipeline.files import atomic_write_bytes
    from .models.scene_notes import derived_lines
    from .models.validate import validate_scene
    imp = None
    try:
        if not is_rexs_path(model):
            raise ConfigError(model, "expected a REXS file named *.rexs (XML) or *.rexsj (JSON)")
        if output is not None and Path(output).is_dir():
            raise ConfigError(output, "is a folder; give the scene file to write")
        step, region = _step_casing(housing, fixed_region, length_unit)
        imp = import_rexs(model, housing=step or housing, fixed_region=region,
                          load_case=load_case)
        if step is not None:
            samples = _seat_radii_from_step(imp, step)
        scene = scene_from_dict(imp.data)
        validate_scene(scene)
        if step is not None:
            _check_step_faces(scene.housing, samples, step)
        notes = derived_lines(scene)
        if step is not None:        # the scene file names the STEP file relative to itself
            imp.data["housing"]["file"] = (os.path.relpath(step, Path(output).resolve().parent)
                                           if output is not None else step)
    except MappingStopped as exc:
        return _stopped(exc.errors, exc.draft, output, argv or [model])
    except ConfigError as exc:
        if imp is not None and exc.path != "--housing":    # mapped, but the scene does not check
            return _stopped(exc.errors, imp, output, argv or [model])
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


def draft_path(output: str) -> Path:
    """``scene.toml`` -> ``scene.draft.toml`` (beside it)."""
    p = Path(output)
    return p.with_name((p.stem if p.suffix.lower() == ".toml" else p.name) + ".draft.toml")


def _stopped(errors: list, draft, output: str | None, argv) -> int:
    """The mapping stopped: every problem on stderr, the draft scene written beside the
    scene file asked for (``-o scene.toml`` -> ``scene.draft.toml``, which ``vibrogear check``
    refuses until its first line is deleted); exit 2."""
    from .config.base import DRAFT_MARKER
    from .config.rexs.scene_toml import scene_toml
    from .pipeline.files import atomic_write_bytes
    import re
    n = len(errors)

    def origin(e) -> str:          # a scene field's REXS component, from the draft's comments
        m = re.match(r"gearbox\.(\w+)\[(\d+)\]", str(getattr(e, "path", "")))
        c = draft.comments.get((m.group(1), int(m.group(2)))) if m and draft else None
        return f" [{c}]" if c else ""
    lines = [f"{k + 1}. {e}{origin(e)}" for k, e in enumerate(errors)]
    print(f"vibrogear: invalid input: the import stopped on {n} problem{'s' * (n != 1)} "
          "(each names the REXS component, the attribute and the fix):", file=sys.stderr)
    for line in lines:
        print(f"  {line}", file=sys.stderr)
    if output is None:
        print("(with -o SCENE.toml the scene as far as it was mapped is written as "
              "SCENE.draft.toml)", file=sys.stderr)
        return 2
    head = [f"{DRAFT_MARKER} the import stopped on {n} problem{'s' * (n != 1)}; "
            f"`vibrogear check` refuses this file until {'they are' if n != 1 else 'it is'} "
            "fixed and this line deleted",
            *[f"# {x}" for line in lines for x in line.splitlines()], ""]
    try:
        body = scene_toml(draft, "vibrogear import " + " ".join(argv))
    except (KeyError, TypeError, ValueError, AttributeError, IndexError):
        body = "# (the mapped part could not be written as TOML)"
    path = draft_path(output)
    try:
        atomic_write_bytes(path, ("\n".join(head) + body + "\n").encode("utf-8"))
    except OSError as exc:
        print(f"vibrogear: {path}: cannot write the draft: {exc.strerror or exc}",
              file=sys.stderr)
        return 2
    print(f"wrote the draft {path} (the scene as far as it was mapped; nothing else written)",
          file=sys.stderr)
    return 2


def _step_casing(housing: str | None, fixed_region: str | None, length_unit: str):
    """(absolute path of the STEP casing or None, fixed_region in m or None); ConfigError
    naming the flag for a missing or unreadable file, a missing or malformed
    --fixed-region, or --fixed-region without a STEP casing."""
    from .config import ConfigError
    from .config.model.housing import LENGTH_UNITS, check_file
    from .config.rexs.mapping_casing_step import parse_fixed_region
    if housing is None or housing == "box" or Path(housing).suffix.lower() not in (".step", ".stp"):
        if fixed_region is not None:
            raise ConfigError("--fixed-region", "only with --housing CASING.step (the box "
                              "housing is clamped on its base plate)")
        return None, None
    f = check_file(housing, "step", "--housing")
    return str(f.resolve()), parse_fixed_region(fixed_region, LENGTH_UNITS[length_unit])


def _step_faces(file: str) -> tuple[dict, float]:
    """({boundary face: sample points (n, 3) in m}, diagonal of the bounding box in m) of the
    STEP solid, read as the housing run reads it (gmsh's OpenCASCADE, in metres)."""
    from .config import ConfigError
    from .geometry.housing import MeshingError, gmsh_session
    from .geometry.housing_import import face_samples
    import numpy as np
    try:
        with gmsh_session(False) as gmsh:
            gmsh.option.setString("Geometry.OCCTargetUnit", "M")
            try:
                gmsh.model.occ.importShapes(file)
            except Exception:
                msg = gmsh.logger.getLastError() or "OpenCASCADE could not read it"
                raise ConfigError("--housing", f"{file}: not a readable STEP file ({msg})") from None
            gmsh.model.occ.synchronize()
            vols = gmsh.model.getEntities(3)
            if not vols:
                raise ConfigError("--housing", f"{file}: holds no solid (an open shell or surface "
                                  "model cannot be meshed with tetrahedra)")
            bbox = gmsh.model.getBoundingBox(-1, -1)
            faces = sorted({abs(t) for _, t in gmsh.model.getBoundary(vols, combined=True,
                                                                      oriented=False)})
            return ({f: face_samples(gmsh, f) for f in faces},
                    float(np.linalg.norm(np.subtract(bbox[3:], bbox[:3]))))
    except MeshingError as exc:
        raise ConfigError("--housing", f"{file}: not a readable STEP file ({exc})") from None


def _seat_radii_from_step(imp, file: str) -> tuple[dict, float]:
    """Read the STEP casing; each bore takes the radius of the boundary cylinder about its line
    (within its search window) nearest to its bearing's, reported where they differ.
    ConfigError naming the bore and the file where no such cylinder exists."""
    import numpy as np
    from .config import ConfigError
    from .config.rexs.mapping_casing_step import set_mesh_size
    from .geometry.housing_import import bore_segments
    samples, scale = _step_faces(file)
    for b in imp.data["housing"]["bores"]:
        c, u, half = np.asarray(b["center"]), np.asarray(b["axis"]), 0.5 * b["length"]
        radii, spans = [], []
        for pts in samples.values():
            d = pts - c
            s = d @ u
            r = np.linalg.norm(d - s[:, None] * u, axis=1)
            if s.min() >= -half - 1e-5 and s.max() <= half + 1e-5 and r.min() > 1e-6 \
                    and r.max() - r.min() <= 1e-6 + 1e-4 * r.mean():
                radii.append(float(r.mean()))
                spans.append((float(s.min()), float(s.max())))
        want = b["bore_radius"]
        if not radii:
            raise ConfigError("--housing", f"{file}: bore {b['name']!r}: no boundary cylinder "
                              f"about the shaft axis through {b['center']} (m) along y within "
                              f"+-{half * 1e3:.4g} mm of the bearing plane; is the casing in the "
                              "housing frame of --housing box (docs/your-gearbox.md)?")
        got = min(radii, key=lambda r: abs(r - want))
        segs = bore_segments([sp for r, sp in zip(radii, spans)
                              if abs(r - got) <= 1e-6 + 1e-4 * got], 1e-6 * scale)
        if len(segs) > 1:          # other seats of this radius in the window: the nearest only
            s0, s1, _ = min(segs, key=lambda g: 0.0 if g[0] <= 0.0 <= g[1] else min(abs(g[0]), abs(g[1])))
            b["length"] = round(2 * max(abs(s0), abs(s1)) + 1e-4, 9)
            imp.report.assumed.append(
                f"gear_casing: housing bore {b['name']!r}: {len(segs)} separate seats of radius "
                f"{got * 1e3:.4g} mm in its window; length {b['length'] * 1e3:.4g} mm takes the "
                "one at the bearing")
        if abs(got - want) > 1e-6 + 1e-4 * want:
            b["bore_radius"] = round(got, 9)
            imp.report.assumed.append(
                f"gear_casing: housing bore {b['name']!r}: the STEP casing has no seat of the "
                f"bearing's radius {want * 1e3:.4g} mm there; its coaxial cylinder nearest to "
                f"it, radius {got * 1e3:.4g} mm, is taken as the bore")
    set_mesh_size(imp.data, imp.report)
    return samples, scale


def _check_step_faces(housing, samples: tuple[dict, float], file: str) -> None:
    """The bore and clamped-face selection the housing run will make, done now: ConfigError
    naming the bore (or --fixed-region) where it selects nothing or clamps a bore."""
    from .config import ConfigError
    from .geometry.housing_import import fixed_faces, select_bores
    faces, scale = samples
    bores, groups = select_bores(housing, faces, file, scale)
    split = sorted({g.name.rpartition("/")[0] for g in bores if g.name.count("/") > 1})
    if split:
        raise ConfigError("--housing", f"{file}: bore {split[0]!r} finds separate seats within "
                          "its search window (its length along the axis): the bearings' seats "
                          "on one axis are closer than the window; shorten that bore's length "
                          "in the scene")
    try:
        fixed_faces(housing, faces, groups, file)
    except ConfigError as exc:
        raise ConfigError("--fixed-region", str(exc).partition(": ")[2]) from None
