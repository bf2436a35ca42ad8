"""Calibration of the accuracy -> tolerance rule (:func:`vibrogear.analyses.study.tolerances_for`).

For regular (settled, non-chaotic) points of gear_pair and single_stage: the error of the monitored
mesh deformation delta(t) over a record window, max |delta - delta_ref| / (max delta_ref -
min delta_ref), at rtol = 1e-3 ... 1e-8 (atol = ATOL_PER_RTOL * rtol) against an rtol = 1e-10
run from the same static state over the same transient + record periods.  A point counts as
regular when its error converges with the tolerance (below 1e-5 at rtol = 1e-8); the
stroboscopic spread of the reference's last 8 periods is reported.  two_stage's points are
run and reported but are chaotic (the free gear G2 rattles over the whole speed range: the
error stays 0.3-0.7 at every rtol), so no tolerance rule applies to them; single_stage
(the housing scene) stands in as the second model.  Fits log10(err) = a + p log10(rtol) over all points (least squares) and
prints the fit, the worst ratio err / (10^a rtol^p) and the rtol the rule picks; writes
benchmarks/results/calibrate_tolerance.json and the work-precision view of the rule,
calibrate_tolerance.png (vibrogear.report.plots.precision.plot_accuracy_rule).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path[:0] = [str(ROOT), str(HERE)]

CASES = {"gear_pair": [4600.0, 5200.0, 5800.0, 6400.0, 7000.0],
         "single_stage": [2500.0, 3500.0, 4500.0, 5500.0],
         "two_stage": [2000.0, 2400.0]}
RTOLS = [1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 1e-6, 1e-7, 1e-8]


def point_errors(model, rpm, u0, transient, record, rtols, atol_per_rtol, spp=32):
    """(errors per rtol, steps per mesh period per rtol, stroboscopic spread of the last 8
    reference periods / range, range of delta_ref)."""
    from vibrogear.solvers.integrator.contact_eval import contact_history
    from vibrogear.solvers.integrator.integrate import IntegrationOptions, integrate

    T = model.excitation_period(rpm)
    n1 = transient + record
    t_eval = np.linspace(transient * T, n1 * T, spp * record + 1)

    def run(rtol):
        o = IntegrationOptions(rtol=rtol, atol=atol_per_rtol * rtol, max_steps=50_000_000)
        tr = integrate(model, rpm, u0, 0.0, n1 * T, t_eval=t_eval, options=o)
        d = contact_history(model, rpm, tr.t, tr.u)[0][model.monitor]
        return d, tr.steps / n1, tr.ok

    ref, _, ok = run(1e-10)
    span = float(ref.max() - ref.min())
    strobe = ref[::spp]
    spread = float(np.ptp(strobe[-8:]) / span)
    errs, steps = [], []
    for rtol in rtols:
        d, s, ok = run(rtol)
        errs.append(float(np.max(np.abs(d - ref)) / span) if ok else float("nan"))
        steps.append(s)
    return errs, steps, spread, span


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--transient", type=int, default=100)
    ap.add_argument("--record", type=int, default=20)
    ap.add_argument("--cases", nargs="*", default=list(CASES))
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/calibrate_tolerance.json"))
    a = ap.parse_args(argv)
    from vibrogear.analyses.study import ACCURACY_RULE, ATOL_PER_RTOL, tolerances_for
    from vibrogear.config import load_scene
    from vibrogear.models.gearbox.model import build_gearbox
    from vibrogear.solvers.static import static_equilibrium

    rows = []
    for case in a.cases:
        gm = build_gearbox(load_scene(ROOT / "configs" / f"{case}.toml"))
        for rpm in CASES[case]:
            t = time.perf_counter()
            u0 = static_equilibrium(gm.reduced, rpm).u0
            errs, steps, spread, span = point_errors(gm.reduced, rpm, u0, a.transient,
                                                       a.record, RTOLS, ATOL_PER_RTOL)
            regular = bool(np.isfinite(errs[-1]) and errs[-1] < 1e-5)
            rows.append({"case": case, "rpm": rpm, "regular": regular, "strobe_spread": spread,
                         "range_m": span,
                         "errors": errs, "steps_per_period": steps})
            print(f"{case} {rpm:.0f} rpm regular={regular} spread={spread:.1e} ({time.perf_counter() - t:.1f} s): "
                  + " ".join(f"{r:.0e}:{e:.1e}" for r, e in zip(RTOLS, errs)), flush=True)
    use = [r for r in rows if r["regular"]]
    x = np.array([np.log10(rt) for r in use for rt in RTOLS])
    y = np.array([np.log10(max(e, 1e-16)) for r in use for e in r["errors"]])
    good = np.isfinite(y)
    p, c = np.polyfit(x[good], y[good], 1)
    ratio = 10 ** (y[good] - (c + p * x[good]))
    fit = {"exponent": float(p), "log10_coefficient": float(c), "worst_ratio": float(ratio.max()),
           "points_used": len(use)}
    print(f"fit over {len(use)} regular points: err = {10 ** c:.3g} rtol^{p:.3f}; worst "
          f"measured / fitted = {ratio.max():.2f}; rule in code: {ACCURACY_RULE}")
    for acc in (1e-2, 1e-3, 1e-4, 1e-5):
        print(f"  accuracy {acc:g} -> rtol, atol = {tolerances_for(acc)}")
    from vibrogear.report.figure import save_figure
    from vibrogear.report.plots.precision import plot_accuracy_rule

    pts = [{"label": f"{r['case']} {r['rpm']:.0f} rpm", "rtols": RTOLS, "errors": r["errors"],
            "steps_per_period": r["steps_per_period"]} for r in use]
    fig = plot_accuracy_rule(pts, ACCURACY_RULE, 1e-3, tolerances_for(1e-3)[0],
                             title="gearbox work-precision: the accuracy -> rtol rule at "
                                   "accuracy 1e-3")
    save_figure(fig, Path(a.out).with_suffix(""), formats=("png",))
    out = {"rtols": RTOLS, "atol_per_rtol": ATOL_PER_RTOL, "transient_periods": a.transient,
           "record_periods": a.record, "points": rows, "fit": fit}
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
