"""The gearbox model against its physics: modal synthesis with every shaft mode kept is the
full FE model, fewer modes approximate it from above (Rayleigh-Ritz); the reduced contact
forces (numpy post-processing and compiled kernel) are the physical gear-mesh forces (the
contact law on ``couplings.mesh_contact_parameters`` in SI units) projected on the modes
(free-gear DOF, omega_ref scaling); speed ratios, mesh sign, static equilibrium and torque
balance; layout errors name the field (``vibrogear check`` exits 2)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from vibrogear.cli import main
from vibrogear.config import ConfigError, load_scene
from vibrogear.config.scene import read_toml, scene_from_dict
from vibrogear.models.validate import validate_scene
from vibrogear.models.contact_law import evaluate, harmonic_series
from vibrogear.models.gearbox.couplings import gear_mesh_geometry, mesh_contact_parameters
from vibrogear.models.gearbox.model import RPM, build_gearbox, housing_to_rotor
from vibrogear.models.gearbox.synthesis import subsystem_offsets
from vibrogear.solvers.integrator.contact_eval import contact_history
from vibrogear.solvers.static import static_equilibrium

ROOT = Path(__file__).resolve().parents[2]
GEAR_PAIR = ROOT / "configs" / "gear_pair.toml"
RPM0 = 5800.0
F_MAX = 5000.0

#: a second, unloaded mesh on the gear_pair shafts: z3 (50 teeth) turns freely on the
#: driving shaft, meshes with z4 (70 teeth) fixed on the driven shaft; same centre distance
#: (0.05 + 0.07 = 0.12 m), gear_a = z4 on the driven shaft (negative drive sense)
FREE_GEAR_MESH = """
[[gearbox.gears]]
name = "z3"
shaft = "driving"
position = 0.16
teeth = 50
module = 0.002
width = 0.02
inner_diameter = 0.045
free = true

[[gearbox.gears]]
name = "z4"
shaft = "driven"
position = 0.16
teeth = 70
module = 0.002
width = 0.02
inner_diameter = 0.05

