"""The contact fractions of many contacts at once (sweep metrics, unloaded rolling elements)
equal the one-contact computation, contact by contact, including events at the window's
start and contacts without events."""
from __future__ import annotations

import numpy as np

from vibrogear.solvers.sequential.motion import _fraction, _fractions


def test_fractions_equal_the_one_contact_form():
    rng = np.random.default_rng(1)
    for _ in range(300):
        nc = 12
        ne = int(rng.integers(0, 60))
        t = np.sort(rng.uniform(0.0, 10.0, ne))
        if ne:
            t[0] = 0.0                      # an event right at the window's start
        j = rng.integers(0, nc, ne)
        md = rng.integers(-1, 2, ne)
        mode0 = rng.integers(-1, 2, nc)
        rows = np.sort(rng.choice(nc, int(rng.integers(1, nc)), replace=False))
        one = [_fraction(int(mode0[c]), t[j == c], md[j == c], 0.0, 10.0) for c in rows]
        np.testing.assert_allclose(_fractions(mode0, t, j, md, 0.0, 10.0, rows), one,
                                   atol=1e-14)


def test_fraction_by_hand():
    # contact 0 closed on [0, 2) and [5, 10): 0.7; contact 1 never touches: 0
    t, j, md = np.array([2.0, 5.0]), np.array([0, 0]), np.array([0, 1])
    np.testing.assert_allclose(_fractions(np.array([1, 0]), t, j, md, 0.0, 10.0, [0, 1]),
                               [0.7, 0.0])
