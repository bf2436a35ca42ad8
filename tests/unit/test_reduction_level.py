"""The reduction level by the frequency criterion (vibrogear.models.gearbox.master_level) in the
reduction study, and the study's cached full reference model."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from vibrogear.analyses.reduction_accuracy import (_compare, _full_reference,
                                                   reduced_linear_modes)
from vibrogear.analyses.study import start_state
from vibrogear.config import load_scene
from vibrogear.config.base import ConfigError
from vibrogear.models.gearbox.model import build_gearbox
from vibrogear.models.gearbox.master_level import excitation_frequencies_hz, highest_speed
from vibrogear.models.validate import validate_scene

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def scene():
    return load_scene(ROOT / "configs" / "gear_pair.toml")


def test_excitation_frequency_by_hand(scene):
    """gear_pair: z1 = 40 teeth on the driving shaft, top speed 7000 rpm ([sweep] and
    [continuation] rpm_max); both shafts carry meshes[0] with its harmonics."""
    m0 = scene.gearbox.meshes[0]
    n = max(len(m0.stiffness_cos), len(m0.stiffness_sin), len(m0.te_cos), len(m0.te_sin), 1)
    assert highest_speed(scene) == 7000.0
    assert np.allclose(excitation_frequencies_hz(scene.gearbox, 7000.0), 40 * 7000 / 60 * n)
    bare = dataclasses.replace(scene, sweep=None, continuation=None, time_response=None,
                               reduction_accuracy=None)
    with pytest.raises(ConfigError, match="gearbox.master_modes"):
        highest_speed(bare)
    # and `vibrogear check` says so before anything runs (frequency level, no speed range)
    bare = dataclasses.replace(bare, gearbox=dataclasses.replace(scene.gearbox,
                                                                 master_modes="frequency"))
    with pytest.raises(ConfigError, match="gearbox.master_modes.*speed range"):
        validate_scene(bare)
    validate_scene(dataclasses.replace(bare, gearbox=scene.gearbox))     # count: no need


def test_frequency_level_is_closer_to_the_full_model_than_the_default_count(scene,
                                                                           tmp_path,
                                                                           monkeypatch):
    """Against the full linearised model (all 180 shaft DOF) below 5 kHz: the frequency
    level with the static correction has a smaller worst frequency error than today's
    16 modes per shaft and than the same level without the correction; the reference comes
    from the cache on the second call, identical."""
    monkeypatch.setenv("VIBROGEAR_CACHE_DIR", str(tmp_path / "cache"))
    ref = build_gearbox(scene)
    x0 = start_state(ref.reduced, 5800.0)[:ref.reduced.n_modes]
    f1, v1, dofs, _, cached1 = _full_reference(ref, scene, x0, 5000.0)
    f2, v2, _, _, cached2 = _full_reference(ref, scene, x0, 5000.0)
    assert (cached1, cached2) == (False, True) and dofs == 180
    assert np.array_equal(f1, f2) and np.array_equal(v1, v2)
    assert not _full_reference(ref, scene, x0, 4000.0)[4]        # another key
    errs = {}
    for name, kw in (("count", {}), ("frequency", {"master_level": "frequency"}),
                     ("no_static", {"master_level": "frequency", "static_correction": False})):
        gm = build_gearbox(scene, **kw)
        x = start_state(gm.reduced, 5800.0)[:gm.reduced.n_modes]
        f_red, v_red = reduced_linear_modes(gm, x)
        cmp = _compare(f1, v1, f_red, v_red, 5000.0)
        errs[name] = max(abs(c["rel_error"]) for c in cmp)
    assert errs["frequency"] < errs["count"]
    assert errs["frequency"] < 0.1 * errs["no_static"]
