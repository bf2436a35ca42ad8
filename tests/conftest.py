"""Test-session settings: single-threaded BLAS before numpy loads (worker processes are
forked; a BLAS thread pool in the parent is what a fork can deadlock on)."""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
