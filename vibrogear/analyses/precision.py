"""The ``report`` analysis of impact-pair scenes: work-precision against the exact solution.

Two studies at one excitation parameter Omega, both measured against the independent
closed-form reference :mod:`vibrogear.verification.impact_exact` (which does not use the
solvers):

* integrator: for each rtol (atol = rtol * 1e-2) integrate from the static state over a
  number of excitation periods; error = max over a grid of dense-output times of
  |q - q_exact|; steps, rhs calls, switching events and the best wall time of a few
  repeats.  The observed slopes of log(error) against log(rtol) (tolerance
  proportionality: ~1) and against log(steps) (minus the order: ~ -5 for DOPRI5) are fitted.
* shooting: from a perturbed guess, shooting with tolerance tol and integrator rtol = tol;
  residual, error of u0 against the exact periodic orbit, error of the Floquet multipliers,
  Newton iterations and wall time.

The files (``work_precision.csv``, ``shooting_precision.csv``, ``work_precision.png/.svg``,
``shooting_precision.png/.svg``) are written by :mod:`vibrogear.report.writers.precision`;
the numbers are returned for ``summary.json``.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..models.impact_pair import impact_pair_from_config
from ..pipeline.outcome import AnalysisOutcome, NumericalFailure, RunContext
from ..solvers.integrator.integrate import IntegrationOptions, integrate
from ..solvers.periodic.shooting import shoot
from ..solvers.static import static_equilibrium
from ..verification.impact_exact import ImpactParams, exact_dense, exact_flow
from ..verification.impact_orbits import periodic_orbit
from ..config.options import ShootingOptions
from ..status import Outcome
from .study import ATOL_PER_RTOL_BY_MODEL

__all__ = ["run_report", "work_precision", "shooting_precision", "fit_slope",
           "ATOL_PER_RTOL", "SAMPLES_PER_PERIOD", "PrecisionResult"]

#: atol = rtol * ATOL_PER_RTOL in both studies: the impact pair's, of the one rule
ATOL_PER_RTOL = ATOL_PER_RTOL_BY_MODEL["impact_pair"]
#: dense-output samples per excitation period on which the error is measured
SAMPLES_PER_PERIOD = 64
#: periods integrated from the static state before the periodic orbit is sought
TRANSIENT_PERIODS = 300
#: relative perturbation of the shooting guess away from the exact orbit
GUESS_PERTURBATION = 0.05

WP_COLUMNS = ("rtol", "atol", "error", "error_end", "steps", "rejected", "rhs_calls", "events",
              "wall_s")
SH_COLUMNS = ("tol", "rtol", "residual", "u0_error", "floquet_error", "iterations",
              "converged", "rhs_calls", "wall_s")


@dataclass(frozen=True, eq=False)
class PrecisionResult:
    """The work-precision (``wp``, columns ``WP_COLUMNS``) and shooting-precision (``sh``,
    columns ``SH_COLUMNS``) tables, the fitted ``slopes`` and the figure titles."""
    wp: dict
    sh: dict
    slopes: dict
    wp_title: str
    sh_title: str


def fit_slope(x, y) -> float:
    """Least-squares slope of log(y) against log(x) over the points with x, y > 0."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = (x > 0) & (y > 0) & np.isfinite(x) & np.isfinite(y)
    if np.count_nonzero(ok) < 2 or np.ptp(np.log(x[ok])) == 0:
        return float("nan")
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


def _options(rtol: float) -> IntegrationOptions:
    return IntegrationOptions(rtol=rtol, atol=rtol * ATOL_PER_RTOL)


def _warm_jit(model, omega: float, u0) -> list:
    """Compile (or load) both integrator variants so that no timing includes the JIT;
    returns the two integrations' outcomes."""
    T = model.excitation_period(omega)
    return [integrate(model, omega, u0, 0.0, T, t_eval=np.linspace(0.0, T, 5),
                      options=_options(1e-6)).outcome,
            integrate(model, omega, u0, 0.0, T, options=_options(1e-6),
                      variational=True).outcome]


def work_precision(model, params: ImpactParams, omega: float, u0, t1: float, rtols, *,
                   t_eval, repeats: int = 3, solves: list | None = None) -> dict[str, np.ndarray]:
    """Integrator error against the exact flow for each rtol: a table of columns.
    ``solves``: a list that gets every integration's :class:`~vibrogear.status.Outcome`
    (the repeats included)."""
    u0 = np.asarray(u0, float)
    flow = exact_flow(params, omega, u0, 0.0, t1)
    exact = exact_dense(params, omega, u0, 0.0, t_eval, flow=flow)
    rows = []
    for rtol in rtols:
        opts = _options(rtol)
        best = np.inf
        tr = None
        for _ in range(repeats):
            tr = integrate(model, omega, u0, 0.0, t1, t_eval=t_eval, options=opts)
            if solves is not None:
                solves.append(tr.outcome)
            if not tr.ok:
                raise NumericalFailure(f"report: integration at rtol = {rtol:g}, "
                                       f"Omega = {omega:g} failed: {tr.message}")
            best = min(best, tr.wall_time)
        rows.append((rtol, opts.atol, float(np.max(np.abs(tr.u[:, 0] - exact[:, 0]))),
                     float(np.max(np.abs(tr.u_end - flow.u_end))), tr.steps, tr.rejected,
                     tr.rhs_calls, tr.events, best))
    table = {c: np.array([r[i] for r in rows]) for i, c in enumerate(WP_COLUMNS)}
    table["exact_switches"] = flow.n_switches
    return table


