"""Rewrite the golden files of the regression tier (``make golden``; optionally only the
named cases).  Review the diff (``git diff tests/regression/golden``) before committing:
every moved number needs a reason."""
from __future__ import annotations

import datetime
import json
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parents[1])]
from regression.cases import CASES, GOLDEN, ROOT, run_case  # noqa: E402


def main(names: list[str]) -> int:
    GOLDEN.mkdir(exist_ok=True)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip()
    for name in names or sorted(CASES):
        with tempfile.TemporaryDirectory() as tmp:
            values = run_case(name, Path(tmp))
        doc = {"case": name, "what": CASES[name].__doc__.split("\n\n")[0].strip(),
               "generated": datetime.date.today().isoformat(), "commit": commit,
               "values": values}
        (GOLDEN / f"{name}.json").write_text(json.dumps(doc, indent=1) + "\n")
        print(f"wrote {GOLDEN / name}.json")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
