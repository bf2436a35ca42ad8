"""The rattle threshold ratio (vibrogear.analyses.mesh_loads.rattle_threshold) against closed
forms of a free gear held on its drive flank by a drag force F0 on a stiff mesh k, driven
through the mesh by a transmission error or a stiffness variation (one coordinate, the free
gear's displacement along the line of action, unit mass):

    x'' + k (1 + a cos W t) (x - e cos W t) = F0.

Linearised about x0 = F0 / k (contact held): a transmission error alone gives the mesh force
dF = k e W^2 / (k - W^2) cos W t, so the ratio is k e W^2 / (|k - W^2| F0): below the
mesh resonance the inertia force of the gear following the driver (e W^2, times its mass)
over the drag force, the classic rattle threshold; a stiffness variation alone gives
dF = -F0 a W^2 / (k - W^2) cos W t, the ratio a W^2 / |k - W^2|.  A gearbox: the shipped
two-stage gearbox's idle mesh G2 (a free gear held by 1 N m of drag) far above 1 at every
speed, as its sweep's rattle says; the FVA gearbox's loaded meshes below 1."""
from __future__ import annotations

import numpy as np
import pytest

from vibrogear.analyses.mesh_loads import rattle_threshold
from vibrogear.models.reduced import ContactSet, Forcing, LinearCoupling, ReducedModel

K, F0, B = 4.0e4, 2.0, 1e-3          # mesh stiffness, drag force, backlash (model units)
GROUPS = {"G": ("mesh", (0,))}


def _free_gear(a=0.0, e=0.0, b_sin=0.0) -> ReducedModel:
    one = np.ones(1)
    contacts = ContactSet(directions=np.ones((1, 1)), k_hi=K * one, k_lo=K * one,
                          gap_hi=np.zeros(1), gap_lo=-B * one, exponent=one,
                          damping=np.zeros(1), stiffness_cos=np.array([[a]]),
                          stiffness_sin=np.array([[b_sin]]), error_cos=np.array([[e]]),
                          error_sin=np.zeros((1, 1)))
    forcing = Forcing(F0=np.array([F0]), Fc=np.zeros((1, 1)), Fs=np.zeros((1, 1)))
    return ReducedModel(omega2=np.zeros(1), damping=np.zeros(1),
                        coupling=LinearCoupling.none(1), forcing=forcing, contacts=contacts)


def _start():
    return np.array([F0 / K, 0.0])


@pytest.mark.parametrize("W", [5.0, 50.0, 150.0, 400.0])
def test_a_transmission_error_gives_the_inertia_force_over_the_drag(W):
    e = 1e-5
    got = rattle_threshold(_free_gear(e=e), _start(), GROUPS, [W])["rattle_threshold_G"]
    assert got[0] == pytest.approx(K * e * W ** 2 / (abs(K - W ** 2) * F0), rel=1e-9)
    if W <= 5.0:                                   # far below the mesh resonance (200)
        assert got[0] == pytest.approx(e * W ** 2 / F0, rel=1e-3)


@pytest.mark.parametrize("W", [20.0, 150.0, 300.0])
def test_a_stiffness_variation_gives_its_closed_form(W):
    a = 0.2
    got = rattle_threshold(_free_gear(a=a), _start(), GROUPS, [W])["rattle_threshold_G"]
    assert got[0] == pytest.approx(a * W ** 2 / abs(K - W ** 2), rel=1e-9)
    # the same amplitude as a sine: the same ratio (only the phase differs)
    sin = rattle_threshold(_free_gear(b_sin=a), _start(), GROUPS, [W])["rattle_threshold_G"]
    assert sin[0] == pytest.approx(got[0], rel=1e-9)


def test_no_drag_nothing_holds_the_teeth():
    """A free gear without drag sits in its backlash at the static state: infinite ratio."""
    model = _free_gear(e=1e-5)
    got = rattle_threshold(model, np.array([-B / 2, 0.0]), GROUPS, [50.0])
    assert got["rattle_threshold_G"][0] == np.inf


@pytest.mark.slow
def test_shipped_gearboxes_idle_mesh_above_one_loaded_meshes_below():
    from vibrogear.analyses.study import build_study
    from vibrogear.config import load_scene
    from vibrogear.solvers.sequential.record_metrics import contact_groups

    sc = load_scene("configs/two_stage.toml")
    st = build_study(sc)
    rpm = np.linspace(1500.0, 3000.0, 7)
    r = rattle_threshold(st.model, st.start(rpm[0]), contact_groups(st.model), rpm)
    assert np.all(r["rattle_threshold_G2"] > 10.0)
    sc = load_scene("configs/fva_two_stage.toml")
    st = build_study(sc)
    rpm = np.linspace(600.0, 3000.0, 7)
    r = rattle_threshold(st.model, st.start(rpm[0]), contact_groups(st.model), rpm)
    assert np.all(r["rattle_threshold_stage19"] < 0.2)
    assert np.all(r["rattle_threshold_stage20"] < 1.0)
