"""Housing eigen-solver choices: ``[housing.modes] solver`` validation (bad values exit 2 naming
the field), cache keys that follow the solver and the resolved mesh default, and agreement of the
SLEPc and AMG (iterative) paths with the block Lanczos frequencies on a small housing."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from vibrogear.config import ConfigError
from vibrogear.config.base import build
from vibrogear.config.model.housing import HOUSING_SOLVERS, HousingConfig

ROOT = Path(__file__).resolve().parents[2]
SMALL = ROOT / "configs" / "housing_small.toml"
VG = Path(sys.executable).parent / "vibrogear"


def _housing(**modes):
    d = dict(length=0.3, width=0.2, height=0.2, wall_thickness=0.012, modes=modes,
             bores=[dict(x=0.1, z=0.1, bore_radius=0.02, boss_radius=0.035, rolling_elements=9)])
    return build(HousingConfig, d, "housing")


@pytest.mark.parametrize("solver", HOUSING_SOLVERS)
def test_every_solver_choice_has_an_eigen_solver(solver):
    """Each ``[housing.modes] solver`` the config accepts is one the FE module dispatches:
    block Lanczos or an entry of the SLEPc table (the two registries agree)."""
    from vibrogear.models.housing.fe_slepc import SLEPC_SOLVERS

    assert _housing(solver=solver).modes.solver == solver
    assert solver == "block" or solver in SLEPC_SOLVERS


def test_bad_solver_value_names_the_field():
    with pytest.raises(ConfigError) as e:
        _housing(solver="arpack")
    assert "housing.modes.solver" in str(e.value) and "krylovschur_gamg" in str(e.value)


def test_bad_solver_through_cli_exits_2(tmp_path):
    env = {**os.environ, "VIBROGEAR_CACHE_DIR": str(tmp_path / "cache")}
    r = subprocess.run([str(VG), "modes", str(SMALL), "--quiet", "--out", str(tmp_path / "out"),
                        "--set", "housing.modes.solver=lanczos"], capture_output=True, text=True, env=env,
                       cwd=ROOT, timeout=120)
    assert r.returncode == 2, r.stderr
    assert "housing.modes.solver" in r.stderr and "lanczos" in r.stderr
    assert not (tmp_path / "out").exists() and not (tmp_path / "cache").exists()


def test_modes_key_follows_solver_and_resolved_mesh_default(monkeypatch):
    from vibrogear.models.housing.run import housing_cache_key

    a, b = _housing(solver="block"), _housing(solver="krylovschur")
    assert housing_cache_key(a, "modes") != housing_cache_key(b, "modes")
    assert housing_cache_key(a, "mesh") == housing_cache_key(b, "mesh")
    before = {s: housing_cache_key(a, s) for s in ("mesh", "modes", "matrices")}
    # a new default mesh-size rule (mesh.size left out) gives new mesh, modes and matrices keys
    monkeypatch.setattr(HousingConfig, "mesh_size", property(lambda self: 0.9 * self.wall_thickness))
    after = {s: housing_cache_key(a, s) for s in ("mesh", "modes", "matrices")}
    assert all(before[s] != after[s] for s in before)


_DRIVER = r"""
import json, sys
import numpy as np
from vibrogear.config import load_scene
from vibrogear.models.housing.run import housing_modes
out = {}
for solver, tol in json.loads(sys.argv[2]):
    sc = load_scene(sys.argv[1], ("housing.mesh.size=0.03", "housing.modes.count=6", "housing.modes.shapes=0",
                                  f"housing.modes.solver={solver}", f"housing.modes.tol={tol}"))
    r = housing_modes(sc.housing, cache=False)
    out[solver] = {"f": r.freqs_hz.tolist(), "res": float(np.max(r.residuals)), "orth": r.orthogonality_error,
                   "status": r.status, "n": r.n_modes}
print(json.dumps(out))
"""


def _solve(tmp_path, cases):
    env = {**os.environ, "VIBROGEAR_CACHE_DIR": str(tmp_path / "cache"), "OPENBLAS_NUM_THREADS": "1"}
    p = subprocess.run([sys.executable, "-c", _DRIVER, str(SMALL), json.dumps(cases)], capture_output=True,
                       text=True, env=env, cwd=ROOT, timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_solver_paths_agree_with_block_lanczos(tmp_path):
    """Direct SLEPc methods to 1e-8 of block Lanczos; the AMG path (inner CG to min(1e-3 tol,
    1e-10)) to 1e-6."""
    res = _solve(tmp_path, [("block", 1e-8), ("krylovschur", 1e-8), ("subspace", 1e-8),
                            ("krylovschur_gamg", 1e-6)])
    ref = np.array(res["block"]["f"])
    assert len(ref) == 6
    for solver, rtol in (("krylovschur", 1e-8), ("subspace", 1e-8), ("krylovschur_gamg", 1e-6)):
        r = res[solver]
        assert r["status"] == "ok" and r["n"] == 6, (solver, r)
        np.testing.assert_allclose(r["f"], ref, rtol=rtol, err_msg=solver)
        assert r["orth"] < 1e-8, (solver, r)
        assert r["res"] < 1e-4, (solver, r)
