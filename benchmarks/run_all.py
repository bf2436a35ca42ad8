"""Run every benchmark of the project side by side and print one summary table.

Run: make bench   (takes several minutes; the housing benchmark much longer: make housing-bench)
"""
from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
BENCHES = ["bench_continuation.py", "bench_integrator.py", "bench_rotor.py"]


def main() -> int:
    rows = []
    for name in BENCHES + [a for a in sys.argv[1:] if a not in BENCHES]:
        print(f"==== {name}", flush=True)
        t0 = time.perf_counter()
        r = subprocess.run([sys.executable, str(HERE / name)], text=True)
        rows.append((name, r.returncode, time.perf_counter() - t0))
    print("\n==== summary (results in benchmarks/results/)")
    for name, rc, wall in rows:
        print(f"{name:28s} exit {rc}  {wall:7.1f} s")
    return max(rc for _, rc, _ in rows)


if __name__ == "__main__":
    sys.exit(main())
