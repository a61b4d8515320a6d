"""Compiled turn test of :func:`.crossing_test.embeds_in_projection` (numba).

The projected corner angles are summed per vertex as the numpy code sums them (corner 0 of
every face, then 1, then 2, each in bincount's order) and compared with the full turn. Angles
come from libm's ``atan2`` where the numpy code's are numpy's, which may differ in the last
bits; a vertex's sum is a whole number of turns of the projection plus rounding, so it lies
either within about 1e-12 of the expected angle or a large fraction of a turn away, far from
the tolerance. A sum within ``TURN_MARGIN`` of the tolerance makes the kernel answer
``sure=False`` and the caller runs the numpy code. tests/algorithms/hu2012/test_min_angle_bilateral.py
checks the kernel against it.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["projected_turns", "TURN_MARGIN"]

TURN_MARGIN = 1e-9


@njit(cache=True)
def projected_turns(Q, F, k, tol):
    """(ok, sure): do the projected corner angles (Q (n, 2), counter-clockwise faces F) add up to
    2 pi at every vertex from k on and to the loop's own interior angle at loop vertices i < k,
    within ``tol``, with every vertex used by a face?"""
    n = Q.shape[0]
    total = np.zeros(n)
    part = np.empty(n)
    used = np.zeros(n, np.bool_)
    for c in range(3):
        part[:] = 0.0
        for f in range(F.shape[0]):
            o, p, q = F[f, c], F[f, (c + 1) % 3], F[f, (c + 2) % 3]
            ax, ay = Q[p, 0] - Q[o, 0], Q[p, 1] - Q[o, 1]
            bx, by = Q[q, 0] - Q[o, 0], Q[q, 1] - Q[o, 1]
            part[o] += math.atan2(ax * by - ay * bx, ax * bx + ay * by)
            used[o] = True
        for v in range(n):
            total[v] += part[v]
    two_pi = 2 * np.pi
    ok = True
    for v in range(n):
        if not used[v]:
            return False, True
        if v < k:
            a, b = (v - 1) % k, (v + 1) % k
            px, py = Q[a, 0] - Q[v, 0], Q[a, 1] - Q[v, 1]
            nx, ny = Q[b, 0] - Q[v, 0], Q[b, 1] - Q[v, 1]
            expected = math.atan2(nx * py - ny * px, nx * px + ny * py) % two_pi
        else:
            expected = two_pi
        off = abs(total[v] - expected)
        if not abs(off - tol) > TURN_MARGIN:  # NaN too
            return False, False
        ok = ok and off < tol
    return ok, True
