"""`make demo` as a user runs it, warm (issue 23 target: <= 45 s, its sweep <= 8 s and its
continuation <= 20 s), with the wall time of each analysis from ``summary.json``.

``--baseline DIR``: a checkout of an earlier vibrogear (e.g. ``git worktree add /tmp/base
<rev>``) run on the same scene file of its own in the same invocation, before ours, each
preceded by a warm-up run of its time response (numba cache and housing FE cache filled), so
the ratio compares like with like on this machine at this moment.

Writes benchmarks/results/bench_demo.json.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
TARGETS = {"total": 45.0, "sweep": 8.0, "continuation": 20.0}


def _run(tree: Path, out: Path, analyses: str | None = None) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1")
    cmd = [sys.executable, "-c", "import sys; from vibrogear.cli import main; "
           "sys.exit(main(sys.argv[1:]))", "run", "configs/two_stage.toml", "--out", str(out),
           "--quiet"]
    if analyses:
        cmd += ["--set", f"scene.analyses={analyses}"]
    t = time.perf_counter()
    subprocess.run(cmd, cwd=tree, env=env, check=True)
    wall = time.perf_counter() - t
    summary = json.loads((out / "summary.json").read_text())
    return {"process_wall_s": wall, "wall_time_s": summary["wall_time_s"],
            "sweep_points": summary["results"].get("sweep", {}).get("points"),
            "branch_points": sum(b["points"] for b in summary["results"].get(
                "continuation", {}).get("branches", []))}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", help="an earlier checkout to run first")
    ap.add_argument("--out", default=str(HERE / "results" / "bench_demo.json"))
    a = ap.parse_args(argv)
    trees = ([("baseline", Path(a.baseline).resolve())] if a.baseline else []) + [
        ("current", ROOT)]
    res = {"targets_s": TARGETS, "load_average_before": os.getloadavg(), "runs": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for name, tree in trees:
            _run(tree, Path(tmp) / f"{name}_warm", '["time_response"]')
            res["runs"][name] = _run(tree, Path(tmp) / name)
            print(name, json.dumps(res["runs"][name]["wall_time_s"]), flush=True)
    res["load_average_after"] = os.getloadavg()
    if a.baseline:
        b, c = (res["runs"][k]["wall_time_s"] for k in ("baseline", "current"))
        res["ratio_current_over_baseline"] = {k: c[k] / b[k] for k in c if k in b and b[k]}
    cur = res["runs"]["current"]["wall_time_s"]
    res["met"] = {k: cur.get(k, float("inf")) <= v for k, v in TARGETS.items()}
    Path(a.out).write_text(json.dumps(res, indent=1))
    return res


if __name__ == "__main__":
    main()
