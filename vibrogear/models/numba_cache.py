"""numba's on-disk cache for vibrogear's compiled modules, invalidated as one.

numba reuses a cached function when the stamp (modification time and size) of the file
that defines it is unchanged.  The kernels inline the contact law
(:mod:`vibrogear.models.contact_law`) and the integrator inlines the kernels, so an edit
of the law alone left the cached kernels running the old law.  This locator stamps every
function of these modules with the stamps of all of them: editing any one recompiles
them all.  Import it before the first compiled call (the compiled modules do).
"""
from __future__ import annotations

import os

from numba.core import caching, config

__all__ = ["COMPILED_SOURCES"]

_PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: the modules whose compiled functions inline each other
COMPILED_SOURCES = tuple(os.path.join(_PACKAGE, *p.split("/")) for p in (
    "models/contact_law.py", "solvers/integrator/kernels.py", "solvers/integrator/tableau.py",
    "solvers/integrator/dense_output.py", "solvers/integrator/jacobian.py", "solvers/integrator/variational.py",
    "solvers/integrator/dopri.py"))

_Base = caching.UserProvidedCacheLocator if config.CACHE_DIR else caching.InTreeCacheLocator


class _JointStampLocator(_Base):
    """The usual locator for these files, with a stamp covering all of them."""

    def get_source_stamp(self):
        stamps = []
        for path in COMPILED_SOURCES:
            st = os.stat(path)
            stamps.append((st.st_mtime, st.st_size))
        return tuple(stamps)

    @classmethod
    def from_function(cls, py_func, py_file):
        if os.path.abspath(py_file) not in COMPILED_SOURCES:
            return None
        return super().from_function(py_func, py_file)


if not any(c.__name__ == _JointStampLocator.__name__ for c in caching.CacheImpl._locator_classes):
    caching.CacheImpl._locator_classes.insert(0, _JointStampLocator)
