"""Hexahedral cantilever (1 x 0.1 x 0.05 m steel, Q2/Q3, GLL-lumped mass) against the Timoshenko
closed form (tests/reference/timoshenko_beam.py, solved independently of the FE code).

The converged 3D solid sits ~0.45 % above Timoshenko theory for this beam (beam-theory error: the
tet P2/P3 studies find the same, docs/housing.md); so the bounds are [0, 0.8 %] for Q3 with one
element through the 0.05 m thickness (the housing's "one element through the wall"), and the
fine Q3 result must sit at that offset: within 0.35-0.55 % of Timoshenko.  Refinement must move
the Q3 frequencies down towards it (GLL lumping lowers them slightly, the stiffness raises them;
both vanish with h).
"""
from __future__ import annotations

import numpy as np
import pytest

from reference.timoshenko_beam import timoshenko_cantilever_f1
from vibrogear.config.model.housing import MaterialConfig

L, B, H = 1.0, 0.1, 0.05
E, NU, RHO = 210e9, 0.3, 7850.0


@pytest.fixture(scope="module")
def hex_beam(tmp_path_factory):
    from vibrogear.geometry.housing_hex import build_hex_beam_mesh
    from vibrogear.models.housing.fe import solve_mesh_modes

    d = tmp_path_factory.mktemp("hexbeam")
    mat = MaterialConfig(E=E, nu=NU, rho=RHO)
    out = {}
    for cells, degrees in (((10, 2, 1), (2, 3)), ((20, 2, 1), (3,)), ((40, 4, 2), (3,))):
        mesh = build_hex_beam_mesh(L, B, H, d / f"beam{cells[0]}", cells=cells)
        assert mesh.cell_type == "hexahedron"
        for deg in degrees:
            res = solve_mesh_modes(mesh, material=mat, degree=deg, count=4)
            assert res.residuals.max() < 1e-6 and res.orthogonality_error < 1e-8
            assert res.mass_kg == pytest.approx(RHO * L * B * H, rel=1e-10)
            out[cells, deg] = res.freqs_hz[:2]
    return out


def _timoshenko():
    return np.array([timoshenko_cantilever_f1(E=E, nu=NU, rho=RHO, L=L, b=B, h=H),     # across 0.05
                     timoshenko_cantilever_f1(E=E, nu=NU, rho=RHO, L=L, b=H, h=B)])    # across 0.1


def test_q3_one_element_through_the_thickness_matches_timoshenko(hex_beam):
    ref = _timoshenko()
    rel = hex_beam[(10, 2, 1), 3] / ref - 1
    print(f"Q3 10x2x1: {np.round(100 * rel, 3)} % vs Timoshenko {ref}")
    assert np.all(rel > 0.0) and np.all(rel < 0.008)


def test_q3_refined_sits_at_the_3d_offset_above_timoshenko(hex_beam):
    ref = _timoshenko()
    fine = hex_beam[(40, 4, 2), 3] / ref - 1
    mid = hex_beam[(20, 2, 1), 3] / ref - 1
    coarse = hex_beam[(10, 2, 1), 3] / ref - 1
    print(f"Q3 offsets: coarse {coarse}, mid {mid}, fine {fine}")
    assert np.all(fine > 0.0025) and np.all(fine < 0.0055)
    assert np.all(coarse > mid) and np.all(mid > fine)


def test_q3_beats_q2_on_the_same_grid(hex_beam):
    ref = hex_beam[(40, 4, 2), 3]
    e2 = hex_beam[(10, 2, 1), 2] / ref - 1
    e3 = hex_beam[(10, 2, 1), 3] / ref - 1
    assert np.all(e3 < e2 / 2)
