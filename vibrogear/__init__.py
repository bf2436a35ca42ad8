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

# One OpenMP thread per process: the parallelism is the worker processes and MPI ranks.  (It
# does not make GNU OpenMP fork-safe: CHOLMOD starts its own team whatever this says, and a
# process forked from one that ran it deadlocks in its first CHOLMOD factorisation; the
# housing's factorisation takes MUMPS in such a process: models/housing/fe_eigen.py.)
# Set before any library that reads it is loaded; a value the user sets is kept.
_os.environ.setdefault("OMP_NUM_THREADS", "1")

from .lazy import lazy_exports  # noqa: E402
from .version import __version__  # noqa: E402

#: the public API, re-exported from vibrogear.api on first access
_API = ("load", "run", "check", "import_rexs", "compare", "Run", "ConfigError",
        "NumericalFailure")
__all__ = ["__version__", *_API]

__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(_API, "api"))
