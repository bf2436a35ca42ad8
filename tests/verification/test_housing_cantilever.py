"""Slender solid cantilever (1 x 0.1 x 0.05 m steel) against the Timoshenko closed form.

The Timoshenko clamped-free frequency equation (Huang 1961) is solved here independently of
the FE code; its Euler-Bernoulli limit is checked first.  The converged 3D solid sits slightly
above Timoshenko theory (about 0.4 %: beam-theory error), so P2 must lie within [0, 1.5 %].
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from vibrogear.config.housing import MaterialConfig
from vibrogear.geometry.housing import build_beam_mesh
from vibrogear.models.housing.fe import solve_mesh_modes

L, B, H = 1.0, 0.1, 0.05
E, NU, RHO = 210e9, 0.3, 7850.0


def timoshenko_cantilever_f1(*, E, nu, rho, L, b, h, kappa=None):
    """First bending frequency (Hz) of a clamped-free Timoshenko beam bending across h."""
    A, I = b * h, b * h ** 3 / 12
    G = E / (2 * (1 + nu))
    kappa = 10 * (1 + nu) / (12 + 11 * nu) if kappa is None else kappa
    r2, s2 = I / (A * L ** 2), E * I / (kappa * G * A * L ** 2)

    def eq(bb):
        root = math.sqrt((r2 - s2) ** 2 + 4 / bb ** 2)
        al = math.sqrt(0.5 * (-(r2 + s2) + root))
        be = math.sqrt(0.5 * ((r2 + s2) + root))
        return (2 + (bb ** 2 * (r2 - s2) ** 2 + 2) * math.cosh(bb * al) * math.cos(bb * be)
                - bb * (r2 + s2) / math.sqrt(1 - bb ** 2 * r2 * s2) * math.sinh(bb * al) * math.sin(bb * be))

    bb = brentq(eq, 1.0, 5.0)          # b = sqrt(rho A L^4 omega^2 / (E I)); EB: b = 1.8751^2
    omega = bb * math.sqrt(E * I / (rho * A * L ** 4))
    return omega / (2 * math.pi)


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
