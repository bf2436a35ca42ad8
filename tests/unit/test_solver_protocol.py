"""The solver result protocol (one status enum), the continuation call shape with its
callback, options defined once, and the parameter keys each model declares."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.config import load_scene
from vibrogear.config.base import ConfigError
from vibrogear.config.scene import read_toml, scene_from_dict
from vibrogear.models.impact_pair import impact_pair_model
from vibrogear.solvers.periodic.continuation import (ContinuationOptions, PeriodicOrbitProblem,
                                            PseudoArclength, continuation)
from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate
from vibrogear.status import MESSAGES, Status, from_code
from vibrogear.verification import impact_exact as ex

CONFIGS = sorted(Path("configs").glob("*.toml"))


# ---------------------------------------------------------------- status

def test_every_status_has_one_message_and_integer_codes_round_trip():
    assert set(MESSAGES) == set(Status)
    for s in Status:
        assert from_code(int(s)) is s and s.message == MESSAGES[s]
    # the codes of the compiled loop (solvers/integrator/dopri.py) are the integrator members
    assert [from_code(c) for c in (0, -1, -2, -3, -4, -5)] == [
        Status.OK, Status.MAX_STEPS, Status.NONFINITE, Status.CHATTERING,
        Status.STEP_TOO_SMALL, Status.GRAZING]
    with pytest.raises(ValueError, match="unknown solver status"):
        from_code(-99)
    assert Status.LEFT_RANGE.success and not Status.STOPPED_BY_CALLBACK.success


def test_integrator_error_estimate_bounds_the_true_error():
    """Linear motion (clearance never reached): the accumulated local error estimate is an
    upper bound of the error against the exact solution, and it falls with rtol."""
    par = dict(zeta=0.05, kappa=0.5, f_m=0.0, f_p=0.2, b_r=100.0)
    model = impact_pair_model(**par)
    om, u0 = 0.9, np.array([0.1, 0.0])
    T = 20 * 2 * np.pi / om
    ref = ex.exact_flow(ex.ImpactParams(**par), om, u0, 0.0, T).u_end
    estimates = []
    for rtol in (1e-5, 1e-8):
        tr = integrate(model, om, u0, 0.0, T, options=IntegrationOptions(rtol=rtol,
                                                                        atol=1e-3 * rtol))
        assert tr.status == Status.OK and tr.events == 0
        err = float(np.sqrt(np.mean((tr.u_end - ref) ** 2)))
        assert err <= tr.error_estimate
        estimates.append(tr.error_estimate)
    assert estimates[1] < 1e-2 * estimates[0]


# ---------------------------------------------------------------- continuation call shape

@pytest.fixture(scope="module")
def orbit():
    model = impact_pair_model(0.015, 0.5, 0.55, 0.12, 1.0)
    p0 = 1.3
    warm = integrate(model, p0, np.array([1.05, 0.0]), 0.0, 300 * 2 * np.pi / p0)
    return PeriodicOrbitProblem(model, warm.u_end, p0, direction=-1)


def test_callback_returning_false_stops_and_keeps_the_points(orbit):
    options = ContinuationOptions(param_min=0.45, param_max=1.3, ds=0.02, ds_max=0.05)
    seen = []

    def stop_after_five(point):
        seen.append(point.param)
        return len(seen) < 5

    res = continuation(orbit, PseudoArclength(), options, callback=stop_after_five)
    assert res.status == Status.STOPPED_BY_CALLBACK and "callback" in res.message
    assert len(res.branches) == 1                       # no period-2 switch after a stop
    b = res.branches[0]
    assert [p.param for p in b.points] == seen and len(seen) == 5
    # the kept points are the ones an unstopped run passes through: a run limited to five
    # points (stopped by max_points, not by the callback) gives the same points
    ref = continuation(orbit, PseudoArclength(),
                       ContinuationOptions(param_min=0.45, param_max=1.3, ds=0.02, ds_max=0.05,
                                           max_points=5))
    assert ref.status == Status.MAX_POINTS
    assert np.array_equal([p.u0 for p in ref.branches[0].points], [p.u0 for p in b.points])
    assert res.counters["points"] == 5 and res.counters["flows"] > 5
    assert res.error_estimate["max_periodicity_residual"] < 1e-9


def test_continuation_options_invariants_on_construction():
    with pytest.raises(ConfigError, match="^ds: must satisfy ds_min <= ds <= ds_max"):
        ContinuationOptions(param_min=0.5, param_max=1.0, ds=0.5, ds_max=0.1)
    with pytest.raises(ConfigError, match="^param_max: must be greater than param_min"):
        ContinuationOptions(param_min=1.0, param_max=0.5)
    with pytest.raises(ConfigError, match="^max_points: value 1 out of range"):
        ContinuationOptions(param_min=0.5, param_max=1.0, max_points=1)
    with pytest.raises(ConfigError, match="^rtol"):
        IntegrationOptions(rtol=2.0)


# ---------------------------------------------------------------- options defined once

def test_sections_are_or_build_the_solver_options():
    s = load_scene("configs/impact_pair.toml")
    assert isinstance(s.integration, IntegrationOptions)
    o = s.continuation.options()
    assert isinstance(o, ContinuationOptions)
    assert (o.param_min, o.param_max, o.ds, o.max_points) == (
        s.continuation.omega_min, s.continuation.omega_max, s.continuation.ds,
        s.continuation.max_points)
    # the solver's rule, reported under the scene's path
    with pytest.raises(ConfigError, match=r"^continuation\.ds: must satisfy ds_min <= ds"):
        load_scene("configs/impact_pair.toml", ("continuation.ds=5.0",))
    with pytest.raises(ConfigError, match=r"^critical_damping\.ds: must satisfy"):
        load_scene("configs/impact_pair.toml", ("critical_damping.ds=5.0",))


# ---------------------------------------------------------------- one parameter name

def test_each_model_declares_its_parameter_and_keys():
    ip = load_scene("configs/impact_pair.toml")
    gp = load_scene("configs/gear_pair.toml")
    assert (ip.parameter.name, ip.parameter.unit) == ("Omega", "")
    assert (gp.parameter.name, gp.parameter.unit) == ("rpm", "rpm")
    data = read_toml("configs/gear_pair.toml")
    assert (gp.sweep.param_min, gp.sweep.param_max) == (data["sweep"]["rpm_min"],
                                                        data["sweep"]["rpm_max"])
    assert gp.time_response.param == data["time_response"]["rpm"]


@pytest.mark.parametrize("config, override, path", [
    ("gear_pair", "sweep.rpm_max=100.0", "sweep.rpm_max"),          # reversed range
    ("gear_pair", "continuation.rpm_min=-5.0", "continuation.rpm_min"),
    ("gear_pair", "time_response.rpm=0.0", "time_response.rpm"),
    ("gear_pair", "sweep.omega_min=1.0", "sweep.omega_min"),        # the other model's key
    ("impact_pair", "sweep.rpm_min=1.0", "sweep.rpm_min"),
    ("impact_pair", "continuation.omega_max=0.01", "continuation.omega_max"),
])
def test_errors_name_the_key_the_user_wrote(config, override, path):
    with pytest.raises(ConfigError) as info:
        load_scene(f"configs/{config}.toml", (override,))
    assert info.value.path == path


def test_gearbox_scene_rejects_omega_keys_in_the_message():
    data = read_toml("configs/gear_pair.toml")
    data["continuation"]["omega_max"] = data["continuation"].pop("rpm_max")
    with pytest.raises(ConfigError, match=r"continuation\.omega_max: unknown key.*rpm_max"):
        scene_from_dict(data)


@pytest.mark.parametrize("path", CONFIGS, ids=[p.stem for p in CONFIGS])
def test_every_config_passes_check(path, capsys):
    assert main(["check", str(path)]) == 0, capsys.readouterr().err


# ---------------------------------------------------------------- one result convention

def _check_outcome(res, counters: set):
    """``res.outcome``: a Status, a message, integer counters (at least ``counters``, all
    >= 0), a wall time >= 0 and an error estimate of floats or None."""
    from vibrogear.status import Outcome

    out = res.outcome
    assert isinstance(out, Outcome) and isinstance(out.status, Status)
    assert isinstance(out.message, str) and out.message
    assert counters <= set(out.counters) and all(
        type(v) is int and v >= 0 for v in out.counters.values())
    assert out.wall_s >= 0.0 and out.error_estimate
    assert all(v is None or isinstance(v, float) for v in out.error_estimate.values())
    return out


def test_every_solver_result_shows_one_outcome(orbit):
    """Integration, static equilibrium, shooting, Lyapunov, run-up, sweep, continuation,
    rotor modes and Campbell: the same five fields; the status is the result's own, the
    counters are the result's own numbers."""
    from rotor_fixtures import friswell_two_disc
    from vibrogear.config.options import SweepOptions
    from vibrogear.solvers.periodic.shooting import shoot
    from vibrogear.solvers.rotor.campbell import campbell_diagram
    from vibrogear.solvers.rotor.modes import rotor_modes
    from vibrogear.solvers.sequential.lyapunov import largest_lyapunov
    from vibrogear.solvers.sequential.ramp import SpeedProfile, ramp
    from vibrogear.solvers.sequential.sweep import sweep
    from vibrogear.solvers.static import static_equilibrium

    model, p0, u0 = orbit.model, orbit.param, orbit.u0
    tr = integrate(model, p0, u0, 0.0, 2 * np.pi / p0)
    out = _check_outcome(tr, {"steps", "rhs_calls", "events"})
    assert out.counters["steps"] == tr.steps and out.status == tr.status == Status.OK
    assert out.error_estimate["accumulated_local_error"] == tr.error_estimate
    st = static_equilibrium(model, p0)
    assert _check_outcome(st, {"iterations"}).ok
    sh = shoot(model, p0, u0)
    out = _check_outcome(sh, {"iterations", "flows", "rhs_calls"})
    assert out.ok and out.error_estimate["periodicity_residual"] == sh.residual
    ly = largest_lyapunov(model, p0, sh.u0, 16, chunk=4)
    out = _check_outcome(ly, {"rhs_calls", "periods"})
    assert out.counters["periods"] == 16
    assert out.error_estimate["exponent_ci_half_width"] == pytest.approx(
        (ly.ci[1] - ly.ci[0]) / 2)
    rp = ramp(model, SpeedProfile(np.array([0.0, 60.0]), np.array([p0, 1.2])), sh.u0,
              chunks_per_period=1, samples_per_period=8)
    assert _check_outcome(rp, {"chunks", "steps"}).counters["chunks"] == rp.chunks
    sw = sweep(model, np.array([1.3, 1.25]), SweepOptions(directions=("up",), workers=1,
                                                           transient_periods=20,
                                                           record_periods=8), u0=sh.u0)
    out = _check_outcome(sw, {"points", "failed_points", "steps"})
    assert out.counters["points"] == 2 and out.status == sw.status_code
    co = continuation(orbit, PseudoArclength(), ContinuationOptions(
        param_min=0.45, param_max=1.3, ds=0.02, ds_max=0.05, max_points=4))
    out = _check_outcome(co, {"points", "flows"})
    assert out.status == Status.MAX_POINTS and not out.ok
    rotor = friswell_two_disc()
    rm = rotor_modes(rotor, 1000.0, count=4)
    assert _check_outcome(rm, {"modes"}).status == Status.OK
    cb = campbell_diagram(rotor, np.array([0.0, 2000.0]), n_modes=4)
    assert _check_outcome(cb, {"speeds"}).counters["speeds"] == 2
