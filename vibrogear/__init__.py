"""vibrogear: nonlinear vibration analysis of gear drives.

From Python (:mod:`vibrogear.api`, imported on first use, so ``import vibrogear`` stays
cheap: no numba, dolfinx or matplotlib until a run needs them)::

    import vibrogear as vg
    scene = vg.load("configs/gear_pair.toml")
    run = vg.run(scene.replace({"sweep.n_points": 6}), ["sweep"])   # in memory, writes nothing
    run.results["sweep"].arrays(); run.results["sweep"].plot(); run.findings

``load``, ``replace`` (a method of the scene), ``check``, ``run``, ``import_rexs``, ``compare`` and the
``Run`` they return are documented in :mod:`vibrogear.api` and docs/python.md.
"""
import os as _os

# GNU OpenMP is not fork-safe: once a process has run an OpenMP region (CHOLMOD's
# factorisation of a housing's stiffness, through PETSc), worker processes forked from it
# deadlock in their first OpenMP region (found in `make test-slow`: an optimisation whose
# forked evaluations each built a housing hung in cholmod_super_numeric).  One OpenMP
# thread keeps every fork safe; the parallelism is the worker processes and MPI ranks.
# Set before any library that reads it is loaded; a value the user sets is kept.
_os.environ.setdefault("OMP_NUM_THREADS", "1")

from .lazy import lazy_exports  # noqa: E402
from .version import __version__  # noqa: E402

#: the public API, re-exported from vibrogear.api on first access
_API = ("load", "run", "check", "import_rexs", "compare", "Run", "ConfigError",
        "NumericalFailure")
__all__ = ["__version__", *_API]

__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(_API, "api"))
