"""Static correction of the master modes (residual flexibility, vibrogear.models.rotor.model.
static_correction) and the frequency criterion (vibrogear.models.gearbox.master_level).

Independent references: the full FE solve of the same shaft on its bearings (a dense
``numpy.linalg.solve`` of the assembled K) for the static deflection, the full FE
eigenvalues (dense ``scipy.linalg.eigh``) for the frequencies, and, for a whole gearbox, the
full linearised model of the reduction study (every shaft DOF, the same couplings in
physical coordinates) under the same load.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from vibrogear.config import load_scene
from vibrogear.models.rotor.model import build_rotor_model, master_modes, static_correction

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def shaft():
    """A stepped shaft with a disc and a free gear, on its two bearings, plus a torsional
    ground spring at bearing 1 and a gear-to-ground spring (so the supported K is regular);
    the coupling DOF: the bearing nodes (u, v, w; psi at bearing 1), all six of the disc
    node, the free gear's torsion."""
    rm = build_rotor_model(load_scene(ROOT / "configs" / "rotor_stepped_free_gear.toml").rotor)
    K = rm.supported()[0].toarray()
    psi = rm.dof(rm.bearing_nodes[0], "psi")
    K[psi, psi] += 1e5
    for g in rm.free_gear_dofs:
        K[g, g] += 1e3
    dofs = sorted({d for n in rm.bearing_nodes for d in rm.node_dofs(n)[:3]} | {psi}
                  | {d for n in rm.disc_nodes for d in rm.node_dofs(n)} | set(rm.free_gear_dofs))
    F = np.zeros((rm.n_dofs, len(dofs)))
    F[dofs, np.arange(len(dofs))] = 1.0
    return rm, K, rm.M.toarray(), dofs, F


def _reduced_static(V, K, F):
    return V @ np.linalg.solve(V.T @ K @ V, V.T @ F)


@pytest.mark.parametrize("cap", [False, True])
def test_static_deflection_at_the_coupling_points_is_the_full_models(shaft, cap):
    rm, K, _, dofs, F = shaft
    exact = np.linalg.solve(K, F)                          # the full FE solve
    scale = np.abs(exact[dofs]).max()
    for cut in (1000.0, 3000.0):
        mm = master_modes(rm, cutoff_hz=cut)
        plain = np.abs(_reduced_static(mm.vectors, K, F)[dofs] - exact[dofs]).max() / scale
        mc = static_correction(rm, mm, F, cap_hz=cut if cap else None)
        err = np.abs(_reduced_static(mc.vectors, K, F)[dofs] - exact[dofs]).max() / scale
        assert mc.n_static > 0
        assert err < 1e-10                                 # exact by construction
        assert plain > 1e-4                                # ... and not without it
        if cap:                                            # no vector faster than the cap
            assert mc.frequencies_hz.max() <= cut * (1 + 1e-12)
        else:                                              # Craig-Chang: kept modes unchanged
            assert np.array_equal(mc.frequencies_hz[:mm.frequencies_hz.size], mm.frequencies_hz)
            assert np.allclose(mc.vectors.T @ rm.M @ mc.vectors, np.eye(mc.vectors.shape[1]),
                               atol=1e-9)


def test_lowest_frequencies_converge_faster_with_the_static_correction(shaft):
    rm, K, M, _, F = shaft
    f_full = np.sqrt(sla.eigh(K, M, eigvals_only=True)[:8]) / (2 * np.pi)
    errs = {}
    for cut in (1000.0, 3000.0, 10000.0):
        mm = master_modes(rm, cutoff_hz=cut)
        for corr in (False, True):
            V = static_correction(rm, mm, F).vectors if corr else mm.vectors
            lam = sla.eigh(V.T @ K @ V, V.T @ M @ V, eigvals_only=True)[:8]
            rel = np.sqrt(lam) / (2 * np.pi) / f_full - 1
            assert np.all(rel > -1e-9)                     # Rayleigh-Ritz: from above
            errs[cut, corr] = rel.max()
    for cut in (1000.0, 3000.0, 10000.0):
        assert errs[cut, True] < 1e-2 * errs[cut, False]
    # with the correction, cutoff 1 kHz beats 10 kHz without it
    assert errs[1000.0, True] < errs[10000.0, False]


def test_gearbox_frequency_level_keeps_the_full_coupling_stiffness():
    """gear_pair at the frequency level: highest shaft frequency <= 2 x the highest mesh
    harmonic at the top speed (40 teeth, 7000 rpm, meshes[0]'s harmonics), every free-shaft
    mode below it kept, and the static deflection of the linearised reduced model under the
    twist-angle load and a unit mesh force equal to the full linearised model's."""
    from vibrogear.analyses.reduction_accuracy import full_linear_model
    from vibrogear.analyses.study import start_state
    from vibrogear.models.gearbox.model import build_gearbox
    from vibrogear.models.rotor.model import lowest_modes
    from vibrogear.models.gearbox.synthesis import modal_vector, subsystem_offsets
    from vibrogear.solvers.linear import tangent_matrices

    scene = load_scene(ROOT / "configs" / "gear_pair.toml")
    m0 = scene.gearbox.meshes[0]
    n_harm = max(len(m0.stiffness_cos), len(m0.stiffness_sin), len(m0.te_cos), len(m0.te_sin), 1)
    cutoff = 2.0 * 40 * 7000.0 / 60.0 * n_harm
    checks = []
    for corr in (True, False):
        gm = build_gearbox(scene, master_level="frequency", static_correction=corr)
        for sub, rotor in zip(gm.subsystems, gm.rotors):
            assert sub.freqs_hz.max() <= cutoff * (1 + 1e-12)
            f_all, _ = lowest_modes(rotor.K, rotor.M, cutoff_hz=cutoff)
            assert sub.n_modes - sub.labels["n_static"] == f_all.size
        x0 = start_state(gm.reduced, 5800.0)[:gm.reduced.n_modes]
        full, obs = full_linear_model(gm, scene, x0)
        Kt, _ = tangent_matrices(gm.reduced, x0, 0.0)
        loads = [gm.static_force, gm.contacts[0].vector]
        f_phys = np.zeros((full.n_dofs, 2))
        off = full.offsets
        for j, vec in enumerate(loads):
            for s, idx, val in vec.parts:
                np.add.at(f_phys[:, j], off[s] + idx, val)
        q_full = np.linalg.solve(full.K.toarray(), f_phys)
        F_red = np.array([modal_vector(v, gm.subsystems) for v in loads]).T / gm.omega_ref ** 2
        x = np.linalg.solve(Kt, F_red)
        ro = subsystem_offsets(gm.subsystems)
        q_red = np.vstack([sub.vectors @ x[ro[k]:ro[k + 1]]
                           for k, sub in enumerate(gm.subsystems)])
        coupled = np.unique(np.concatenate([off[s] + idx for v in gm.contacts for s, idx, _ in
                                            v.vector.parts]))
        err = np.abs(q_red[coupled] - q_full[coupled]).max() / np.abs(q_full[coupled]).max()
        checks.append(err)
    with_corr, without = checks
    assert with_corr < 1e-10
    assert without > 1e3 * with_corr
