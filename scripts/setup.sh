#!/usr/bin/env bash
# Idempotent set-up on a fresh Debian 12 machine: apt stack, venv, editable install.
# Prints a few lines; the tools' own output goes to a log in $TMPDIR, shown when a step fails.
set -euo pipefail
cd "$(dirname "$0")/.."
LOG="$(mktemp -t vibrogear-setup.XXXXXX.log)"
: > "$LOG"
step() {   # step "what" command...: run quietly, show the log and stop on failure
  local what="$1"; shift
  if ! "$@" >>"$LOG" 2>&1; then
    echo "setup: FAILED: $what; its output:" >&2
    tail -n 60 "$LOG" >&2
    exit 1
  fi
}
# --browser: also Debian's chromium, which the test tier's browser test renders report.html in
[ "${1:-}" = "--browser" ] && BROWSER="chromium" || BROWSER=""
PKGS="$BROWSER python3-dolfinx python3-petsc4py python3-slepc4py python3-mpi4py python3-gmsh python3-h5py-mpi python3-scipy python3-matplotlib python3-venv libopenblas0-pthread"
missing=""
for p in $PKGS; do dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"; done
if [ -n "$missing" ]; then
  echo "setup: installing Debian packages:$missing"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  step "apt-get update" $SUDO apt-get update -qq
  step "apt-get install" env DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq \
    -o Dpkg::Use-Pty=0 $missing
fi
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv"
  step "python3 -m venv" /usr/bin/python3 -m venv --system-site-packages .venv
fi
echo "setup: installing vibrogear (editable) and its Python dependencies"
step "pip install" .venv/bin/pip install -q --disable-pip-version-check -c constraints.txt -e ".[test]"
step "import check" .venv/bin/python -c "import vibrogear, numba, tqdm; assert tuple(int(x) for x in numba.__version__.split('.')[:2]) >= (0, 58), numba.__version__"
touch .venv/.installed
echo "setup: done (log: $LOG)"
