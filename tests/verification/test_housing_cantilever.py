"""Slender solid cantilever (1 x 0.1 x 0.05 m steel) against the Timoshenko closed form.

The Timoshenko clamped-free frequency equation (Huang 1961) is solved here independently of
the FE code; its Euler-Bernoulli limit is checked first.  The converged 3D solid sits slightly
above Timoshenko theory (about 0.4 %: beam-theory error), so P2 must lie within [0, 1.5 %].
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from reference.timoshenko_beam import timoshenko_cantilever_f1
from vibrogear.config.model.housing import MaterialConfig
from vibrogear.geometry.housing import build_beam_mesh
from vibrogear.models.housing.fe import solve_mesh_modes

L, B, H = 1.0, 0.1, 0.05
E, NU, RHO = 210e9, 0.3, 7850.0




def test_closed_form_euler_bernoulli_limit():
    # a very slender beam: Timoshenko -> Euler-Bernoulli, (beta L)^2 = 1.875104^2
    f = timoshenko_cantilever_f1(E=E, nu=NU, rho=RHO, L=100.0, b=0.1, h=0.05)
    I, A = 0.1 * 0.05 ** 3 / 12, 0.1 * 0.05
    f_eb = 1.8751040687 ** 2 * math.sqrt(E * I / (RHO * A * 100.0 ** 4)) / (2 * math.pi)
    assert f == pytest.approx(f_eb, rel=1e-6)


@pytest.fixture(scope="module")
def beam_modes(tmp_path_factory):
    d = tmp_path_factory.mktemp("beam")
    mesh = build_beam_mesh(L, B, H, d / "beam.msh", size=0.025)
    mat = MaterialConfig(E=E, nu=NU, rho=RHO)
    return {deg: solve_mesh_modes(mesh, material=mat, degree=deg, count=4) for deg in (1, 2)}


def test_p2_bending_matches_timoshenko(beam_modes):
    res = beam_modes[2]
    f_thin = timoshenko_cantilever_f1(E=E, nu=NU, rho=RHO, L=L, b=B, h=H)    # bending across 0.05
    f_wide = timoshenko_cantilever_f1(E=E, nu=NU, rho=RHO, L=L, b=H, h=B)    # bending across 0.1
    rel = (res.freqs_hz[:2] - [f_thin, f_wide]) / [f_thin, f_wide]
    print(f"P2 {res.n_dofs} DOF: f1 {res.freqs_hz[0]:.3f} Hz vs {f_thin:.3f} ({rel[0]:+.3%}), "
          f"f2 {res.freqs_hz[1]:.3f} vs {f_wide:.3f} ({rel[1]:+.3%})")
    assert np.all(rel > 0.0) and np.all(rel < 0.015)
    assert res.residuals.max() < 1e-6 and res.orthogonality_error < 1e-8
    assert res.mass_kg == pytest.approx(RHO * L * B * H, rel=1e-10)


def test_p1_is_stiffer_than_p2_on_the_same_mesh(beam_modes):
    """P1 tets lock in bending: same mesh, higher frequencies (both converge from above)."""
    assert np.all(beam_modes[1].freqs_hz[:2] > beam_modes[2].freqs_hz[:2] * 1.05)
