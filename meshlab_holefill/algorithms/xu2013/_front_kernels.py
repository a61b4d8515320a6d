"""Compiled kernels of the advancing front's obstacle tests (numba).

:func:`min_point_triangle_distance` does, per triangle, the IEEE operations of
:func:`._front_predicates.point_triangle_distance` in the same order (no fastmath), so its
minimum is bit for bit the numpy function's (tests/algorithms/xu2013/test_front_kernels.py).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["min_point_triangle_distance"]


@njit(cache=True)
def _sq3(a0, a1, a2):
    return math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)


@njit(cache=True)
def min_point_triangle_distance(x, V, F, cand, radius):
    """min(radius, distance from x (3,) to the triangles V[F[cand]])."""
    best_all = np.inf
    for c in range(cand.shape[0]):
        f = cand[c]
        A = V[F[f, 0]]
        B = V[F[f, 1]]
        C = V[F[f, 2]]
        e1 = (B[0] - A[0], B[1] - A[1], B[2] - A[2])
        e2 = (C[0] - A[0], C[1] - A[1], C[2] - A[2])
        n0 = e1[1] * e2[2] - e1[2] * e2[1]
        n1 = e1[2] * e2[0] - e1[0] * e2[2]
        n2 = e1[0] * e2[1] - e1[1] * e2[0]
        nn = n0 * n0 + n1 * n1 + n2 * n2
        w0, w1, w2 = x[0] - A[0], x[1] - A[1], x[2] - A[2]
        ok = nn > 0
        t = (w0 * n0 + w1 * n1 + w2 * n2) / nn if ok else 0.0
        p0, p1, p2 = x[0] - t * n0, x[1] - t * n1, x[2] - t * n2
        inside = ok
        for k in range(3):
            U = A if k == 0 else (B if k == 1 else C)
            W = B if k == 0 else (C if k == 1 else A)
            a0, a1, a2 = W[0] - U[0], W[1] - U[1], W[2] - U[2]
            b0, b1, b2 = p0 - U[0], p1 - U[1], p2 - U[2]
            c0 = a1 * b2 - a2 * b1
            c1 = a2 * b0 - a0 * b2
            c2 = a0 * b1 - a1 * b0
            if not (c0 * n0 + c1 * n1 + c2 * n2 >= 0.0):
                inside = False
        best = abs(t) * math.sqrt(nn) if inside else np.inf
        for k in range(3):
            U = A if k == 0 else (B if k == 1 else C)
            W = B if k == 0 else (C if k == 1 else A)
            e0, e1_, e2_ = W[0] - U[0], W[1] - U[1], W[2] - U[2]
            ee = max(e0 * e0 + e1_ * e1_ + e2_ * e2_, 1e-300)
            s = ((x[0] - U[0]) * e0 + (x[1] - U[1]) * e1_ + (x[2] - U[2]) * e2_) / ee
            s = min(max(s, 0.0), 1.0)
            d = _sq3(x[0] - (U[0] + s * e0), x[1] - (U[1] + s * e1_), x[2] - (U[2] + s * e2_))
            best = min(best, d)
        best_all = min(best_all, best)
    return min(best_all, radius)
