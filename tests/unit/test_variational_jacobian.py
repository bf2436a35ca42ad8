"""The variational equations' Jacobian action, by loops and by BLAS, against independent
references: central differences of the compiled right-hand side (the Jacobian) and of
the flow (the monodromy), on the gear pair (dense rows of P, a gear mesh with events)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.config import load_scene
from vibrogear.models.gearbox.model import build_gearbox
from vibrogear.solvers.integrator import jacobian as J
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.solvers.integrator.kernels import accel, contact_modes, model_arrays
from vibrogear.solvers.static import static_equilibrium

GEAR_PAIR = Path(__file__).resolve().parents[2] / "configs" / "gear_pair.toml"


@pytest.fixture(scope="module")
def case():
    scene = load_scene(GEAR_PAIR)
    model = build_gearbox(scene).reduced
    p = 0.5 * (scene.sweep.param_min + scene.sweep.param_max)
    return model, p, static_equilibrium(model, p).u0


def _rhs(A, Om, mode, t, y):
    m = A.w2.size
    nc, r, H = A.C.shape[0], A.P.shape[0], A.Fc.shape[0]
    out, Cx, Cv, kd, cd = np.empty(2 * m), np.empty(nc), np.empty(nc), np.empty(nc), np.empty(nc)
    accel(t, y, mode, A, Om, np.empty(H), np.empty(H), out, Cx, Cv, kd, cd, np.empty(2 * r + 1))
    return out, kd, cd


def test_jacobian_action_matches_central_differences_of_the_rhs(case):
    model, p, u0 = case
    A, Om = model_arrays(model, p)[:2]
    m, n = model.n_modes, model.n_states
    t = 0.3 * model.excitation_period(p)
    rng = np.random.default_rng(1)
    y = u0 + 1e-3 * np.abs(u0).max() * rng.standard_normal(n)
    mode = np.zeros(A.C.shape[0], np.int64)
    contact_modes(A, t, Om, y[:m], mode)
    assert np.any(mode != 0)                    # the mesh is in contact: its rank-1 term acts
    _, kd, cd = _rhs(A, Om, mode, t, y)
    Phi = np.ascontiguousarray(rng.standard_normal((n, 7)))
    fd = np.empty_like(Phi)
    for c in range(Phi.shape[1]):
        h = 1e-6 * np.linalg.norm(y) / np.linalg.norm(Phi[:, c])
        fd[:, c] = (_rhs(A, Om, mode, t, y + h * Phi[:, c])[0]
                    - _rhs(A, Om, mode, t, y - h * Phi[:, c])[0]) / (2 * h)
    loops = np.empty_like(Phi)
    J.jac_times(Phi, mode, A, kd, cd, loops, J.jac_workspace(A, Phi.shape[1]))
    blas = np.empty_like(Phi)
    J.jac_times_blas(Phi, mode, A, kd, cd, blas, J.jac_blas_workspace(A, Phi.shape[1]))
    scale = np.abs(fd).max()
    assert np.abs(loops - fd).max() < 1e-6 * scale
    assert np.abs(blas - fd).max() < 1e-6 * scale
    assert np.abs(blas - loops).max() < 1e-13 * scale   # the same products, other order


def test_monodromy_by_blas_and_by_loops_match_the_flows_differences(case):
    """Three mesh periods with contact losses (saltation): both ways of applying the
    Jacobian give the same monodromy and parameter sensitivity to round-off, and both
    match central differences of the flow."""
    model, p, u0 = case
    T = 3 * model.excitation_period(p)
    o = IntegrationOptions(rtol=1e-10, atol=1e-16)
    runs = {k: integrate(model, p, u0, 0.0, T, options=o, variational=True, jacobian=k)
            for k in ("loops", "blas")}
    assert runs["loops"].events > 0 and runs["loops"].ok
    M, Mb = runs["loops"].monodromy, runs["blas"].monodromy
    assert np.abs(Mb - M).max() < 1e-9 * np.abs(M).max()
    dp, dpb = runs["loops"].dparam, runs["blas"].dparam
    assert np.abs(dpb - dp).max() < 1e-9 * np.abs(dp).max()
    m = model.n_modes
    for c in (0, m // 2, m, model.n_states - 1):     # positions and rates, both ends
        h = 1e-7 * max(1.0, abs(u0[c])) if c < m else 1e-7 * np.abs(u0[m:]).max() + 1e-9
        e = np.zeros_like(u0)
        e[c] = h
        fd = (integrate(model, p, u0 + e, 0.0, T, options=o).u_end
              - integrate(model, p, u0 - e, 0.0, T, options=o).u_end) / (2 * h)
        assert np.abs(Mb[:, c] - fd).max() < 1e-4 * np.abs(fd).max(), c


def test_jacobian_choice_is_checked(case):
    model, p, u0 = case
    with pytest.raises(ValueError, match="jacobian"):
        integrate(model, p, u0, 0.0, 1e-4, variational=True, jacobian="dense")
