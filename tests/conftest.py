"""Test-session settings, made once in the controlling process before any xdist worker
starts (the workers inherit its environment and find the compiled code on disk):

* single-threaded BLAS before numpy loads (worker processes are forked; a BLAS thread pool
  in the parent is what a fork can deadlock on);
* a temporary vibrogear cache (``VIBROGEAR_CACHE_DIR``) for the session, shared by the
  workers and removed at its end, unless the caller names one: the tests neither read nor
  fill the user's ``~/.cache/vibrogear``;
* with workers (``-n``), the integrator compiled before they start: numba's on-disk cache
  (:mod:`vibrogear.models.numba_cache`) then holds it and every worker loads it instead of
  compiling it again (on a fresh machine each worker spent ~25 s of CPU on that compile).
"""
import os
import shutil
import tempfile

import pytest

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

_SESSION_CACHE = []          # the temporary cache folder this process made (to remove)


def _controller(config) -> bool:
    return not hasattr(config, "workerinput")


def _compile_integrator() -> None:
    """Run every compiled function once on the impact pair: a contact event, dense output
    and the variational equations (a cold cache compiles them; a warm one loads them)."""
    import numpy as np

    from vibrogear.models.contact_law import evaluate
    from vibrogear.models.impact_pair import impact_pair_model
    from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate

    model = impact_pair_model(zeta=0.05, kappa=0.5, f_m=0.55, f_p=0.12, b_r=1.0)
    T = 2 * np.pi / 0.9
    integrate(model, 0.9, np.array([1.05, 0.0]), 0.0, 2 * T, t_eval=np.linspace(0, 2 * T, 9),
              options=IntegrationOptions(rtol=1e-8, atol=1e-10), variational=True)
    evaluate(np.zeros(2), k_hi=1.0, k_lo=1.0, gap_hi=0.0, gap_lo=-1.0, exponent=1.0)


def pytest_configure(config):
    if not _controller(config):
        return
    if not os.environ.get("VIBROGEAR_CACHE_DIR"):
        _SESSION_CACHE.append(tempfile.mkdtemp(prefix="vibrogear-test-cache."))
        os.environ["VIBROGEAR_CACHE_DIR"] = _SESSION_CACHE[0]
    workers = getattr(config.option, "numprocesses", None)
    if workers and workers != "0" and getattr(config.option, "dist", "no") != "no":
        try:
            _compile_integrator()
        except Exception as exc:        # noqa: BLE001 - the workers compile (or fail) then
            import warnings
            warnings.warn(f"compiling the integrator before the workers start failed: {exc!r}")


def pytest_unconfigure(config):
    if _controller(config):
        for d in _SESSION_CACHE:
            shutil.rmtree(d, ignore_errors=True)


@pytest.fixture(scope="module")
def empty_vibrogear_cache(tmp_path_factory):
    """An empty vibrogear cache for one test module (tests that must see a cache miss or
    keep their housings apart from the session's), the session's restored after it."""
    d = tmp_path_factory.mktemp("vgcache")
    old = os.environ.get("VIBROGEAR_CACHE_DIR")
    os.environ["VIBROGEAR_CACHE_DIR"] = str(d)
    yield d
    if old is None:
        os.environ.pop("VIBROGEAR_CACHE_DIR")
    else:
        os.environ["VIBROGEAR_CACHE_DIR"] = old
