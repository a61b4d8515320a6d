"""Compiled inverse-distance interpolation of :mod:`.attributes` (numba)."""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["idw_interpolated"]


@njit(cache=True)
def idw_interpolated(sources, targets, values):
    """``values`` (s, c) given at ``sources`` (s, 3), interpolated at ``targets`` (t, 3): (t, c) float64.

    Each target takes the mean of the values weighted by 1 / max(d^2, 1e-300), d its distance
    to the source. A target's weights are held for that target alone, never for all of them:
    no (t, s) array, whose size grows as the cube of a hole's border length (27,553 new vertices
    by 908 border ones: the largest hole of face000.ply midpoint-subdivided twice, 2.8M faces).
    """
    t, s, c = targets.shape[0], sources.shape[0], values.shape[1]
    out = np.zeros((t, c))
    weights = np.empty(s)  # (s,) the current target's
    for i in range(t):
        total = 0.0
        for j in range(s):
            weights[j] = 1.0 / max(_squared_distance(targets, i, sources, j), 1e-300)
            total += weights[j]
        for j in range(s):
            w = weights[j] / total
            for q in range(c):
                out[i, q] += w * values[j, q]
    return out


@njit(cache=True)
def _squared_distance(A, i, B, j):
    """|A[i] - B[j]|^2, its terms added x, y, z."""
    dx, dy, dz = A[i, 0] - B[j, 0], A[i, 1] - B[j, 1], A[i, 2] - B[j, 2]
    return (dx * dx + dy * dy) + dz * dz
