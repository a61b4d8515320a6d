"""Compiled candidate test of :func:`.unfolded_triangulation.sample_patch` (the resampling, beyond the paper).

:func:`best_candidates` takes, for each planar point still without a holding triangle, the
triangles the k-d tree proposed and keeps the one whose smallest barycentric coordinate is
largest, as the numpy code does with arrays of shape (points, candidates, 3): the same
coordinates (operation for operation), numpy's minimum (a NaN wins) and argmax (the first
largest, a NaN first), and a triangle replaces the point's earlier one only with a larger value.
The numpy version built a dozen such arrays per round: about half of the sampling's time.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["best_candidates"]


@njit(cache=True)
def _min3(a, b, c):
    """np.min of three values: NaN if any is NaN, the later of equal values (-0.0 and 0.0 as numpy's)."""
    m = a
    for v in (b, c):
        if not (m < v or math.isnan(m)):
            m = v
    return m


@njit(cache=True)
def best_candidates(targets, todo, cand, A, B, C, best_score, best_face, best_w):
    """For each point ``targets[todo[t]]``, its best candidate triangle ``cand[t]``, kept where it beats the point's best so far.

    Parameters
    ----------
    targets : (p, 2) float64  planar points
    todo : (q,) int64  the points tested
    cand : (q, k) int64  candidate triangles of each tested point
    A, B, C : (t, 2) float64  the triangles' corners
    best_score, best_face, best_w : (p,), (p,), (p, 3)  updated in place

    Notes
    -----
    Coordinates of point x in triangle (a, b, c): with v0 = b - a, v1 = c - a, v2 = x - a and
    den = v0 x v1 (1e-300 where it is 0), w1 = (v2 x v1) / den, w2 = (v0 x v2) / den and
    w = (1 - w1 - w2, w1, w2); the score is min(w).
    """
    w = np.empty(3)
    for t in range(todo.shape[0]):
        i = todo[t]
        px, py = targets[i, 0], targets[i, 1]
        top, top_face = 0.0, -1
        top_w = np.empty(3)
        for e in range(cand.shape[1]):
            f = cand[t, e]
            ax, ay = A[f, 0], A[f, 1]
            v0x, v0y = B[f, 0] - ax, B[f, 1] - ay
            v1x, v1y = C[f, 0] - ax, C[f, 1] - ay
            v2x, v2y = px - ax, py - ay
            den = v0x * v1y - v0y * v1x
            if den == 0.0:
                den = 1e-300
            w1 = (v2x * v1y - v2y * v1x) / den
            w2 = (v0x * v2y - v0y * v2x) / den
            w[0], w[1], w[2] = 1.0 - w1 - w2, w1, w2
            score = _min3(w[0], w[1], w[2])
            # argmax: the first candidate larger than every earlier one, or the first NaN
            if top_face < 0 or (not math.isnan(top) and (score > top or math.isnan(score))):
                top, top_face = score, f
                top_w[:] = w
        if top > best_score[i]:
            best_score[i], best_face[i] = top, top_face
            best_w[i] = top_w
