#!/usr/bin/env bash
# Idempotent set-up on a fresh Debian 12 machine: apt stack, venv, editable install.
set -euo pipefail
cd "$(dirname "$0")/.."
PKGS="python3-dolfinx python3-petsc4py python3-slepc4py python3-mpi4py python3-gmsh python3-scipy python3-matplotlib python3-venv libopenblas0-pthread"
missing=""
for p in $PKGS; do dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"; done
if [ -n "$missing" ]; then
  echo "setup: installing Debian packages:$missing"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $missing
fi
if [ ! -x .venv/bin/python ]; then
  /usr/bin/python3 -m venv --system-site-packages .venv
fi
.venv/bin/pip install -q --disable-pip-version-check -c constraints.txt -e ".[test]" 2>&1 | grep -v "is ignored" || true
.venv/bin/python -c "import vibrogear, numba; assert tuple(int(x) for x in numba.__version__.split('.')[:2]) >= (0, 58), numba.__version__"
touch .venv/.installed
