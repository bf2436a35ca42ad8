"""A scene: one TOML file read once into a frozen, validated :class:`Scene`."""
from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .base import ConfigError, ErrorList, as_data, build, read_toml_file, spec
from .overrides import parse_key, parse_override, set_path
from .sections.findings import FindingsConfig
from .model.gearbox import GearboxConfig
from .model.housing import HousingConfig, resolve_file
from .model.housing_sizing import fill_housing
from .sections.housing import HousingConvergenceConfig, HousingSweepConfig
from .sections.map import MapConfig
from .sections.nvh import NvhConfig
from .sections.nnm import NnmConfig
from .sections.optimize import OptimizeConfig
from .options import Parameter
from .model.rotor import RotorConfig
from .sections.runup import RunupConfig
from .sections.states import RpmStatesConfig, StatesConfig
from .verbs import MODEL_KINDS, VERBS
from .sections.common import (ContinuationConfig, CriticalDampingConfig, FiguresConfig,
    ImpactPairConfig, IntegrationOptions, ReductionAccuracyConfig, ReportConfig,
    RpmContinuationConfig, RpmSweepConfig, RpmTimeResponseConfig, SceneInfo, ShootingOptions,
    SweepConfig, TimeResponseConfig)

__all__ = ["Scene", "GearboxScene", "load_scene", "scene_from_dict", "read_toml", "MODEL_SECTIONS"]

#: sections that define the mechanical model; a scene has exactly one kind of model
MODEL_SECTIONS = MODEL_KINDS

#: analysis -> option section it needs (None: needs none); from the verb registry
ANALYSIS_SECTION = {name: v.section for name, v in VERBS.items()}

#: analysis -> model sections that support it; from the verb registry
ANALYSIS_MODELS = {name: v.models for name, v in VERBS.items()}


@dataclass(frozen=True)
class Scene:
    scene: SceneInfo = spec()
    impact_pair: ImpactPairConfig | None = spec(None)
    gearbox: GearboxConfig | None = spec(None)
    rotor: RotorConfig | None = spec(None)
    housing: HousingConfig | None = spec(None)
    housing_sweep: HousingSweepConfig | None = spec(None)
    housing_convergence: HousingConvergenceConfig | None = spec(None)
    integration: IntegrationOptions = spec(IntegrationOptions())
    shooting: ShootingOptions = spec(ShootingOptions())
    sweep: SweepConfig | None = spec(None)
    continuation: ContinuationConfig | None = spec(None)
    time_response: TimeResponseConfig | None = spec(None)
    report: ReportConfig | None = spec(None)
    critical_damping: CriticalDampingConfig | None = spec(None)
    reduction_accuracy: ReductionAccuracyConfig | None = spec(None)
    nvh: NvhConfig | None = spec(None)
    map: MapConfig | None = spec(None)
    runup: RunupConfig | None = spec(None)
    nnm: NnmConfig | None = spec(None)
    optimize: OptimizeConfig | None = spec(None)
    states: StatesConfig | None = spec(None)
    findings: FindingsConfig = spec(FindingsConfig())
    figures: FiguresConfig = spec(FiguresConfig())

    @property
    def parameter(self) -> Parameter | None:
        """The continuation parameter the scene's model declares (None: no reduced model)."""
        for section in (self.impact_pair, self.gearbox):
            if section is not None:
                return section.PARAMETER
        return None

    @property
    def model_kind(self) -> str:
        present = [s for s in MODEL_SECTIONS if getattr(self, s) is not None]
        return present[0]

    def validate(self, path: str) -> None:
        present = [s for s in MODEL_SECTIONS if getattr(self, s) is not None]
        if not present:
            raise ConfigError("", f"missing section: a scene needs one of [{'], ['.join(MODEL_SECTIONS)}]")
        if len(present) > 1 and "impact_pair" in present:
            raise ConfigError("impact_pair", "an impact-pair scene cannot also have "
                              f"[{'], ['.join(p for p in present if p != 'impact_pair')}]")
        if self.gearbox is not None and self.rotor is not None:
            raise ConfigError("rotor", "a gearbox scene defines its shafts in [[gearbox.shafts]]; "
                              "[rotor] is for single-rotor scenes")
        errs = ErrorList()          # every problem found, reported together
        for i, analysis in enumerate(self.scene.analyses):
            with errs.catch():
                self._check_analysis(i, analysis)
        if self.housing_sweep is not None and self.housing is not None:
            with errs.catch():
                self.housing_sweep.housing_points(self.housing, "housing_sweep")
        if self.map is not None and self.gearbox is not None and "map" in self.scene.analyses:
            with errs.catch():
                self.map.check_couplings(self.gearbox, "map")
        # scene.analyses is the verb alone for `vibrogear runup` / `vibrogear nnm` (the CLI
        # rebuilds the scene with it), so these also run for a verb the scene does not list
        if self.runup is not None and self.gearbox is not None and "runup" in self.scene.analyses:
            with errs.catch():
                self.runup.check_gearbox(self.gearbox, "runup")
        if self.nnm is not None and "nnm" in self.scene.analyses:
            with errs.catch():
                self.nnm.check_model(self.impact_pair, self.gearbox, "nnm")
        if self.states is not None:
            with errs.catch():
                self.states.check_model(self.impact_pair, self.gearbox, "states")
        from .model.layout import check_layout        # checks across sections, in one place
        with errs.catch():
            check_layout(self)
        errs.raise_if()
        if self.optimize is not None:           # the evaluated scene at the variables' bounds
            self.optimize.check_scene(self, scene_from_dict, "optimize")

    def replace(self, changes: dict[str, Any]) -> "Scene":
        """A new scene with ``changes`` applied, checked as ``vibrogear check`` checks a scene
        file (every field's type and range, the rules across sections): ``{key: value}`` with
        the keys of ``--set`` (``"gearbox.meshes[0].backlash": 5e-5``, ``"sweep.n_points":
        6``) and plain Python values (numbers, strings, lists, tables as dicts).  A bad value
        raises :class:`ConfigError` naming the field, its expected type and range; ``self`` is
        unchanged (a scene is frozen).  The gear-mesh geometry checks of the model layer run
        when the scene is loaded and run (:func:`vibrogear.api.load`, :func:`vibrogear.api.run`)."""
        if not isinstance(changes, dict):
            raise ConfigError("replace", f"expected a dict of --set keys and values, got "
                              f"{type(changes).__name__}")
        # the scene as written (before the sizes derived from other sections were filled in,
        # so that they follow the change as they follow a --set), else as it stands
        written = getattr(self, "_written", None)
        data = copy.deepcopy(written) if written is not None else as_data(self)
        for key, value in changes.items():
            if not isinstance(key, str):
                raise ConfigError("replace", f"keys are --set paths such as "
                                  f"'sweep.n_points', got {key!r}")
            set_path(data, parse_key(key, what="replace"), _plain(value))
        return scene_from_dict(data)

    def _check_analysis(self, i: int, analysis: str) -> None:
        allowed = ANALYSIS_MODELS[analysis]
        if not any(getattr(self, s) is not None for s in allowed):
            raise ConfigError(f"scene.analyses[{i}]", f"{analysis!r} needs a model section "
                              f"[{'] or ['.join(allowed)}]")
        section = ANALYSIS_SECTION[analysis]
        if section is not None and getattr(self, section) is None:
            raise ConfigError(section, f"missing section: analysis {analysis!r} needs [{section}]")
        if analysis == "campbell" and self.rotor is not None and self.rotor.campbell is None:
            raise ConfigError("rotor.campbell", "missing section: analysis 'campbell' needs "
                              "[rotor.campbell] (rpm_max, ...)")


