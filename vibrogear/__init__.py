"""vibrogear: nonlinear vibration analysis of gear drives."""
import os as _os

# GNU OpenMP is not fork-safe: once a process has run an OpenMP region (CHOLMOD's
# factorisation of a housing's stiffness, through PETSc), worker processes forked from it
# deadlock in their first OpenMP region (found in `make test-slow`: an optimisation whose
# forked evaluations each built a housing hung in cholmod_super_numeric).  One OpenMP
# thread keeps every fork safe; the parallelism is the worker processes and MPI ranks.
# Set before any library that reads it is loaded; a value the user sets is kept.
_os.environ.setdefault("OMP_NUM_THREADS", "1")

__version__ = "0.1.0"
__all__ = ["__version__"]
