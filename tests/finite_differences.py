"""Central finite differences of the shooting function, shared by the Jacobian tests."""
from __future__ import annotations

import numpy as np

from vibrogear.solvers.periodic.shooting import periodic_flow

__all__ = ["fd_shooting_jacobian"]


def fd_shooting_jacobian(model, param, u0, options, eps=1e-6):
    """(dG/du0, dG/dparam) of G = u(T(param); u0, param) - u0 by central differences."""
    u0 = np.asarray(u0, float)
    n = u0.size

    def G(u, p):
        return periodic_flow(model, p, u, options=options).G

    J = np.zeros((n, n))
    for k in range(n):
        e = np.zeros(n)
        e[k] = eps
        J[:, k] = (G(u0 + e, param) - G(u0 - e, param)) / (2 * eps)
    dp = (G(u0, param + eps) - G(u0, param - eps)) / (2 * eps)
    return J, dp
