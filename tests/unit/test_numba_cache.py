"""The compiled modules share one cache stamp: an edit of the contact law alone must not
leave cached kernels inlining the old law (numba stamps only a function's own file)."""
from __future__ import annotations

import os
from pathlib import Path

from vibrogear.models import numba_cache
from vibrogear.models.contact_law import contact_force
from vibrogear.solvers.integrator import dopri, kernels


def _locator(dispatcher):
    dispatcher.enable_caching()
    return dispatcher._cache._impl.locator


def test_compiled_functions_use_the_joint_stamp():
    for fn in (kernels.accel, dopri.dopri_loop, contact_force):
        assert type(_locator(fn)).__name__ == "_JointStampLocator"


def test_the_stamp_covers_every_compiled_module():
    stamp = _locator(kernels.accel).get_source_stamp()
    assert len(stamp) == len(numba_cache.COMPILED_SOURCES)
    # every solver module with cached compiled functions (they inline each other) is stamped
    solvers = Path(kernels.__file__).parent
    compiled = {str(p) for p in solvers.glob("*.py") if "@njit(cache=True" in p.read_text()}
    assert {"kernels.py", "dopri.py", "variational.py", "dense_output.py"} <= {
        Path(p).name for p in compiled}
    assert compiled <= set(numba_cache.COMPILED_SOURCES)
    law = numba_cache.COMPILED_SOURCES[0]
    assert law.endswith(os.path.join("models", "contact_law.py"))
    st = os.stat(law)
    assert stamp[0] == (st.st_mtime, st.st_size)   # the kernels' stamp moves with the law's file