@dataclass(frozen=True)
class GearboxScene(Scene):
    """A gearbox scene: its parameter is the driving-shaft speed (``GearboxConfig.PARAMETER``),
    so [sweep], [continuation] and [time_response] take ``rpm_min``/``rpm_max``/``rpm``."""
    sweep: RpmSweepConfig | None = spec(None)
    continuation: RpmContinuationConfig | None = spec(None)
    time_response: RpmTimeResponseConfig | None = spec(None)
    states: RpmStatesConfig | None = spec(None)


def _plain(value: Any) -> Any:
    """A numpy scalar or array as the plain number or list a scene file holds."""
    if type(value).__module__ == "numpy" and hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def read_toml(path: str | Path) -> dict[str, Any]:
    return read_toml_file(path, Scene)


def scene_from_dict(data: dict[str, Any], overrides: tuple[str, ...] = (),
                    base_dir: str | Path | None = None) -> Scene:
    """``base_dir``: the scene file's folder; relative data-file paths (``housing.file``) are
    taken relative to it."""
    data = copy.deepcopy(data)
    for text in overrides:
        keys, value = parse_override(text)
        set_path(data, keys, value)
    if base_dir is not None:
        resolve_file(data, base_dir)
    written = copy.deepcopy(data)   # what Scene.replace changes
    fill_housing(data)              # a parametric housing's missing sizes, from the gearbox
    # the sections that take the parameter read it under the model's keys
    scene = build(GearboxScene if "gearbox" in data else Scene, data)
    object.__setattr__(scene, "_written", written)
    return scene


def load_scene(path: str | Path, overrides: tuple[str, ...] = (),
               changes: dict[str, Any] | None = None) -> Scene:
    """Read, override (``section.key=value``) and validate a scene file; a REXS model
    (``.rexs``, ``.rexsj``) is imported first (:mod:`.rexs`).  ``changes``: more overrides as
    {``--set`` key: Python value} (:meth:`Scene.replace`), applied before ``overrides``."""
    from .rexs import import_rexs, is_rexs_path
    data = import_rexs(path).data if is_rexs_path(path) else read_toml(path)
    try:
        if changes:
            if not isinstance(changes, dict):
                raise ConfigError("overrides", "expected a dict of --set keys and values, got "
                                  f"{type(changes).__name__}")
            data = copy.deepcopy(data)
            for key, value in changes.items():
                set_path(data, parse_key(str(key), what="overrides"), _plain(value))
        return scene_from_dict(data, overrides, base_dir=Path(path).parent)
    except RecursionError:
        raise ConfigError(str(path), "arrays or tables nested too deeply") from None
