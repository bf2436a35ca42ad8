"""The full linear reference model: sparse assembly with rank-one couplings, lowest modes of a
singular (unsupported) system against dense eigh, modal synthesis of free-free chains (exact with
all modes kept, monotone convergence under truncation), MAC and mode pairing."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from vibrogear.models.gearbox.full_linear import (assemble_full, coupling_vector, lowest_modes_full, mac_matrix,
                                          pair_modes)


def chain(n: int, seed: int) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """Free-free spring-mass chain: masses 0.5-1.5 kg, springs 0.5-1.5 MN/m (K singular)."""
    rng = np.random.default_rng(seed)
    k = 1e6 * rng.uniform(0.5, 1.5, n - 1)
    m = rng.uniform(0.5, 1.5, n)
    main = np.zeros(n)
    main[:-1] += k
    main[1:] += k
    K = sp.diags([main, -k, -k], [0, 1, -1], format="csr")
    return K, sp.diags(m, format="csr")


def spring(n: int, i: int, j: int) -> tuple[np.ndarray, np.ndarray]:
    """c = e_i - e_j as an (indices, values) pair."""
    return np.array([i, j]), np.array([1.0, -1.0])


N1, N2 = 40, 50
A_NODE, B_NODE = 17, 3           # the coupling spring joins chain 1 node 17 and chain 2 node 3
K_C = 3e5


@pytest.fixture(scope="module")
def two_chains():
    blocks = [chain(N1, 1), chain(N2, 2)]
    model = assemble_full(blocks, [(spring(N1 + N2, A_NODE, N1 + B_NODE), K_C)])
    lam, X = sla.eigh(model.K.toarray(), model.M.toarray())
    return blocks, model, lam, X


def test_assembly_offsets_and_coupling_vector_formats(two_chains):
    blocks, model, _, _ = two_chains
    n = N1 + N2
    assert list(model.offsets) == [0, N1, n] and model.n_dofs == n
    assert model.block(1) == slice(N1, n) and model.D is None
    K = model.K.toarray()
    assert np.array_equal(K[:N1, :N1] - blocks[0][0].toarray(),
                          K_C * np.outer(np.eye(N1)[A_NODE], np.eye(N1)[A_NODE]))
    assert K[A_NODE, N1 + B_NODE] == -K_C and np.allclose(K, K.T)
    assert np.array_equal(model.M.toarray(), sla.block_diag(*(b[1].toarray() for b in blocks)))
    # the same coupling as a sparse row, a sparse column, a dense array and an (indices, values) pair
    dense = np.zeros(n)
    dense[[A_NODE, N1 + B_NODE]] = [1.0, -1.0]
    for c in (sp.csr_matrix(dense), sp.csc_matrix(dense[:, None]), dense, spring(n, A_NODE, N1 + B_NODE)):
        assert abs(assemble_full(blocks, [(c, K_C)]).K - model.K).max() == 0.0
        assert np.array_equal(coupling_vector(c, n).toarray().ravel(), dense)
    with pytest.raises(ValueError):
        coupling_vector(np.ones(n + 1), n)
    # damping: block damping plus a rank-one dashpot
    damped = assemble_full(blocks, [(dense, K_C, 7.0)], damping_blocks=[1e-5 * blocks[0][0], None])
    D = damped.D.toarray()
    assert np.allclose(D[:N1, :N1] - 1e-5 * blocks[0][0].toarray(),
                       7.0 * np.outer(dense, dense)[:N1, :N1])
    assert D[N1 + B_NODE, N1 + B_NODE] == 7.0 and np.count_nonzero(D[N1:, N1:]) == 1


def test_lowest_modes_of_the_unsupported_coupled_chains_match_dense_eigh(two_chains):
    """K is singular (one rigid-body mode): the negative shift copes; 33 modes via ARPACK."""
    _, model, lam, X = two_chains
    f_ref = np.sqrt(np.maximum(lam, 0)) / (2 * np.pi)
    f_max = 0.5 * (f_ref[32] + f_ref[33])
    f, V = lowest_modes_full(model, f_max)
    assert f.shape == (33,) and V.shape == (N1 + N2, 33)
    assert abs(lam[0]) < 1e-6 * lam[1] and f[0] < 1e-5 * f[1]        # the rigid-body mode
    assert np.allclose(f[1:], f_ref[1:33], rtol=1e-10, atol=0)
    assert np.allclose(V.T @ model.M @ V, np.eye(33), atol=1e-10)
    assert np.allclose(np.diag(mac_matrix(V, X[:, :33], model.M)), 1.0, atol=1e-10)
    for i, j, mac, err in pair_modes(f_ref[:33], X[:, :33], f, V, model.M):
        # the rigid-body mode's frequency is round-off (checked against f[1] above): its
        # relative error compares two round-off values and is not asserted
        assert i == j and mac > 1 - 1e-10 and (i == 0 or abs(err) < 1e-9)
    # the whole spectrum (the request reaches N - 1: dense path), and the max_count cap
    f_all, V_all = lowest_modes_full(model, 2 * f_ref[-1])
    assert f_all.size == N1 + N2 and np.allclose(f_all[1:], f_ref[1:], rtol=1e-10)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        f10, _ = lowest_modes_full(model, f_max, max_count=10)
    assert f10.size == 10 and any("max_count" in str(x.message) for x in w)


def _synthesis(blocks, m_keep):
    """Modal synthesis: each chain reduced to its lowest m_keep free-free modes, joined in modal
    coordinates by the same rank-one spring (c_r = V^T c), assembled by assemble_full."""
    red, V = [], []
    for K, M in blocks:
        lam, Phi = sla.eigh(K.toarray(), M.toarray())
        red.append((sp.diags(lam[:m_keep]), sp.identity(m_keep)))
        V.append(Phi[:, :m_keep])
    c_r = np.concatenate([V[0][A_NODE], -V[1][B_NODE]])
    return assemble_full(red, [(c_r, K_C)]), sla.block_diag(*V)


def test_modal_synthesis_with_all_modes_is_exact_and_converges_monotonically(two_chains):
    blocks, model, lam, X = two_chains
    f_ref = np.sqrt(np.maximum(lam, 0)) / (2 * np.pi)
    # all modes kept per chain (padded to the same count is not needed: each keeps its own n)
    red, V = [], []
    for K, M in blocks:
        lam_s, Phi = sla.eigh(K.toarray(), M.toarray())
        red.append((sp.diags(lam_s), sp.identity(K.shape[0])))
        V.append(Phi)
    c_r = np.concatenate([V[0][A_NODE], -V[1][B_NODE]])
    full_r = assemble_full(red, [(c_r, K_C)])
    Vb = sla.block_diag(*V)
    assert np.allclose(full_r.K.toarray(), Vb.T @ model.K @ Vb, atol=1e-8 * lam.max())
    f_r, Q = lowest_modes_full(full_r, 1.01 * f_ref[-1])
    assert np.allclose(f_r[1:], f_ref[1:], rtol=1e-9)
    assert np.allclose(np.diag(mac_matrix(Vb @ Q[:, 1:], X[:, 1:], model.M)), 1.0, atol=1e-9)
    # truncation: nested Ritz spaces, so each of the 8 lowest elastic frequencies decreases
    # monotonically towards the full one from above (Rayleigh-Ritz upper bounds)
    errors = []
    for m_keep in (6, 10, 15, 20, 30, 40):
        red_m, Vm = _synthesis(blocks, m_keep)
        f_m, Qm = lowest_modes_full(red_m, 10 * f_ref[-1])
        rel = f_m[1:9] / f_ref[1:9] - 1
        assert np.all(rel > -1e-12)
        errors.append(rel)
        assert min(p[2] for p in pair_modes(f_ref[1:9], X[:, 1:9], f_m[1:9], Vm @ Qm[:, 1:9],
                                            model.M)) > 0.9
    errors = np.array(errors)
    assert np.all(np.diff(errors, axis=0) <= 1e-12)
    assert errors[-1].max() < 1e-3 * errors[0].max() and errors[0].max() > 1e-4


def test_mac_of_identical_scaled_and_m_orthogonal_vectors(two_chains):
    _, model, _, X = two_chains
    Y = X[:, :12]
    assert np.allclose(mac_matrix(Y, Y, model.M), np.eye(12), atol=1e-12)     # M-orthogonal modes
    assert np.allclose(np.diag(mac_matrix(Y, -3.0 * Y)), 1.0)                 # scale and sign free
    assert mac_matrix(Y[:, 0], Y[:, 0]).shape == (1, 1)
    z = Y[:, :3] * np.exp(1j * np.array([0.3, 1.0, 2.0]))                      # complex phases
    assert np.allclose(np.diag(mac_matrix(z, Y[:, :3], model.M)), 1.0)
    assert np.allclose(mac_matrix(Y, Y, model.M.toarray()), mac_matrix(Y, Y, model.M))
    rng = np.random.default_rng(0)
    R = rng.standard_normal((Y.shape[0], 4))
    assert np.all((mac_matrix(R, Y) >= 0) & (mac_matrix(R, Y) <= 1 + 1e-12))
    # pairing finds a shuffled, sign-flipped candidate set
    perm = np.array([3, 0, 5, 1, 4, 2, 7, 6, 9, 8, 11, 10])
    f = np.arange(1.0, 13.0)
    pairs = pair_modes(f, Y, f[perm] * 1.01, -Y[:, perm], model.M)
    assert [p[1] for p in pairs] == list(np.argsort(perm))
    assert all(abs(p[2] - 1) < 1e-12 and abs(p[3] - 0.01) < 1e-12 for p in pairs)
