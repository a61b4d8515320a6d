"""Compiled steps of the bilateral filter (numba): the guard :func:`.bilateral_filter._refuse_slivers_numpy`
and the ring iteration of :func:`.bilateral_filter.bilateral_filter` around its exponential.

The same IEEE operations in the same order as the numpy code (face qualities as
:func:`geometry.quality.triangle_quality`, cross products as ``cross_rows``, dots in numpy's
einsum order, sums in bincount's order), so the same vertices are moved and put back and the
result is the same bits. The exponential of the weights stays numpy's (its SIMD routine may
differ from libm's in the last bit). tests/algorithms/hu2012/test_bilateral_filter.py checks
the kernels against the numpy code.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...geometry._quality_kernels import face_cross, face_quality, unit_vertex_normals
from ...geometry._vector_kernels import dot3, npmax

__all__ = ["refuse_slivers", "ring_log_weights", "ring_step"]  # undo_moves: a helper compiled into them


@njit(cache=True)
def undo_moves(V, V_old, moved, back):
    """Put the vertices marked ``back`` where they were in V_old and mark them unmoved (in place)."""
    for v in range(len(back)):
        if back[v]:
            V[v, 0], V[v, 1], V[v, 2] = V_old[v, 0], V_old[v, 1], V_old[v, 2]
            moved[v] = False


@njit(cache=True)
def refuse_slivers(V_old, V_new, F, moved, min_quality):
    """V_new with the moves undone around each face that drops below min(min_quality, its quality
    before) or flips (V_old, V_new (n, 3) float64; F (m, 3) int64 with valid indices; moved (n,) bool)."""
    n, m = V_old.shape[0], F.shape[0]
    floor = np.empty(m)
    n_old = np.empty((m, 3))
    for f in range(m):
        q = face_quality(V_old, F[f, 0], F[f, 1], F[f, 2])
        floor[f] = q if q < min_quality or q != q else min_quality  # np.minimum (NaN wins)
        n_old[f, 0], n_old[f, 1], n_old[f, 2] = face_cross(V_old, F, f)
    V = V_new.copy()
    moved = moved.copy()
    back = np.zeros(n, np.bool_)
    for _ in range(n):
        back[:] = False
        anything = False
        for f in range(m):
            i, j, k = F[f, 0], F[f, 1], F[f, 2]
            if not (moved[i] or moved[j] or moved[k]):
                continue
            c = face_cross(V, F, f)
            bad = face_quality(V, i, j, k) < floor[f] * (1 - 1e-12) or \
                dot3((n_old[f, 0], n_old[f, 1], n_old[f, 2]), c) <= 0
            if bad:
                anything = True
                for v in (i, j, k):
                    if moved[v]:
                        back[v] = True
        if not anything:
            break
        undo_moves(V, V_old, moved, back)
    return V


@njit(cache=True)
def ring_log_weights(V, F, rows, cols, sc, ss):
    """One ring iteration of :func:`.bilateral_filter.bilateral_filter` up to its exponential.

    Returns the vertex normals N, the heights h of the pairs (rows[p], cols[p]) and their
    log-weights shifted by their row's largest (the numpy code's operations in its order; rows
    sorted; sc, ss per vertex), so that ``np.exp`` of the last gives the filter's weights.
    """
    n = V.shape[0]
    N = unit_vertex_normals(V, F, n)
    s = rows.shape[0]
    h = np.empty(s)
    z = np.empty(s)
    for p in range(s):
        r, q = rows[p], cols[p]
        d = (V[r, 0] - V[q, 0], V[r, 1] - V[q, 1], V[r, 2] - V[q, 2])
        t2 = dot3(d, d)
        h[p] = dot3((N[r, 0], N[r, 1], N[r, 2]), d)
        c, g = sc[r], ss[r]
        z[p] = -t2 / (2 * (c * c)) - (h[p] * h[p]) / (2 * (g * g))
    start = 0
    while start < s:  # per row: subtract its largest log-weight (np.maximum: NaN wins)
        stop = start + 1
        top = z[start]
        while stop < s and rows[stop] == rows[start]:
            top = npmax(top, z[stop])
            stop += 1
        for p in range(start, stop):
            z[p] = z[p] - top
        start = stop
    return N, h, z


@njit(cache=True)
def ring_step(V, N, rows, w, h, movable):
    """The move of one ring iteration: v <- v - n sum(w h) / sum(w) (bincount's order of sums).

    Returns the moved vertices and which of them moved (movable, with weights, a nonzero shift).
    """
    n = V.shape[0]
    num = np.zeros(n)
    den = np.zeros(n)
    for p in range(rows.shape[0]):
        num[rows[p]] += w[p] * h[p]
        den[rows[p]] += w[p]
    V_new = V.copy()
    moved = np.zeros(n, np.bool_)
    for v in range(n):
        if movable[v] and den[v] > 0:
            d = num[v] / den[v]
            V_new[v, 0] = V[v, 0] - N[v, 0] * d
            V_new[v, 1] = V[v, 1] - N[v, 1] * d
            V_new[v, 2] = V[v, 2] - N[v, 2] * d
            moved[v] = d != 0
    return V_new, moved
