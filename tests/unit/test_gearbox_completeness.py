"""Small gearbox-model completeness against closed forms: anisotropic linear bearings (the
rigid rotor's bounce eigenvalues are those of 2 K / m, also for kxy != kyx and with
damping), gears and discs given by mass and inertias (the same model as the geometric disc
with the same values), gravity as a static load (simply supported Timoshenko shaft under its
own weight; bearing reactions equal the weight), and the keys' errors."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from vibrogear.config import ConfigError
from vibrogear.config.scene import read_toml, scene_from_dict
from vibrogear.models.gearbox.model import build_gearbox
from vibrogear.solvers.linear import linear_modes, tangent_matrices
from vibrogear.solvers.static import static_equilibrium

ROOT = Path(__file__).resolve().parents[2]
GEAR_PAIR = ROOT / "configs" / "gear_pair.toml"
RHO, E, NU = 7850.0, 2.1e11, 0.3


def _one_shaft(bearing: dict, *, length=0.4, d=0.04, elements=4, discs=(), master_count=6,
               gravity=None, couplings=()):
    """One steel shaft on two spring bearings at its ends (no meshes, no housing)."""
    gb = {"name": "rotor", "shafts": [{
        "name": "s", "x": 0.1, "z": 0.2, "master_count": master_count,
        "material": {"E": E, "nu": NU, "rho": RHO},
        "sections": [{"length": length, "outer_diameter": d, "elements": elements}],
        "discs": list(discs)}],
        "bearings": [dict(bearing, name="A", shaft="s", position=0.0, type="spring"),
                     dict(bearing, name="B", shaft="s", position=length, type="spring")],
        "couplings": list(couplings)}
    if gravity is not None:
        gb["gravity"] = gravity
    return scene_from_dict({"scene": {"name": "t", "analyses": ["modes"]}, "gearbox": gb})


def _state_eigenvalues(K, D):
    m = K.shape[0]
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-K, -D]])
    return np.linalg.eigvals(A)


DISC = {"position": 0.2, "mass": 12.0, "Id": 0.05, "Ip": 0.09}


@pytest.mark.parametrize("K, C", [
    (((1.0e6, 0.0), (0.0, 2.5e6)), ((0.0, 0.0), (0.0, 0.0))),
    (((1.0e6, 4.0e5), (4.0e5, 2.0e6)), ((50.0, 0.0), (0.0, 80.0))),
    (((1.0e6, 3.0e5), (1.0e5, 2.0e6)), ((60.0, 20.0), (-10.0, 90.0))),
])
def test_anisotropic_bearing_rigid_rotor_bounce(K, C):
    """Master modes = the 6 rigid-body modes of the free shaft: the reduced model is the
    rigid rotor.  Bearings symmetric about the centre of mass (disc in the middle): the
    lateral translation decouples from the rocking, its eigenvalues are those of
    m q'' + 2 C q' + 2 K q = 0 with m = shaft + disc mass (closed form).  Undamped and
    symmetric: bounce frequencies sqrt(eig(2 K / m)), for diagonal K sqrt(2 kxx / m),
    sqrt(2 kyy / m)."""
    (kxx, kxy), (kyx, kyy) = K
    (cxx, cxy), (cyx, cyy) = C
    sc = _one_shaft({"kxx": kxx, "kyy": kyy, "kxy": kxy, "kyx": kyx, "cxx": cxx, "cyy": cyy,
                     "cxy": cxy, "cyx": cyx}, discs=[DISC])
    gm = build_gearbox(sc)
    assert gm.reduced.n_modes == 6
    m = RHO * math.pi * 0.04**2 / 4 * 0.4 + DISC["mass"]
    Kt, Dt = tangent_matrices(gm.reduced, np.zeros(6), 0.0)
    w_ref = gm.omega_ref
    lam = _state_eigenvalues(Kt, Dt) * w_ref                   # [1/s]
    Kp, Cp = 2 * np.array(K) / m, 2 * np.array(C) / m
    ref = np.linalg.eigvals(np.block([[np.zeros((2, 2)), np.eye(2)], [-Kp, -Cp]]))
    for r in ref:
        assert np.min(np.abs(lam - r)) <= 1e-9 * abs(r), (r, lam)
    if not any(np.ravel(C)) and kxy == kyx:
        f = np.sort(np.sqrt(np.linalg.eigvalsh(Kp))) / (2 * np.pi)
        lm = linear_modes(gm.reduced, np.zeros(6), 0.0)
        got = lm.undamped[lm.undamped > 0] * w_ref
        for fr in f:
            assert np.min(np.abs(got - fr)) <= 1e-9 * fr
        if kxy == 0.0:
            assert f == pytest.approx(np.sqrt([2 * kxx / m, 2 * kyy / m]) / (2 * np.pi),
                                      rel=1e-12)


def test_isotropic_keys_give_the_isotropic_bearing():
    """stiffness = k and kxx = kyy = k (damping = c and cxx = cyy = c) build the same links."""
    a = build_gearbox(_one_shaft({"stiffness": 3e6, "damping": 40.0}, discs=[DISC]))
    b = build_gearbox(_one_shaft({"kxx": 3e6, "kyy": 3e6, "cxx": 40.0, "cyy": 40.0},
                                 discs=[DISC]))
    for name in ("P", "Kc0", "Bc0"):
        np.testing.assert_array_equal(getattr(a.reduced.coupling, name),
                                      getattr(b.reduced.coupling, name))


def _hollow_disc(D, d, w, rho):
    """Closed-form mass, diametral and polar inertia of a hollow cylinder (disc)."""
    m = rho * math.pi * (D**2 - d**2) / 4 * w
    return m, m * ((D**2 + d**2) / 16 + w**2 / 12), m * (D**2 + d**2) / 8


def test_gears_and_discs_by_mass_and_inertia_equal_the_geometric_ones():
    geo = read_toml(GEAR_PAIR)
    geo["scene"]["analyses"] = ["modes"]
    geo["gearbox"]["shafts"][0]["discs"] = [{"position": 0.28, "outer_diameter": 0.12,
                                             "inner_diameter": 0.035, "width": 0.03}]
    given = read_toml(GEAR_PAIR)
    given["scene"]["analyses"] = ["modes"]
    m, i_d, i_p = _hollow_disc(0.12, 0.035, 0.03, RHO)
    given["gearbox"]["shafts"][0]["discs"] = [{"position": 0.28, "mass": m, "Id": i_d,
                                               "Ip": i_p}]
    for g in given["gearbox"]["gears"]:
        D = g["module"] * g["teeth"]                        # spur: pitch diameter
        g["mass"], g["Id"], g["Ip"] = _hollow_disc(D, g.pop("inner_diameter"), g["width"], RHO)
    a, b = build_gearbox(scene_from_dict(geo)), build_gearbox(scene_from_dict(given))
    for ra, rb in zip(a.rotors, b.rotors):
        for name in ("M", "G", "K"):
            A, B = getattr(ra, name).toarray(), getattr(rb, name).toarray()
            assert np.max(np.abs(A - B)) <= 1e-12 * np.max(np.abs(A))
    np.testing.assert_allclose(b.reduced.omega2, a.reduced.omega2, rtol=1e-10, atol=1e-12)
    fa = linear_modes(a.reduced, static_equilibrium(a.reduced, 5800.0).x, 5800.0).frequency
    fb = linear_modes(b.reduced, static_equilibrium(b.reduced, 5800.0).x, 5800.0).frequency
    np.testing.assert_allclose(fb, fa, rtol=1e-9)


def test_gravity_simply_supported_shaft_deflection_and_reactions():
    """Steel shaft L = 0.6 m, d = 30 mm, 12 Timoshenko elements, all its modes kept, on
    spring bearings k at its ends (simply supported), own weight w = rho A g downwards
    (housing z up = rotor Y).  Midspan deflection (exact at the nodes for this element):
    5 w L^4 / (384 E I) + w L^2 / (8 kappa G A) + w L / (2 k), kappa = 6 (1 + nu) / (7 + 6 nu)
    (Cowper, solid circle); the bearing reactions add up to the weight."""
    L, d, n, k, g = 0.6, 0.03, 12, 5e7, 9.81
    sc = _one_shaft({"stiffness": k, "axial_stiffness": 1e7}, length=L, d=d, elements=n,
                    master_count=6 * (n + 1), gravity=[0.0, 0.0, -g],
                    couplings=[{"name": "hold", "shaft": "s", "position": 0.0, "role": "motor",
                                "stiffness": 1e3, "twist": 0.0}])
    gm = build_gearbox(sc)
    st = static_equilibrium(gm.reduced, 0.0)
    assert st.converged
    q = gm.subsystems[0].vectors @ st.x
    A, I = math.pi * d**2 / 4, math.pi * d**4 / 64
    w = RHO * A * g
    kappa = 6 * (1 + NU) / (7 + 6 * NU)
    G = E / (2 * (1 + NU))
    ref = 5 * w * L**4 / (384 * E * I) + w * L**2 / (8 * kappa * G * A) + w * L / (2 * k)
    mid = n // 2
    assert q[6 * mid + 1] == pytest.approx(-ref, rel=1e-9)
    assert np.max(np.abs(q[0::6])) <= 1e-10 * ref          # nothing horizontal
    assert q[0 * 6 + 1] == pytest.approx(-w * L / (2 * k), rel=1e-9)
    # reactions: sum over the vertical spring links of k (v . q) = -weight
    reaction = sum(l.stiffness * (l.vector.parts[0][2] @ q[l.vector.parts[0][1]])
                   for l in gm.links if l.name.endswith(":y"))
    assert reaction == pytest.approx(-w * L, rel=1e-9)


def test_gravity_reactions_with_disc_and_gears():
    """gear_pair on its spring bearings with gravity (no twist load): the vertical bearing
    forces add up to the total weight of shafts and gears from their geometry (the mesh
    force is internal)."""
    data = read_toml(GEAR_PAIR)
    data["scene"]["analyses"] = ["modes"]
    data["gearbox"]["gravity"] = [0.0, 0.0, -9.81]
    for c in data["gearbox"]["couplings"]:
        c["twist"] = 0.0
    gm = build_gearbox(scene_from_dict(data))
    st = static_equilibrium(gm.reduced, 0.0)
    assert st.converged
    q = [s.vectors @ st.x[o:o + s.n_modes]
         for s, o in zip(gm.subsystems, np.cumsum([0] + [s.n_modes for s in gm.subsystems]))]
    gb = data["gearbox"]
    mass = sum(RHO * math.pi / 4 * (s["outer_diameter"]**2 - s.get("inner_diameter", 0.0)**2)
               * s["length"] for sh in gb["shafts"] for s in sh["sections"])
    mass += sum(_hollow_disc(g["module"] * g["teeth"], g["inner_diameter"], g["width"], RHO)[0]
                for g in gb["gears"])
    weight = 9.81 * mass
    assert sum(_lateral_mass(r) for r in gm.rotors) == pytest.approx(mass, rel=1e-12)
    reaction = 0.0
    for l in gm.links:
        if l.name.endswith(":y"):
            s, idx, val = l.vector.parts[0]
            reaction += l.stiffness * (val @ q[s][idx])
    assert reaction == pytest.approx(-weight, rel=1e-8)


def _lateral_mass(rotor):
    """Total translational mass of a rotor: 1^T M 1 over its Y DOF (rigid translation)."""
    e = np.zeros(rotor.n_dofs)
    e[1:6 * rotor.n_nodes:6] = 1.0
    return float(e @ (rotor.M @ e))


@pytest.mark.parametrize("bearing, field, words", [
    ({"type": "ball", "stiffness": 1e9, "kxx": 1e8, "elements": 8}, "kxx", "spring"),
    ({"type": "spring", "kxx": 1e8}, "kyy", "missing"),
    ({"type": "spring"}, "kxx", "missing"),
    ({"type": "spring", "stiffness": 1e8, "kxx": -1.0}, "kxx", ">= 0"),
])
def test_bad_bearing_keys_name_the_field(bearing, field, words):
    data = read_toml(GEAR_PAIR)
    b = data["gearbox"]["bearings"][1]
    for key in ("stiffness", "type", "damping"):
        b.pop(key, None)
    b.update(bearing)
    with pytest.raises(ConfigError) as exc:
        scene_from_dict(data)
    assert exc.value.path == f"gearbox.bearings[1].{field}" and words in str(exc.value)


@pytest.mark.parametrize("gear, field", [({"mass": 1.0, "Ip": 0.01}, "Id"),
                                         ({"mass": 1.0, "Id": 0.01, "Ip": 0.02,
                                           "density": 7000.0}, "density")])
def test_bad_gear_inertia_keys_name_the_field(gear, field):
    data = read_toml(GEAR_PAIR)
    data["gearbox"]["gears"][0].update(gear)
    with pytest.raises(ConfigError) as exc:
        scene_from_dict(data)
    assert exc.value.path == f"gearbox.gears[0].{field}"


def test_gravity_out_of_range():
    data = read_toml(GEAR_PAIR)
    data["gearbox"]["gravity"] = [0.0, 0.0, -2000.0]
    with pytest.raises(ConfigError) as exc:
        scene_from_dict(data)
    assert exc.value.path == "gearbox.gravity"
    data["gearbox"]["gravity"] = [0.0, 9.81]
    with pytest.raises(ConfigError) as exc:
        scene_from_dict(data)
    assert exc.value.path == "gearbox.gravity"
