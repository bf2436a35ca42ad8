"""Housing FE model: what its eigen-solver modules share (:mod:`.fe_eigen`, :mod:`.fe_slepc`,
:mod:`.fe_iterative`): the PETSc options prefix, the solver failure and the scoped option
defaults.  PETSc is imported inside functions (see :mod:`.fe`)."""
from __future__ import annotations

from contextlib import contextmanager

__all__ = ["PREFIX", "HousingSolveError", "option_defaults"]

#: the PETSc options prefix of the housing eigen-solve (``-vghousing_...``)
PREFIX = "vghousing_"


class HousingSolveError(RuntimeError):
    """The eigen-solve failed or converged too few modes."""


@contextmanager
def option_defaults(prefix: str, defaults: dict):
    """PETSc options ``prefix + key`` set to ``defaults`` where the user set none, for the
    ``setFromOptions``/``setUp`` inside the block; removed after it (a user's stay)."""
    from petsc4py import PETSc

    opts = PETSc.Options()
    added = [k for k in defaults if f"{prefix}{k}" not in opts]
    for k in added:
        opts[f"{prefix}{k}"] = defaults[k]
    try:
        yield
    finally:
        for k in added:
            opts.delValue(f"{prefix}{k}")
