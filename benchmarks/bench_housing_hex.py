"""Hexahedra against tetrahedra for the housing (issue 34): 100 master modes of configs/housing.toml,
empty vibrogear cache per run, whole-CLI wall (``vibrogear modes``), 1 rank and ``mpirun -n 2``.

Runs, back to back in one invocation (so that their ratios share one machine load):

- the P3 tetrahedra of the shipped scene (the baseline), ``tol`` 1e-5;
- Q3 hexahedra at the hex defaults (``element = "hex"``), ``tol`` 1e-5, and at one rank also
  ``tol`` 1e-8 (the tolerance check: the largest relative change of a frequency between the two);
- each at 1 and 2 ranks (``--ranks``).

Every run's frequencies are compared per mode with the P3 reference of docs/housing.md
(``results/bench_housing_p_refinement.json``, "reference_hz"), and its split (meshing, assembly,
factorisation, iterations, bore/surface values), CPU seconds of the process tree and the load
average before and after are recorded in ``benchmarks/results/bench_housing_hex.json``.

Usage: ``python benchmarks/bench_housing_hex.py [--ranks 1 2] [--only hex|tet] [--out FILE]``
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_housing_p_refinement import ROOT, run_modes  # noqa: E402

OUT = ROOT / "benchmarks" / "results" / "bench_housing_hex.json"
REF = ROOT / "benchmarks" / "results" / "bench_housing_p_refinement.json"
HEX = ('housing.mesh.element="hex"',)
#: (label, size, degree, bore_size, extra overrides, rank counts): the shipped P3 scene and the
#: hex defaults (the tolerance check, tol 1e-8 against 1e-5, at one rank only)
CASES = {
    "tet": [("P3 tet 0.024 / 0.012", 0.024, 3, 0.012, ('housing.mesh.element="tet"', "housing.modes.tol=1e-05"),
             (1, 2))],
    "hex": [("Q3 hex, tol 1e-8", 0.072, 3, 0.030, HEX + ("housing.modes.tol=1e-08",), (1,)),
            ("Q3 hex, tol 1e-5", 0.072, 3, 0.030, HEX + ("housing.modes.tol=1e-05",), (1, 2))],
}


def _split(t: dict) -> dict:
    """The time split asked for by the issue, s."""
    return {"meshing": t.get("meshing", 0.0), "mesh_read": t.get("mesh_read", 0.0),
            "form_compilation": t.get("form_compilation", 0.0), "assembly": t.get("assembly", 0.0),
            "factorization": t.get("eigensolve_factorization", 0.0),
            "iterations": t.get("eigensolve_iterations", 0.0),
            "bore_and_surface_values": t.get("postprocess", 0.0)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--only", choices=["hex", "tet"], default=None)
    ap.add_argument("--out", type=Path, default=OUT, help="results JSON (default %(default)s)")
    a = ap.parse_args()
    ref_rec = json.loads(REF.read_text())["reference"]
    ref = np.array(ref_rec["reference_hz"])
    unc = np.array(ref_rec["uncertainty_rel"])
    rows = []
    tmp = Path(tempfile.mkdtemp(prefix="vg-hex-"))
    try:
        for n in a.ranks:
            for kind in ("tet", "hex"):
                if a.only and kind != a.only:
                    continue
                for label, size, deg, bore, sets, ranks in CASES[kind]:
                    if n not in ranks:
                        continue
                    r = run_modes(size, deg, bore_size=bore, count=100, n=n, tmp=tmp, sets=sets)
                    r["label"] = label
                    if "failed" not in r:
                        f = np.array(r["frequencies_hz"][:100])
                        err = f / ref - 1.0
                        r.update(split_s=_split(r["timings_s"]), max_abs_err=float(np.abs(err).max()),
                                 max_err_mode=int(np.abs(err).argmax()) + 1, err_f1=float(err[0]),
                                 err_f100=float(err[-1]), max_abs_err_plus_uncertainty=float(
                                     np.max(np.abs(err) + unc)))
                    print(f"{label}, {n} rank(s): {r.get('n_dofs')} DOF, wall {r['wall_s']:.1f} s, cpu "
                          f"{r['cpu_s']:.1f} s, load {r['load_average'][0]:.1f}, worst "
                          f"{100 * r.get('max_abs_err', np.nan):.2f} % (mode {r.get('max_err_mode')}), "
                          f"split {r.get('split_s')}", flush=True)
                    rows.append(r)
                    a.out.write_text(json.dumps({"scene": "configs/housing.toml", "runs": rows}, indent=1))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    rec = {"scene": "configs/housing.toml", "runs": rows, "ratios": _ratios(rows)}
    a.out.write_text(json.dumps(rec, indent=1))
    print(json.dumps(rec["ratios"], indent=1))


def _ratios(rows: list[dict]) -> dict:
    """Per rank count: hex (tol 1e-5) wall and CPU over the P3 baseline's, and the tolerance check."""
    out = {}
    ok = [r for r in rows if "failed" not in r]
    for n in sorted({r["n_processes"] for r in ok}):
        by = {r["label"]: r for r in ok if r["n_processes"] == n}
        base, hx, h8 = by.get(CASES["tet"][0][0]), by.get(CASES["hex"][1][0]), by.get(CASES["hex"][0][0])
        d = {}
        if base and hx:
            d.update(wall_ratio_hex_over_p3=hx["wall_s"] / base["wall_s"], cpu_ratio_hex_over_p3=hx["cpu_s"] / base["cpu_s"])
        if hx and h8:
            f5, f8 = np.array(hx["frequencies_hz"][:100]), np.array(h8["frequencies_hz"][:100])
            d["tol_1e5_vs_1e8_max_rel_change"] = float(np.max(np.abs(f5 / f8 - 1.0)))
        out[f"{n}_ranks"] = d
    return out


if __name__ == "__main__":
    main()
