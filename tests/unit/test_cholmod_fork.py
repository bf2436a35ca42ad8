"""A worker process forked from one that ran CHOLMOD factorises a housing's stiffness with
MUMPS (models/housing/fe_eigen.py ``cholesky_factor``).  CHOLMOD's supernodal factorisation
starts GNU OpenMP threads of its own, and GNU OpenMP is not fork-safe: with CHOLMOD again in
the forked process, its first factorisation waited forever (an optimisation whose
evaluations each build a housing, after the parent had built one).  Here: a 3D Laplacian
(27,000 unknowns) factorised in this process, then in two forked workers; they finish and
name MUMPS, this process keeps CHOLMOD, and each factor solves K x = b to 1e-10."""
from __future__ import annotations

import numpy as np
import pytest

petsc4py = pytest.importorskip("petsc4py")


def _laplacian(m: int = 30):
    import scipy.sparse as sp
    from petsc4py import PETSc

    eye = sp.identity(m)
    d = sp.diags([np.full(m - 1, -1.0), np.full(m - 1, -1.0)], [-1, 1])
    A = (sp.kron(sp.kron(eye, eye), d) + sp.kron(sp.kron(eye, d), eye)
         + sp.kron(sp.kron(d, eye), eye) + 7.0 * sp.identity(m ** 3)).tocsr()
    K = PETSc.Mat().createAIJ(size=A.shape, csr=(A.indptr, A.indices, A.data),
                              comm=PETSc.COMM_SELF)
    K.assemble()
    return K, A


def _factor_and_solve(_unit=None, _emit=None):
    from petsc4py import PETSc

    from vibrogear.models.housing.fe_eigen import cholesky_factor

    K, A = _laplacian()
    ksp = cholesky_factor(K, PETSc.COMM_SELF.tompi4py())
    b = K.createVecLeft()
    b.setArray(np.linspace(1.0, 2.0, A.shape[0]))
    x = K.createVecRight()
    ksp.solve(b, x)
    res = np.linalg.norm(A @ x.getArray() - b.getArray()) / np.linalg.norm(b.getArray())
    return ksp.getPC().getFactorSolverType(), float(res)


@pytest.mark.timeout(120)
def test_forked_workers_after_cholmod_take_mumps_and_finish():
    from petsc4py import PETSc

    from vibrogear.pipeline.executors import run_units

    if not PETSc.Sys.hasExternalPackage("suitesparse"):
        pytest.skip("PETSc without SuiteSparse: CHOLMOD is never chosen")
    here = _factor_and_solve()
    assert here[0] == "cholmod" and here[1] < 1e-10
    got = run_units(_factor_and_solve, [0, 1], workers=2)
    assert [g[0] for g in got] == ["mumps", "mumps"]
    assert all(g[1] < 1e-10 for g in got)
    assert _factor_and_solve()[0] == "cholmod"          # this process keeps CHOLMOD
