"""model_arrays reuses the last parameter's packing: alternating parameters must still get
each parameter's own spin-dependent coupling (Kc0 + spin Kc1, Bc0 + spin Bc1)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from vibrogear.config import load_scene
from vibrogear.models.gearbox.model import build_gearbox
from vibrogear.solvers.integrator.kernel_pack import _model_arrays, model_arrays

GEAR_PAIR = Path(__file__).resolve().parents[2] / "configs" / "gear_pair.toml"


def test_alternating_parameters_get_their_own_packing():
    scene = load_scene(GEAR_PAIR)
    model = build_gearbox(scene).reduced
    p1, p2 = scene.sweep.param_min, scene.sweep.param_max
    cp = model.coupling
    for p in (p1, p2, p1, p1, p2):
        arrs, Om, spin = model_arrays(model, p)[:3]
        assert Om == model.omega_per_param * p and spin == model.spin_per_param * p
        np.testing.assert_array_equal(arrs.Bc, cp.Bc0 + spin * cp.Bc1)
        np.testing.assert_array_equal(arrs.Kc, cp.Kc0 + spin * cp.Kc1)
        fresh = _model_arrays(model, p)[0]
        for name in arrs._fields:
            np.testing.assert_array_equal(getattr(arrs, name), getattr(fresh, name))
    assert model_arrays(model, p2)[0] is model_arrays(model, p2)[0]    # reused, not repacked
    assert not np.array_equal(model_arrays(model, p1)[0].Bc, model_arrays(model, p2)[0].Bc)
