"""Independent reference solutions used by the test suite.

Nothing in this package imports :mod:`vibrogear`; the references are built
from closed-form mathematics only (numpy / scipy), so that they can verify
the project's numerical solvers independently.
"""
