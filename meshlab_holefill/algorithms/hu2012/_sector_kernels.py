"""Compiled hole-sector tests (numba): :meth:`.hole_guards.LoopSectors.contains` row by row, and both ends of swaps.

The angle of each direction about the vertex normal is computed with the numpy code's
operations in its order (row dots in numpy's einsum order, the same floor modulo), except that
``arctan2`` is libm's where the numpy code's is numpy's SIMD routine, which may differ in the
last bits. The angle is only compared with the sector's bounds, so a comparison within
``ANGLE_MARGIN`` of a bound (far more than that difference) makes the kernel answer
``sure=False`` and the caller runs the numpy code. tests/algorithms/hu2012/test_min_angle_bilateral.py
checks the kernel against it.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...geometry._vector_kernels import dot3

# The filter runs swaps_in_sectors (its warm-up loads it); sector_contains serves LoopSectors.contains.
__all__ = ["swaps_in_sectors", "ANGLE_MARGIN"]

ANGLE_MARGIN = 1e-12


@njit(cache=True)
def sector_contains(points, u, w, limit, index, targets, margin):
    """(inside, sure): does the segment from loop vertex index[j] to targets[j] start into its hole sector?"""
    s = index.shape[0]
    inside = np.zeros(s, np.bool_)
    two_pi = 2 * np.pi
    for r in range(s):
        i = index[r]
        d = (targets[r, 0] - points[i, 0], targets[r, 1] - points[i, 1], targets[r, 2] - points[i, 2])
        phi = math.atan2(dot3(d, (w[i, 0], w[i, 1], w[i, 2])), dot3(d, (u[i, 0], u[i, 1], u[i, 2]))) % two_pi
        upper = limit[i] - margin
        if not (abs(phi - margin) > ANGLE_MARGIN and abs(phi - upper) > ANGLE_MARGIN):  # NaN too
            return inside, False
        inside[r] = phi > margin and phi < upper
    return inside, True


@njit(cache=True)
def swaps_in_sectors(points, u, w, limit, V, B, margin):
    """(ok, sure): :func:`sector_contains` for both ends of each swap's new edge (B[r, 1], B[r, 2]).

    A new edge (c, d) is allowed when, at each end on the loop (index below ``len(points)``),
    it starts into that vertex's hole sector; ``sure=False`` as soon as one angle is too close
    to a bound to decide here, or an index is out of range.
    """
    s = B.shape[0]
    ok = np.ones(s, np.bool_)
    for r in range(s):
        verdict = new_edge_in_sectors(points, u, w, limit, V, B[r, 1], B[r, 2], margin)
        if verdict < 0:
            return ok, False
        ok[r] = verdict == 1
    return ok, True


@njit(cache=True)
def new_edge_in_sectors(points, u, w, limit, V, c, d, margin):
    """1 / 0: the edge (c, d) starts into the hole sector at each of its loop ends / does not; -1: undecided."""
    k = points.shape[0]
    if c < 0 or d < 0 or c >= V.shape[0] or d >= V.shape[0]:
        return -1
    verdict = 1
    for end in range(2):
        i, j = (c, d) if end == 0 else (d, c)
        if i >= k:
            continue
        dv = (V[j, 0] - points[i, 0], V[j, 1] - points[i, 1], V[j, 2] - points[i, 2])
        phi = math.atan2(dot3(dv, (w[i, 0], w[i, 1], w[i, 2])), dot3(dv, (u[i, 0], u[i, 1], u[i, 2]))) % (2 * np.pi)
        upper = limit[i] - margin
        if not (abs(phi - margin) > ANGLE_MARGIN and abs(phi - upper) > ANGLE_MARGIN):  # NaN too
            return -1
        if not (phi > margin and phi < upper):
            verdict = 0
    return verdict
