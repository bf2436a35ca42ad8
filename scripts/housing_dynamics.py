"""Housing-geometry sweep that changes the gearbox dynamics: wall thickness -> resonance
speeds and bifurcation diagram of the G1 mesh deformation (``make housing-dynamics``).

For each wall thickness the scene runs ``modes`` and an up ``sweep`` (through the normal
CLI, so each housing is meshed, solved and cached once and every sweep is resumable), then
one figure compares them: the resonance speeds (natural frequencies with a large mesh
strain-energy share crossing 1x / 2x the mesh frequency) against the wall thickness, and the
bifurcation diagrams (min / max of the mesh deformation per speed) overlaid.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="configs/two_stage.toml")
    ap.add_argument("--walls", default="0.010,0.012,0.015", help="wall thicknesses [m]")
    ap.add_argument("--points", type=int, default=61, help="speeds per sweep")
    ap.add_argument("--out", default="out/housing_dynamics")
    ap.add_argument("--set", action="append", default=[], help="extra overrides")
    args = ap.parse_args(argv)
    out = Path(args.out)
    walls = [float(w) for w in args.walls.split(",")]
    runs = {}
    for w in walls:
        d = out / f"wall_{w * 1000:g}mm"
        cmd = [sys.executable, "-m", "vibrogear.cli", "run", args.scene, "--out", str(d), "--quiet",
               "--set", f"housing.wall_thickness={w}",
               "--set", f"housing.mesh.size={1.8 * w}",
               "--set", 'scene.analyses=["modes","sweep"]',
               "--set", 'sweep.directions=["up"]', "--set", f"sweep.n_points={args.points}",
               "--set", "sweep.segments=2", "--set", "integration.rtol=1e-5",
               "--set", "integration.atol=1e-11"]
        for s in args.set:
            cmd += ["--set", s]
        rc = subprocess.call(cmd)
        if rc != 0:
            print(f"wall {w}: vibrogear exited with {rc}", file=sys.stderr)
            continue
        summary = json.loads((d / "summary.json").read_text())
        runs[w] = {"summary": summary, "sweep": dict(np.load(d / "sweep.npz"))}
    if not runs:
        return 1
    _plot(out, runs)
    table = {f"{w:g}": {"resonance_speeds_rpm": r["summary"]["results"]["modes"]["resonance_speeds_rpm"],
                        "first_frequencies_hz": r["summary"]["results"]["modes"]["first_frequencies_hz"],
                        "mesh_interruption_points": r["summary"]["results"]["sweep"]["points_with_contact_loss"]}
             for w, r in runs.items()}
    (out / "housing_dynamics.json").write_text(json.dumps(table, indent=1))
    print(f"wrote {out}/housing_dynamics.png, .svg, .json")
    return 0


def _plot(out: Path, runs: dict) -> None:
    from vibrogear.report.figure import new_figure, save_figure

    fig = new_figure((11.0, 4.8))
    a1, a2 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 2]})
    for w, r in runs.items():
        for c in r["summary"]["results"]["modes"]["resonance_speeds_rpm"]:
            a1.plot(w * 1000, c["rpm"], "o" if c["mesh_order"] == 1 else "s",
                    color="C0" if c["mesh_order"] == 1 else "C1",
                    ms=3 + 12 * min(1.0, c["mesh_energy_share"]))
        s = r["sweep"]
        a2.plot(s["param"], s["qmax"] * 1e6, "-", lw=0.9, label=f"wall {w * 1000:g} mm")
        a2.plot(s["param"], s["qmin"] * 1e6, "--", lw=0.9, color=a2.lines[-1].get_color())
    a1.set_xlabel("wall thickness [mm]")
    a1.set_ylabel("resonance speed [rpm]")
    a1.set_title("o: 1x mesh, s: 2x mesh (size = mesh energy)", fontsize=8)
    a2.axhline(0.0, color="k", lw=0.7)
    a2.set_xlabel("driving speed [rpm]")
    a2.set_ylabel("G1 mesh deformation max (-) / min (--) [um]")
    a2.legend(fontsize=8)
    fig.suptitle("housing wall thickness -> gearbox dynamics", fontsize=9)
    save_figure(fig, out / "housing_dynamics")


if __name__ == "__main__":
    raise SystemExit(main())