[[gearbox.meshes]]
name = "G2"
gear_a = "z4"
gear_b = "z3"
stiffness = 2.0e8
damping = 300.0
backlash = 5.0e-5
"""


@pytest.fixture(scope="module")
def scene():
    return load_scene(GEAR_PAIR)


@pytest.fixture(scope="module")
def free_gear_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("scene") / "gear_pair_free_gear.toml"
    path.write_text(GEAR_PAIR.read_text() + FREE_GEAR_MESH)
    return path


def _full_dof_vector(vec, offsets):
    """A PhysicalVector of a rotor-only scene as a dense vector over all shaft DOF."""
    c = np.zeros(offsets[-1])
    for s, idx, val in vec.parts:
        np.add.at(c, offsets[s] + idx, val)
    return c


def _physical_reference(gm, x0):
    """Own dense assembly of the full linearised model: blockdiag(K_s) + sum k c c^T over
    the linear links and the meshes in contact at the physical static deformation; its
    undamped frequencies [Hz] (all, ascending)."""
    sizes = [r.n_dofs for r in gm.rotors]
    off = np.concatenate([[0], np.cumsum(sizes)])
    K = sla.block_diag(*[r.K.toarray() for r in gm.rotors])
    M = sla.block_diag(*[r.M.toarray() for r in gm.rotors])
    for link in gm.links:
        c = _full_dof_vector(link.vector, off)
        K += link.stiffness * np.outer(c, c)
    q = np.concatenate([s.vectors @ x0[a:b] for s, a, b in
                        zip(gm.subsystems, subsystem_offsets(gm.subsystems)[:-1],
                            subsystem_offsets(gm.subsystems)[1:])])
    for law in gm.contacts:
        assert law.kind == "mesh" and law.exponent == 1.0
        c = _full_dof_vector(law.vector, off)
        delta = c @ q
        if delta > law.gap_hi:
            K += law.k_hi * np.outer(c, c)
        elif delta < law.gap_lo:
            K += law.k_lo * np.outer(c, c)
    lam = sla.eigh(K, M, eigvals_only=True)
    return np.sqrt(np.clip(lam, 0.0, None)) / (2 * np.pi)


def _reduced_undamped_hz(gm, x0):
    from vibrogear.solvers.linear import tangent_matrices

    K, _ = tangent_matrices(gm.reduced, x0, 0.0)
    lam = np.linalg.eigvalsh(0.5 * (K + K.T))
    return np.sqrt(np.clip(lam, 0.0, None)) * gm.omega_ref / (2 * np.pi)


# ------------------------------------------------------------------ synthesis vs full model

def test_all_shaft_modes_kept_is_the_full_model(scene):
    from vibrogear.analyses.reduction_accuracy import full_linear_model, reduced_linear_modes
    from vibrogear.models.gearbox.full_linear import lowest_modes_full

    n = tuple(r.n_dofs for r in build_gearbox(scene).rotors)
    gm = build_gearbox(scene, master_counts=n)
    assert [s.n_modes for s in gm.subsystems] == list(n) == [90, 90]
    st = static_equilibrium(gm.reduced, RPM0)
    assert st.converged
    f_own = _physical_reference(gm, st.x)
    f_red = _reduced_undamped_hz(gm, st.x)
    f_full, _ = lowest_modes_full(full_linear_model(gm, scene, st.x)[0], F_MAX)
    f_red2, _ = reduced_linear_modes(gm, st.x)
    k = f_full.size
    assert 10 <= k == int(np.sum(f_own <= F_MAX))            # the scene has ~16 modes < 5 kHz
    for ref in (f_own[:k], f_full):
        np.testing.assert_allclose(f_red[:k], ref, rtol=1e-8)
        np.testing.assert_allclose(f_red2[:k], ref, rtol=1e-8)
    # and the whole spectrum (up to the MHz axial modes) of the 180 x 180 system
    np.testing.assert_allclose(f_red, f_own, rtol=1e-7)


def test_fewer_modes_approximate_from_above(scene):
    """Rayleigh-Ritz: nested mode sets give frequencies >= the full model's, decreasing with
    the number of modes (the mesh stays in contact, so the tangent is the same linear one)."""
    full = build_gearbox(scene, master_counts=(90, 90))
    f_ref = _physical_reference(full, static_equilibrium(full.reduced, RPM0).x)
    k = int(np.sum(f_ref <= F_MAX))
    errors = []
    for count in (10, 16, 30):
        gm = build_gearbox(scene, master_counts=(count, count))
        st = static_equilibrium(gm.reduced, RPM0)
        assert st.converged and gm.reduced.contacts.directions[0] @ st.x > 0
        f = _reduced_undamped_hz(gm, st.x)[:k]
        errors.append((f - f_ref[:k]) / f_ref[:k])
    errors = np.array(errors)
    assert np.all(errors > -1e-9)                            # never below the full model
    assert np.all(np.diff(errors, axis=0) < 1e-9)            # more modes: never worse
    assert np.all(errors[:, :4] > 1e-5)                      # and really an approximation
    assert errors[0, :4].max() > 3 * errors[-1, :4].max()
    assert errors[-1].max() < 5e-3                           # 30 modes per shaft: < 0.5 %


# ------------------------------------------------------------------ contact forces

def _mesh_geometry_from_config(cfg, i):
    """Independent geometry of meshes[i] from the config (axes x, z; pitch radii)."""
    _, gear_p = cfg.speed_ratios()
    m = cfg.meshes[i]
    ka, kb = cfg.gear_index(m.gear_a, ""), cfg.gear_index(m.gear_b, "")
    ga, gb = cfg.gears[ka], cfg.gears[kb]
    sa, sb = cfg.shaft_index(ga.shaft, ""), cfg.shaft_index(gb.shaft, "")
    centre = lambda s: housing_to_rotor([cfg.shafts[s].x, 0.0, cfg.shafts[s].z])[:2]  # noqa
    geom = gear_mesh_geometry(centre(sa), centre(sb), ga.pitch_diameter / 2,
                              gb.pitch_diameter / 2, math.radians(m.pressure_angle),
                              drive_sense=1 if gear_p[ka] > 0 else -1)
    return geom, (sa, ga), (sb, gb)


def _gear_dofs(gm, s, gear):
    """u, v, w, phi, theta of the gear's node and the gear body's rotation: the node's psi
    for a fixed gear, the extra torsional DOF (after all node DOF) for a free one."""
    rotor = gm.rotors[s]
    node = int(np.argmin(np.abs(rotor.node_z - gear.position)))
    assert abs(rotor.node_z[node] - gear.position) < 1e-12
    if gear.free:
        psi = 6 * rotor.n_nodes
        assert rotor.free_gear_dofs == (psi,) and rotor.n_dofs == psi + 1
    else:
        psi = 6 * node + 5
    return [6 * node + k for k in range(5)] + [psi]


def _physical_mesh_forces(gm, cfg, x, v, tau, rpm):
    """Sum over the meshes of V^T F_phys (in model units, / omega_ref^2) with F_phys = -c f,
    f the contact law on the mesh's parameters in SI units at q = V x, q' = omega_ref V x',
    t = tau / omega_ref; and the physical deformations delta = c . q - e(t)."""
    om = gm.omega_ref
    off = subsystem_offsets(gm.subsystems)
    q = [s.vectors @ x[off[k]:off[k + 1]] for k, s in enumerate(gm.subsystems)]
    qd = [om * (s.vectors @ v[off[k]:off[k + 1]]) for k, s in enumerate(gm.subsystems)]
    w_mesh = 2 * np.pi * gm.mesh_teeth * rpm / 60.0                # rad/s
    gen = np.zeros(x.size)
    deltas = []
    for i, m in enumerate(cfg.meshes):
        geom, (sa, ga), (sb, gb) = _mesh_geometry_from_config(cfg, i)
        ia, ib = _gear_dofs(gm, sa, ga), _gear_dofs(gm, sb, gb)
        law = mesh_contact_parameters(m.stiffness, m.backlash, m.damping, m.stiffness_cos,
                                      m.stiffness_sin, m.te_cos, m.te_sin)
        e, e_dot = harmonic_series(m.te_cos, m.te_sin, w_mesh, tau / om)
        mu = 1.0 + harmonic_series(m.stiffness_cos, m.stiffness_sin, w_mesh, tau / om)[0]
        delta = geom.c @ np.concatenate([q[sa][ia], q[sb][ib]]) - e[0]
        delta_dot = geom.c @ np.concatenate([qd[sa][ia], qd[sb][ib]]) - e_dot[0]
        f = evaluate(delta, delta_dot, modulation=mu[0], **{k: law[k] for k in (
            "k_hi", "k_lo", "gap_hi", "gap_lo", "exponent", "damping")}).force
        F = -geom.c * float(f)
        gen[off[sa]:off[sa + 1]] += gm.subsystems[sa].vectors[ia].T @ F[:6]
        gen[off[sb]:off[sb + 1]] += gm.subsystems[sb].vectors[ib].T @ F[6:]
        deltas.append(delta)
    return gen / om ** 2, np.array(deltas)


def _kernel_contact_accel(model, rpm, tau, x, v):
    """Contact part of the compiled right-hand side: accel(contact modes from the sign of
    the deformations) - accel(every contact in its dead zone)."""
    from vibrogear.solvers.integrator.kernels import accel, contact_modes, model_arrays

    A, Om = model_arrays(model, rpm)[:2]
    m, nc, H = model.n_modes, model.contacts.count, model.n_harmonics
    y = np.concatenate([x, v])
    mode = np.zeros(nc, dtype=np.int64)
    contact_modes(A, tau, Om, x, mode)

    def run(md):
        out = np.zeros(2 * m)
        accel(tau, y, md, A, Om, np.empty(H), np.empty(H), out, np.zeros(nc), np.zeros(nc),
              np.zeros(nc), np.zeros(nc), np.zeros(2 * (A.P.shape[0] + m + nc)))
        return out[m:]

    return run(mode) - run(np.zeros(nc, dtype=np.int64)), mode


def test_reduced_contact_forces_are_projected_physical_mesh_forces(free_gear_file):
    """Two meshes (G1 with stiffness and TE harmonics; G2 with a free gear, negative drive
    sense), states placed on every branch of the dead-zone law, random velocities and
    times: the reduced forces equal V^T F_phys / omega_ref^2 to round-off."""
    sc = load_scene(free_gear_file)
    gm = build_gearbox(sc)
    r = gm.reduced
    assert [c.name for c in gm.contacts] == ["G1", "G2"] and r.contacts.count == 2
    rng = np.random.default_rng(7)
    x_static = static_equilibrium(r, RPM0).x
    Dm = r.contacts.directions
    b = np.array([m.backlash for m in sc.gearbox.meshes])
    seen = set()
    for target in ([3e-6, 2e-5], [-5e-5, -1e-5], [-1.5e-4, -8e-5], [1e-5, -9e-5]):
        tau = rng.uniform(0.0, 20.0)
        x = x_static + 1e-6 * rng.standard_normal(r.n_modes) / np.sqrt(1.0 + r.omega2)
        v = 1e-5 * rng.standard_normal(r.n_modes)
        # move x along the contact directions so that delta = c . x - e(tau) = target
        d_now = contact_history(r, RPM0, [tau], np.concatenate([x, v])[None])[0][:, 0]
        x = x + Dm.T @ np.linalg.solve(Dm @ Dm.T, np.asarray(target) - d_now)
        delta, _, force = contact_history(r, RPM0, [tau], np.concatenate([x, v])[None])
        np.testing.assert_allclose(delta[:, 0], target, rtol=1e-9)
        phys, delta_phys = _physical_mesh_forces(gm, sc.gearbox, x, v, tau, RPM0)
        np.testing.assert_allclose(delta_phys, target, rtol=1e-9)
        red = -(Dm.T @ force[:, 0])
        scale = np.max(np.abs(phys)) if np.any(phys) else 1.0
        assert np.max(np.abs(red - phys)) <= 1e-9 * scale
        kern, mode = _kernel_contact_accel(r, RPM0, tau, x, v)
        assert np.max(np.abs(kern - phys)) <= 1e-9 * scale
        expected = np.where(np.asarray(target) > 0, 1, np.where(np.asarray(target) < -b, -1, 0))
        np.testing.assert_array_equal(mode, expected)
        seen.update((j, int(md)) for j, md in enumerate(mode))
    assert seen == {(j, md) for j in (0, 1) for md in (-1, 0, 1)}  # every branch of both laws


# ------------------------------------------------------------------ kinematics and statics

def test_speed_ratios_and_mesh_frequency(scene, free_gear_file):
    gm = build_gearbox(scene)
    assert gm.shaft_ratios == (1.0, -0.5)                    # external pair 40 -> 80 teeth
    assert [s.spin_ratio for s in gm.subsystems] == [1.0, -0.5]
    assert gm.mesh_teeth == 40 and gm.mesh_frequency_hz(6000.0) == pytest.approx(4000.0)
    r = gm.reduced
    assert r.excitation_frequency(6000.0) * gm.omega_ref == pytest.approx(2 * np.pi * 4000.0)
    assert r.spin_per_param == pytest.approx(RPM)
    shafts, gears = load_scene(free_gear_file).gearbox.speed_ratios()
    assert shafts == [1.0, -0.5]
    # z1, z2 with their shafts; free z3 driven by z4 (70 teeth at -0.5): -(-0.5) 70 / 50
    np.testing.assert_allclose(gears, [1.0, -0.5, 0.7, -0.5], rtol=1e-14)


def test_static_load_mesh_sign_and_torque_balance(scene):
    cfg = scene.gearbox
    gm = build_gearbox(scene)
    r = gm.reduced
    st = static_equilibrium(r, RPM0)
    assert st.converged and st.residual < 1e-12 and st.iterations < 20
    mesh = cfg.meshes[0]
    delta = float(r.contacts.directions[0] @ st.x)
    assert delta > 0                                         # working flank in contact
    f = mesh.stiffness * delta                               # mean stiffness, no TE
    geom, (sa, ga), (sb, gb) = _mesh_geometry_from_config(cfg, 0)
    off = subsystem_offsets(gm.subsystems)
    q = [s.vectors @ st.x[off[k]:off[k + 1]] for k, s in enumerate(gm.subsystems)]
    torques = []
    for c in cfg.couplings:
        s = cfg.shaft_index(c.shaft, "")
        rotor = gm.rotors[s]
        psi = q[s][rotor.dof(rotor.node_at(c.position), "psi")]
        sense = np.sign(gm.shaft_ratios[s])
        disc = sense * c.twist * (1.0 if c.role == "motor" else -1.0)
        torques.append((s, c.stiffness * (disc - psi)))      # on the shaft, about +z
    t_motor = sum(t for s, t in torques if s == 0)
    t_load = sum(t for s, t in torques if s == 1)
    # bearings act on the axis (spring links on u, v, w only): no torque about z
    for link in gm.links:
        if link.name not in ("motor", "load"):
            for s, idx, _ in link.vector.parts:
                assert np.all(idx % 6 < 3)
    # the rigid-body modes are in the basis, so the balance is exact in the reduced model
    assert t_motor == pytest.approx(f * geom.base_radius_a, rel=1e-6)
    assert t_load == pytest.approx(f * geom.base_radius_b, rel=1e-6)
    F_transmitted = t_motor / geom.base_radius_a
    assert delta == pytest.approx(F_transmitted / mesh.stiffness, rel=1e-6)
    # of the order of the nominal motor torque's force over the mesh stiffness
    nominal = cfg.couplings[0].stiffness * cfg.couplings[0].twist / geom.base_radius_a
    assert 0.3 < delta / (nominal / mesh.stiffness) < 3.0


# ------------------------------------------------------------------ layout errors

BAD = [
    (["gearbox.shafts.1.x=0.25"], "gearbox.meshes[0]", "centre distance"),
    (["gearbox.shafts.1.z=0.2"], "gearbox.meshes[0]", "centre distance"),
    (["gearbox.gears.0.shaft=nope"], "gearbox.gears[0].shaft", "unknown shaft"),
    (["gearbox.bearings.2.shaft=nope"], "gearbox.bearings[2].shaft", "unknown shaft"),
    (["gearbox.meshes.0.gear_b=z9"], "gearbox.meshes[0].gear_b", "unknown gear"),
    # a gear between nodes gets its node (config/model/gearbox.py); the mesh planes then differ
    (["gearbox.gears.1.position=0.105"], "gearbox.meshes[0].gear_b", "different planes"),
    (["gearbox.gears.1.position=0.12"], "gearbox.meshes[0].gear_b", "different planes"),
    (["gearbox.gears.0.free=true"], "gearbox.meshes[0]", "fixed gears"),
]
BAD_FREE = [
    (["gearbox.gears.3.free=true"], "gearbox.meshes[1]", "two free gears"),
]


def _check_bad(path, overrides, field, words, capsys, tmp_path):
    with pytest.raises(ConfigError) as info:
        validate_scene(load_scene(path, tuple(overrides)))
    assert info.value.path.startswith(field) and words in str(info.value)
    args = [a for o in overrides for a in ("--set", o)]
    assert main(["check", str(path), *args]) == 2
    assert field in capsys.readouterr().err
    out = tmp_path / "o"
    assert main(["run", str(path), "--quiet", "--out", str(out), *args]) == 2
    assert field in capsys.readouterr().err and not out.exists()


@pytest.mark.parametrize("overrides, field, words", BAD)
def test_layout_errors_name_the_field(overrides, field, words, capsys, tmp_path):
    _check_bad(GEAR_PAIR, overrides, field, words, capsys, tmp_path)


@pytest.mark.parametrize("overrides, field, words", BAD_FREE)
def test_layout_errors_second_mesh(free_gear_file, overrides, field, words, capsys, tmp_path):
    assert main(["check", str(free_gear_file)]) == 0         # the variant itself is valid
    capsys.readouterr()
    _check_bad(free_gear_file, overrides, field, words, capsys, tmp_path)


def test_scene_dict_without_axis_is_rejected():
    data = read_toml(GEAR_PAIR)
    del data["gearbox"]["shafts"][1]["x"]
    with pytest.raises(ConfigError, match="gearbox.shafts\\[1\\].x"):
        validate_scene(scene_from_dict(data))
