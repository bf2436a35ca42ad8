"""Modes of the parametric housing with an inner wall (configs/housing_small.toml, one wall at
y = 0.08 m, mid-width), against the same box without it.

The inner wall is a plate in the x-z plane spanning the cavity: a shear wall for motion along x
(in its plane), a loose plate for motion along y (normal to it), where it adds mass and next to
no stiffness.  So the first mode whose bores move mainly along x must rise, and nothing forces
the y modes up.  Measured (P2, 6 modes, under load on 2 cores):

    size 0.03         no wall: 1958.2 2529.0 3041.3 3615.4 4471.2 4583.7 Hz (16,989 DOF)
                      wall:    1913.1 2895.2 3555.3 4169.7 4212.8 5092.8 Hz (20,511 DOF)
    refine = 1        no wall: 1935.1 2492.2 2949.9 3568.0 4255.9 4376.1 Hz (112,440 DOF)
                      wall:    1885.7 2859.3 3505.8 3977.2 4040.0 4843.3 Hz (136,239 DOF)

The first x mode (bore centres 89-90 % along x) rises 14.5 % (coarse) and 14.7 % (refined);
the first mode (bores 80-85 % along y; top wall 37 % of the kinetic energy) falls 2.3 % / 2.6 %: the
lowest frequency does not rise with the wall, and the test does not claim it does.  The
pictures' regions know the inner wall: with it, modes 5 and 6 are "inner wall 1 with bores 2,
5 bending" (44 %, 47 % of the kinetic energy, coarse mesh).  Refining
the mesh (gmsh's split, so the coarse P2 space is a subspace of the fine one) lowers every
frequency (the min-max principle: exact for nested spaces), with and without the wall.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.config import load_scene
from vibrogear.config.base import as_data, build
from vibrogear.config.model.housing import HousingConfig
from vibrogear.geometry.housing import housing_volume

SMALL = Path(__file__).resolve().parents[2] / "configs" / "housing_small.toml"


def _cfg(walls, refine=0) -> HousingConfig:
    d = as_data(load_scene(SMALL).housing)
    d["inner_walls"] = list(walls)
    d["mesh"] = {**d["mesh"], "refine": refine}
    d["modes"] = {**d["modes"], "count": 6, "shapes": 0}
    return build(HousingConfig, d, "housing")


def _modes(walls, refine=0):
    from vibrogear.models.housing.run import housing_modes
    return housing_modes(_cfg(walls, refine))


def _direction_share(res) -> np.ndarray:
    """(m, 3): share of x, y, z in the bore centres' |displacement| per mode."""
    v = np.abs(res.bore_center_values).sum(axis=0).T          # (m, 3)
    return v / v.sum(axis=1, keepdims=True)


def _first_x_mode(res) -> float:
    share = _direction_share(res)
    k = int(np.flatnonzero(share[:, 0] > 0.7)[0])
    return float(res.freqs_hz[k])


def _check_pair(plain, walled, walls):
    cfg = _cfg(walls)
    assert walled.mass_kg == pytest.approx(housing_volume(cfg) * cfg.material.rho, rel=2e-3)
    assert walled.residuals.max() < 1e-6 and walled.orthogonality_error < 1e-8
    assert len(walled.bore_names) == 3 * len(cfg.bores)
    fx0, fx1 = _first_x_mode(plain), _first_x_mode(walled)
    assert fx1 > 1.10 * fx0, f"the shear wall should stiffen the x sway: {fx0:.1f} -> {fx1:.1f} Hz"
    # the inner wall is a region of its own (the kinetic energy's shares sum to 1 with it), and
    # some mode is named after it and its two bores
    assert walled.region_names[-1] == "inner wall 1" and len(walled.region_names) == 6 + 6 + 1
    np.testing.assert_allclose(walled.region_energy.sum(axis=1), 1.0, rtol=1e-9)
    assert any(lab.startswith("inner wall 1 with bores 2, 5") for lab in walled.mode_motion()[0])
    # the radiating skin (ERP) is the outside only: none of the inner wall's faces is on it
    from vibrogear.models.housing.surface_mesh import outer_skin
    v, tri = walled.shape_vertices, walled.shape_triangles
    c, t = v[tri].mean(axis=1), cfg.wall_thickness
    on_wall = np.all((c > t + 1e-6) & (c < np.array([cfg.length, cfg.width, cfg.height]) - t - 1e-6),
                     axis=1) & (np.abs(c[:, 1] - walls[0]) <= t / 2 + 1e-6)
    assert on_wall.sum() > 100 and not np.any(outer_skin(v, tri, walled.shape_facet_tag)[on_wall])
    # the first mode moves the bores along y (normal to the walls) in both
    assert _direction_share(plain)[0, 1] > 0.7 and _direction_share(walled)[0, 1] > 0.7


def test_inner_wall_stiffens_the_in_plane_sway(empty_vibrogear_cache):
    _check_pair(_modes(()), _modes((0.08,)), (0.08,))


@pytest.mark.slow
def test_nested_refinement_lowers_every_frequency_with_and_without_the_wall(empty_vibrogear_cache):
    for walls in ((), (0.08,)):
        coarse, fine = _modes(walls), _modes(walls, refine=1)
        assert fine.n_dofs > 5 * coarse.n_dofs
        assert np.all(fine.freqs_hz <= coarse.freqs_hz * (1 + 1e-9)), (walls, coarse.freqs_hz, fine.freqs_hz)
        assert np.all(fine.freqs_hz >= 0.9 * coarse.freqs_hz)     # converging, not collapsing
    _check_pair(_modes((), refine=1), _modes((0.08,), refine=1), (0.08,))