def _multiplier_error(mu, mu_ref) -> float:
    """max |mu - mu_ref| under the best matching of the two sets."""
    mu, mu_ref = np.asarray(mu), np.asarray(mu_ref)
    if not np.all(np.isfinite(mu)):
        return float("nan")
    if mu.size <= 4:
        return float(min(np.max(np.abs(mu[list(p)] - mu_ref))
                         for p in itertools.permutations(range(mu.size))))
    a, b = mu[np.lexsort((mu.imag, mu.real))], mu_ref[np.lexsort((mu_ref.imag, mu_ref.real))]
    return float(np.max(np.abs(a - b)))


def shooting_precision(model, omega: float, guess, orbit, tols, *, repeats: int = 3,
                       max_iter: int = 25, solves: list | None = None) -> dict[str, np.ndarray]:
    """Shooting from ``guess`` at each tol (integrator rtol = tol) against the exact
    ``orbit``.  ``solves``: a list that gets every shooting's
    :class:`~vibrogear.status.Outcome` (the repeats included)."""
    rows = []
    for tol in tols:
        best = np.inf
        sh = None
        for _ in range(repeats):
            sh = shoot(model, omega, guess, options=_options(tol), shooting=ShootingOptions(tol=tol, max_iter=max_iter))
            if solves is not None:
                solves.append(sh.outcome)
            best = min(best, sh.wall_time)
        rows.append((tol, tol, sh.residual, float(np.max(np.abs(sh.u0 - orbit.u0))),
                     _multiplier_error(sh.floquet, orbit.floquet), sh.iterations,
                     bool(sh.converged), sh.rhs_calls, best))
    return {c: np.array([r[i] for r in rows]) for i, c in enumerate(SH_COLUMNS)}


def _table_json(table: dict, columns) -> dict:
    return {c: [v.item() for v in np.asarray(table[c])] for c in columns}


def run_report(scene, ctx: RunContext) -> AnalysisOutcome:
    cfg = scene.report
    c = scene.impact_pair
    model = impact_pair_from_config(c)
    params = ImpactParams(c.zeta, c.kappa, c.f_m, c.f_p, c.b_r, c.contact_damping)
    omega = cfg.omega
    T = model.excitation_period(omega)
    st = static_equilibrium(model)
    u_start = st.u0 if st.converged else np.zeros(model.n_states)
    # every solve this analysis runs, for the runner's solver entries (the exact references
    # of vibrogear.verification are closed forms, not solves)
    solves = [st.outcome, *_warm_jit(model, omega, u_start)]

    # ---- integrator tolerance -> error -> work
    t1 = cfg.periods * T
    n = max(int(round(cfg.periods * SAMPLES_PER_PERIOD)), 2)
    t_eval = np.linspace(0.0, t1, n + 1)
    rtols = sorted(cfg.rtols, reverse=True)
    wp = work_precision(model, params, omega, u_start, t1, rtols, t_eval=t_eval,
                        repeats=cfg.repeats, solves=solves)
    slopes = {
        "error_vs_rtol": fit_slope(wp["rtol"], wp["error"]),
        "error_vs_steps": fit_slope(wp["steps"], wp["error"]),
        "error_vs_rhs_calls": fit_slope(wp["rhs_calls"], wp["error"]),
        "error_vs_wall": fit_slope(wp["wall_s"], wp["error"]),
    }
    slopes["order"] = -slopes["error_vs_steps"]

    # ---- shooting residual -> error -> work
    warm = integrate(model, omega, u_start, 0.0, TRANSIENT_PERIODS * T, options=_options(1e-10))
    solves.append(warm.outcome)
    if not warm.ok:
        raise NumericalFailure(f"report: transient at Omega = {omega:g} failed: {warm.message}")
    orbit = periodic_orbit(params, omega, warm.u_end)
    if not orbit.converged:
        raise NumericalFailure(f"report: no exact period-1 orbit at Omega = {omega:g} "
                               f"(residual {orbit.residual:.3g})")
    scale = 1.0 + np.abs(orbit.u0)
    sign = np.where(np.arange(model.n_states) % 2 == 0, 1.0, -1.0)
    guess = orbit.u0 + GUESS_PERTURBATION * scale * sign
    tols = sorted(cfg.shooting_tols, reverse=True)
    sh = shooting_precision(model, omega, guess, orbit, tols, repeats=cfg.repeats,
                            solves=solves)

    title = (f"{scene.scene.name}: zeta={c.zeta:g}, kappa={c.kappa:g}, f_m={c.f_m:g}, "
             f"f_p={c.f_p:g}, b_r={c.b_r:g}, Omega={omega:g}")
    result = PrecisionResult(wp=wp, sh=sh, slopes=dict(slopes),
                             wp_title=title + f", {cfg.periods:g} periods", sh_title=title)

    err = wp["error"]
    summary = {
        "omega": omega, "periods": cfg.periods, "samples": int(t_eval.size),
        "repeats": cfg.repeats, "atol_per_rtol": ATOL_PER_RTOL,
        "start_state": u_start.tolist(),
        "exact_switches": int(wp["exact_switches"]),
        "work_precision": _table_json(wp, WP_COLUMNS),
        "slopes": slopes,
        "errors_decrease": bool(np.all(np.diff(err) < 0)),
        "exact_orbit": {"u0": orbit.u0.tolist(), "q_max": orbit.q_max, "q_min": orbit.q_min,
                        "floquet_abs": np.abs(orbit.floquet).tolist(),
                        "residual": orbit.residual, "shooting_guess": guess.tolist()},
        "shooting": _table_json(sh, SH_COLUMNS),
        "error_estimate": {"integrator_error_at_min_rtol": float(err[-1]),
                           "min_rtol": float(wp["rtol"][-1]),
                           "shooting_u0_error_at_min_tol": float(sh["u0_error"][-1]),
                           "reference": "closed-form exact flow (vibrogear.verification)"},
    }
    return AnalysisOutcome(summary=summary, result=result, solver=Outcome.combine(solves))
