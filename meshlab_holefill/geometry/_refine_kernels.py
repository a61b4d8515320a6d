"""Compiled split test of the refinement (numba): :func:`.refine.split_condition` element by element.

The same IEEE operations in the same order as the numpy code (means of three corners added
left to right then divided by 3, row norms as in :mod:`._vector_kernels`), so centroids, scales
and the distance tests are the same bits. The one exception is the largest-angle test: the
numpy code's ``arctan2`` is numpy's SIMD routine, which may differ from libm's in the last
bits, so a corner angle within ``ANGLE_MARGIN`` of 5 pi / 6 makes the kernel answer
``sure=False`` and the caller runs the numpy code. tests/geometry/test_refine.py checks the
kernel against it.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._vector_kernels import cross3, dot3, norm3, sub3

__all__ = ["split_test", "split_faces", "ANGLE_MARGIN"]

ANGLE_MARGIN = 1e-12


@njit(cache=True)
def _corner_angle(V, p, q, r):
    P = (V[p, 0], V[p, 1], V[p, 2])
    u = sub3((V[q, 0], V[q, 1], V[q, 2]), P)
    w = sub3((V[r, 0], V[r, 1], V[r, 2]), P)
    return math.atan2(norm3(cross3(u, w)), dot3(u, w))


@njit(cache=True)
def split_test(V, F, scale, alpha):
    """(mask, centroids, centroid_scale, sure) of split_condition for V (n, 3), F (m, 3) int64, scale (n,)."""
    m = F.shape[0]
    mask = np.zeros(m, np.bool_)
    C = np.empty((m, 3))
    sc = np.empty(m)
    limit = 5.0 * np.pi / 6.0
    for f in range(m):
        i, j, k = F[f, 0], F[f, 1], F[f, 2]
        for x in range(3):
            C[f, x] = ((V[i, x] + V[j, x]) + V[k, x]) / 3
        sc[f] = ((scale[i] + scale[j]) + scale[k]) / 3
        split = True
        for v in (i, j, k):
            d = alpha * norm3((V[v, 0] - C[f, 0], V[v, 1] - C[f, 1], V[v, 2] - C[f, 2]))
            split = split and d > sc[f] and d > scale[v]
        for p, q, r in ((i, j, k), (j, k, i), (k, i, j)):
            angle = _corner_angle(V, p, q, r)
            if not abs(angle - limit) > ANGLE_MARGIN:  # NaN too
                return mask, C, sc, False
            split = split and angle < limit
        mask[f] = split
    return mask, C, sc, True


@njit(cache=True)
def split_faces(V, F, scale, mask, C, sc):
    """Split each face f with mask[f] at its centroid C[f] into three: (V, F, scale) with s new vertices.

    Face (i, j, k) becomes (c, j, k) in place and (i, c, k), (i, j, c) are appended, all the
    first of these in face order then all the second; the new vertex c = n + its rank among the
    split faces has position C[f] and scale sc[f].

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int64, scale : (n,) float64
    mask : (m,) bool, C : (m, 3) float64, sc : (m,) float64

    Returns
    -------
    V : (n + s, 3) float64, F : (m + 2 s, 3) int64, scale : (n + s,) float64
    """
    n, m = V.shape[0], F.shape[0]
    s = 0
    for f in range(m):
        s += mask[f]
    V2, F2, scale2 = np.empty((n + s, 3)), np.empty((m + 2 * s, 3), np.int64), np.empty(n + s)
    for v in range(n):
        V2[v, 0], V2[v, 1], V2[v, 2] = V[v, 0], V[v, 1], V[v, 2]
        scale2[v] = scale[v]
    r = 0
    for f in range(m):
        i, j, k = F[f, 0], F[f, 1], F[f, 2]
        if not mask[f]:
            F2[f, 0], F2[f, 1], F2[f, 2] = i, j, k
            continue
        c = n + r
        V2[c, 0], V2[c, 1], V2[c, 2] = C[f, 0], C[f, 1], C[f, 2]
        scale2[c] = sc[f]
        F2[f, 0], F2[f, 1], F2[f, 2] = c, j, k
        F2[m + r, 0], F2[m + r, 1], F2[m + r, 2] = i, c, k
        F2[m + s + r, 0], F2[m + s + r, 1], F2[m + s + r, 2] = i, j, c
        r += 1
    return V2, F2, scale2
