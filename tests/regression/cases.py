"""The regression tier's runs: golden numbers of reviewed runs, regenerated only on purpose.

Each case runs one scene through the command line with fixed, CI-sized settings and returns
the numbers it pins (a flat dict of floats, ints and lists).  ``test_golden.py`` compares a
fresh run with ``golden/<case>.json`` within the tolerances below; ``regenerate.py`` (``make
golden``) rewrites the files, whose diff is then reviewed like code.

These are not verification: they hold behaviour still (a refactoring must not move a fold by
a tenth of an rpm), they do not prove it right.  The verification tier (tests/verification)
compares with independent references.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from vibrogear.cli import main

ROOT = Path(__file__).resolve().parents[2]
GOLDEN = Path(__file__).resolve().parent / "golden"
CONFIGS = ROOT / "configs"

__all__ = ["CASES", "TOLERANCES", "GOLDEN", "run_case", "compare"]


def _run(verb: str, scene: str, out: Path, *overrides: str) -> dict:
    args = [verb, str(CONFIGS / scene), "--quiet", "--out", str(out)]
    for o in overrides:
        args += ["--set", o]
    code = main(args)
    if code != 0:
        raise RuntimeError(f"vibrogear {' '.join(args)} exited {code}")
    return json.loads((out / "summary.json").read_text())["results"]


def _branch_numbers(out: Path, param: str) -> dict:
    """Special points by label (sorted parameter values) and points per branch."""
    with np.load(out / "branch.npz") as z:
        label, p, br = z["label"].astype(str), z["param"], z["branch"]
        counts = [int(np.sum(br == b)) for b in np.unique(br)]
    vals: dict = {"points_per_branch": counts}
    for lab in ("LP", "PD"):
        vals[f"{lab}_{param}"] = sorted(float(x) for x in p[label == lab])
    return vals


def gear_pair_modes(out: Path) -> dict:
    """gear_pair, linearised at 5800 rpm: the twelve lowest natural frequencies."""
    res = _run("modes", "gear_pair.toml", out)["modes"]
    return {"first_frequencies_hz": res["first_frequencies_hz"][:12]}


def gear_pair_fold(out: Path) -> dict:
    """gear_pair continuation over 4900-5400 rpm: the jump region's two folds, the PD pair
    and the period-2 branch between them."""
    _run("continue", "gear_pair.toml", out, "continuation.rpm_min=4900",
         "continuation.rpm_max=5400")
    return _branch_numbers(out, "rpm")


def gear_pair_sweep(out: Path) -> dict:
    """gear_pair sweep, 6 speeds from 5000 to 6250 rpm up and down: the motion class of
    every point and the mesh-deformation extrema of the periodic ones (the extrema of
    non-periodic points do not converge and are not pinned)."""
    _run("sweep", "gear_pair.toml", out, "sweep.n_points=6", "sweep.rpm_min=5000",
         "sweep.rpm_max=6250")
    with np.load(out / "sweep.npz") as z:
        order = np.lexsort((z["param"], z["direction"].astype(str)))
        n = z["period_n"][order]
        per = n > 0
        return {"rpm": [float(x) for x in z["param"][order]],
                "period_n": [int(x) for x in n],
                "qmin_periodic_m": [float(x) for x in z["qmin"][order][per]],
                "qmax_periodic_m": [float(x) for x in z["qmax"][order][per]]}


def impact_pair_branch(out: Path) -> dict:
    """The impact pair (zeta = 0.015) continued over Omega = 0.1-3: primary and
    superharmonic folds, the PD pair, the period-2 branch."""
    _run("continue", "impact_pair.toml", out)
    return _branch_numbers(out, "Omega")


def single_stage_modes(out: Path) -> dict:
    """single_stage with a small housing (8 + 8 shaft modes, 10 housing modes): the twelve
    lowest natural frequencies of the coupled reduced model."""
    res = _run("modes", "single_stage.toml", out, "gearbox.shafts.0.master_count=8",
               "gearbox.shafts.1.master_count=8", "housing.modes.count=10")["modes"]
    return {"first_frequencies_hz": res["first_frequencies_hz"][:12]}


CASES = {f.__name__: f for f in (gear_pair_modes, gear_pair_fold, gear_pair_sweep,
                                 impact_pair_branch, single_stage_modes)}

#: relative tolerance per key (default 1e-6); counts: absolute
TOLERANCES = {
    "first_frequencies_hz": 1e-6,
    "LP_rpm": 1e-5, "PD_rpm": 1e-5, "LP_Omega": 1e-5, "PD_Omega": 1e-5,
    "points_per_branch": 0,
    "rpm": 0.0, "period_n": 0,
    "qmin_periodic_m": 1e-3, "qmax_periodic_m": 1e-3,   # periodicity is decided to 1e-4
}


def run_case(name: str, out: Path) -> dict:
    return CASES[name](Path(out))


def compare(name: str, got: dict, golden: dict) -> list[str]:
    """Differences between a fresh run and the golden values (empty: equal within
    tolerance)."""
    problems = []
    for key, ref in golden.items():
        if key not in got:
            problems.append(f"{name}.{key}: missing from the fresh run")
            continue
        a, b = np.atleast_1d(np.asarray(got[key], float)), np.atleast_1d(np.asarray(ref, float))
        if a.shape != b.shape:
            problems.append(f"{name}.{key}: {a.size} values, golden {b.size}: {got[key]} vs {ref}")
            continue
        tol = TOLERANCES.get(key, 1e-6)
        bad = np.abs(a - b) > tol * np.maximum(np.abs(b), 1e-300) if tol else a != b
        if np.any(bad):
            problems.append(f"{name}.{key}: {a[bad].tolist()} vs golden {b[bad].tolist()} "
                            f"(tolerance {tol:g})")
    return problems
