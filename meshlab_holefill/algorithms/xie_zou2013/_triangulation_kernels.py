"""Compiled kernels of the planar triangulation of Sec. 4.6 (numba): which prediction points lie
inside the boundary polygon, and how far from it.

Each kernel does, point by point and edge by edge, the IEEE operations of the numpy expression
it replaces in the same order (no fastmath, no contraction to FMA), so the results are bit for
bit those of the (q, k) arrays the expressions build (tests/algorithms/xie_zou2013/
test_triangulation_kernels.py checks them against the numpy references kept there).
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["points_in_polygon", "distance_to_polygon"]


@njit(cache=True)
def points_in_polygon(Q, X):
    """Even-odd rule: which 2D points X (q, 2) lie inside the closed polygon Q (k, 2), (q,) bool.

    A point counts the edges (a, b) whose ends lie on either side of its horizontal line and
    whose crossing x = a_x + (p_y - a_y) (b_x - a_x) / (b_y - a_y) lies right of it.
    """
    k = Q.shape[0]
    inside = np.zeros(X.shape[0], np.bool_)
    for i in range(X.shape[0]):
        px, py = X[i, 0], X[i, 1]
        odd = False
        for e in range(k):
            ax, ay = Q[e, 0], Q[e, 1]
            bx, by = Q[(e + 1) % k, 0], Q[(e + 1) % k, 1]
            if (ay > py) != (by > py):
                # by != ay here, so no division by zero (numpy's expression divides everywhere)
                if px < ax + (py - ay) * (bx - ax) / (by - ay):
                    odd = not odd
        inside[i] = odd
    return inside


@njit(cache=True)
def distance_to_polygon(Q, X):
    """Distance of 2D points X (q, 2) to the edges of the closed polygon Q (k, 2), (q,).

    Per edge (a, b), d = b - a: t = clip(((x - a) . d) / max(d . d, 1e-300), 0, 1) and the
    distance |x - (a + t d)|. The dot products of two terms are the products rounded and then
    added (numpy's einsum and norm over an axis of length 2), the smallest distance is exact.
    """
    k = Q.shape[0]
    out = np.empty(X.shape[0])
    for i in range(X.shape[0]):
        x0, x1 = X[i, 0], X[i, 1]
        best = np.inf
        for e in range(k):
            a0, a1 = Q[e, 0], Q[e, 1]
            d0, d1 = Q[(e + 1) % k, 0] - a0, Q[(e + 1) % k, 1] - a1
            t = ((x0 - a0) * d0 + (x1 - a1) * d1) / max(d0 * d0 + d1 * d1, 1e-300)
            t = min(max(t, 0.0), 1.0)
            e0, e1 = x0 - (a0 + t * d0), x1 - (a1 + t * d1)
            best = min(best, np.sqrt(e0 * e0 + e1 * e1))
        out[i] = best
    return out
