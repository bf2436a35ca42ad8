"""Switch-off study of ``configs/two_stage.toml`` (docs/gearbox.md, "What drives the two-stage
dynamics"): the motion class at 5 speeds with one ingredient changed at a time.

    baseline                 the scene as shipped
    bearings linear          every ball bearing a linear isotropic spring, 2e8 N/m, no clearance
    drag x10 / x100          free-gear drag torque 1 -> 10 / 100 N m
    modulation off           G1 stiffness_cos = [] (TE only, as the seed)
    rigid housing            no [housing]: the bearings' rolling elements push on rigid ground
                             (shafts at the bores' x, z; 9 / 10 elements as the bores)
    all linear               linear bearings + drag x100 + modulation off (a check: no
                             contact changes are left, so the settled motion is period-1)
    all linear, rtol 1e-6    the same at rtol 1e-6 and 300 + 300 transient periods

Each case is one upward sweep of the scene's own [sweep] settings (transient 150 + 100
periods, record 32, the accuracy rule's rtol) at 1500, 1875, 2250, 2625, 3000 rpm, one
worker; ~20-60 s per case on a quiet core.  Results: a Markdown table on stdout and
``benchmarks/results/switch_off_two_stage.json``.

    python benchmarks/switch_off_two_stage.py [--cases baseline,drag_x10,...]
"""
from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from identify_two_stage_seed import run_sweep  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "configs" / "two_stage.toml"
RESULTS = ROOT / "benchmarks" / "results" / "switch_off_two_stage.json"
SPEEDS = np.linspace(1500.0, 3000.0, 5)

_LINEAR = [s for i in range(4) for s in (f"gearbox.bearings[{i}].type=spring",
                                         f"gearbox.bearings[{i}].stiffness=2e8",
                                         f"gearbox.bearings[{i}].clearance=0.0",
                                         f"gearbox.bearings[{i}].axial_stiffness=5e7")]
CASES = {
    "baseline": [],
    "bearings_linear": _LINEAR,
    "drag_x10": ["gearbox.gears[3].drag_torque=10.0"],
    "drag_x100": ["gearbox.gears[3].drag_torque=100.0"],
    "modulation_off": ["gearbox.meshes[0].stiffness_cos=[]"],
    "rigid_housing": [],
    # all smooth: no impacts left (z4 held, no bearing clearance, no modulation) -- a linear
    # time-invariant system under the TE, whose settled motion is period-1 by construction
    "all_linear": _LINEAR + ["gearbox.gears[3].drag_torque=100.0",
                             "gearbox.meshes[0].stiffness_cos=[]"],
    # the same at rtol 1e-6 with 300 + 300 transient periods (a diagnostic of the classes,
    # not a switch: the scene's own rtol is the accuracy rule's ~1e-4)
    "all_linear_rtol1e-6": _LINEAR + ["gearbox.gears[3].drag_torque=100.0",
                                      "gearbox.meshes[0].stiffness_cos=[]",
                                      "integration.rtol=1e-6", "integration.atol=1e-12",
                                      "sweep.transient_periods=300",
                                      "sweep.extra_transient_periods=300"],
}


def rigid_housing_scene(src: Path = SCENE) -> Path:
    """A copy of the scene without [housing]: each shaft at its bore's (x, z), each bearing
    with its bore's rolling-element count."""
    text = src.read_text()
    bores = dict(re.findall(r'name = "(input|output)"\nx = ([0-9.]+)', text))
    z = re.search(r'\[\[housing\.bores\]\]\nname = "input"\nx = [0-9.]+\nz = ([0-9.]+)',
                  text).group(1)
    elements = dict(re.findall(r'name = "(input|output)"[^\[]*?rolling_elements = (\d+)',
                               text, flags=re.S))
    text = text[:text.index("# ---------------------------------------------------------------"
                            "- housing")] + text[text.index("# -------------------------------"
                                                            "--------------------------------"
                                                            "- analyses"):]
    for bore in ("input", "output"):
        text = text.replace(f'bore = "{bore}"', f"x = {bores[bore]}\nz = {z}")
    shaft_bore = {"driving": "input", "driven": "output"}
    for shaft, bore in shaft_bore.items():
        text = re.sub(rf'(shaft = "{shaft}"\nposition = [0-9.]+\ntype = "ball")',
                      rf"\1\nelements = {elements[bore]}", text)
    out = Path(tempfile.mkdtemp(prefix="vg_rigid_")) / "two_stage_rigid.toml"
    out.write_text(text)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=",".join(CASES))
    args = ap.parse_args(argv)
    done = json.loads(RESULTS.read_text()) if RESULTS.is_file() else {}
    for case in args.cases.split(","):
        scene = rigid_housing_scene() if case == "rigid_housing" else SCENE
        res = run_sweep(CASES[case] + ["sweep.second_tolerance=false"], SPEEDS,
                        transient=150, extra=100, scene=scene)
        done[case] = res
        RESULTS.parent.mkdir(parents=True, exist_ok=True)
        RESULTS.write_text(json.dumps(done, indent=1))
        print(case, f"{res['wall_s']:.0f} s", res.get("error", "")[-300:], flush=True)
    print("| case | " + " | ".join(f"{s:.0f} rpm" for s in SPEEDS) + " |")
    print("|---|" + "---|" * SPEEDS.size)
    for case, res in done.items():
        cells = []
        for r in res.get("rows", []):
            n = f" (P{r['period_n']})" if r["period_n"] else ""
            cells.append(f"{r['motion_class']}{n}, G2 {r['drive_G2'] + r['back_G2']:.2f}")
        print(f"| {case} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
