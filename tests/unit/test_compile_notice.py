"""The line on stderr while numba compiles vibrogear's kernels (issue 23, item 5:
:mod:`vibrogear.pipeline.compile_notice`): the outermost compile of a vibrogear function
only, its name and the time it took; nothing for a cached function, nothing under --quiet.

The cold-cache case compiles the integrator in a subprocess with an empty NUMBA_CACHE_DIR
(~30 s of CPU time): ``slow``."""
from __future__ import annotations

import io
import os
import re
import subprocess
import sys
from pathlib import Path

import numba
import pytest
from numba.core.event import Event, EventStatus

from vibrogear.pipeline.compile_notice import ESTIMATE, CompileNotice, compile_notice

ROOT = Path(__file__).resolve().parents[2]


class _Dispatcher:
    def __init__(self, module, name):
        def f():
            pass
        f.__module__, f.__qualname__ = module, name
        self.py_func = f


def _event(status, module, name, exc=None):
    return Event("numba:compile", status, data={"dispatcher": _Dispatcher(module, name)},
                 exc_details=exc)


def test_only_the_outermost_vibrogear_compile_prints():
    out = io.StringIO()
    n = CompileNotice(out)
    S, E = EventStatus.START, EventStatus.END
    for ev in (_event(S, "numpy.fake", "outer"),            # not vibrogear: nothing
               _event(S, "vibrogear.solvers.integrator.dopri", "dopri_loop"),
               _event(S, "vibrogear.solvers.integrator.kernels", "accel"),   # nested
               _event(S, "numba.np.fake", "helper"),
               _event(E, "numba.np.fake", "helper"),
               _event(E, "vibrogear.solvers.integrator.kernels", "accel"),
               _event(E, "vibrogear.solvers.integrator.dopri", "dopri_loop"),
               _event(E, "numpy.fake", "outer"),
               _event(S, "vibrogear.models.contact_law", "_evaluate"),
               _event(E, "vibrogear.models.contact_law", "_evaluate",
                      exc=(RuntimeError, RuntimeError("x"), None))):
        n.notify(ev)
    lines = out.getvalue().splitlines()
    assert len(lines) == 4, lines
    assert lines[0] == (f"compiling the integrator (first run or changed source; {ESTIMATE}, "
                        "cached afterwards): vibrogear.solvers.integrator.dopri.dopri_loop")
    assert re.fullmatch(r"compiled in \d+\.\d s", lines[1])
    assert lines[2] == ("compiling (first run or changed source; cached afterwards): "
                        "vibrogear.models.contact_law._evaluate")
    assert re.fullmatch(r"compile failed after \d+\.\d s", lines[3])
    assert n.announced == ["vibrogear.solvers.integrator.dopri.dopri_loop",
                           "vibrogear.models.contact_law._evaluate"]


def _fresh(module):
    """A new (uncompiled) njit function whose module is ``module``."""
    def tiny(x):
        return 2.0 * x + 1.0
    tiny.__module__ = module
    return numba.njit(tiny)


def test_a_real_compile_prints_its_name_and_time_only_inside_the_block():
    out = io.StringIO()
    with compile_notice(stream=out):
        assert _fresh("vibrogear.fake_kernels")(1.0) == 3.0
        _fresh("somebody_else")(1.0)                    # not vibrogear's: nothing
    _fresh("vibrogear.fake_kernels")(1.0)               # after the block: nothing
    lines = out.getvalue().splitlines()
    assert len(lines) == 2, lines
    assert lines[0] == ("compiling (first run or changed source; cached afterwards): "
                        "vibrogear.fake_kernels._fresh.<locals>.tiny")
    assert re.fullmatch(r"compiled in \d+\.\d s", lines[1])


def test_quiet_prints_nothing():
    out = io.StringIO()
    with compile_notice(quiet=True, stream=out) as listener:
        _fresh("vibrogear.fake_kernels")(1.0)
    assert listener is None and out.getvalue() == ""


def _time_run(cache: Path, out: Path, *extra):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    cmd = [sys.executable, "-m", "vibrogear.cli", "time", str(ROOT / "configs" /
                                                               "impact_pair.toml"),
           "--out", str(out), "--set", "time_response.periods=2", *extra]
    r = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return r.stderr


@pytest.mark.slow
def test_cold_cache_prints_the_line_and_a_warm_one_nothing(tmp_path):
    """An empty NUMBA_CACHE_DIR: `vibrogear time` announces the integrator's compile with
    the function and its time (~30 s of CPU); the same command again (cached): no line."""
    cache = tmp_path / "numba_cache"
    cache.mkdir()
    err = _time_run(cache, tmp_path / "cold")
    m = re.search(r"^compiling the integrator \(first run or changed source; ~\d+ s, cached "
                  r"afterwards\): (vibrogear\.solvers\.integrator\.\S+)\n"
                  r"compiled in (\d+\.\d) s$", err, re.M)
    assert m, err
    assert m.group(1) == "vibrogear.solvers.integrator.dopri.dopri_loop"
    assert float(m.group(2)) > 0.0
    assert not re.search(r"^compiling .*vibrogear\.solvers\.integrator\.(kernels|jacobian)",
                         err, re.M)                # nested compiles print nothing
    assert any(cache.rglob("*.nbi"))
    err = _time_run(cache, tmp_path / "warm")
    assert "compil" not in err, err
