"""Compiled guard of the bilateral filter (numba): :func:`.bilateral_filter._refuse_slivers_numpy`.

The same IEEE operations in the same order as the numpy code (face qualities as
:func:`geometry.quality.triangle_quality`, cross products as ``cross_rows``, the flip test's dot in
numpy's einsum order), so the same vertices are put back and the result is the same bits.
tests/algorithms/hu2012/test_bilateral_filter.py checks it against the numpy code.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...geometry._quality_kernels import face_cross, face_quality
from ...geometry._tri_kernels import _dot

__all__ = ["refuse_slivers"]  # undo_moves is a helper of the compiled guards, compiled into them


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
                _dot((n_old[f, 0], n_old[f, 1], n_old[f, 2]), c) <= 0
            if bad:
                anything = True
                for v in (i, j, k):
                    if moved[v]:
                        back[v] = True
        if not anything:
            break
        undo_moves(V, V_old, moved, back)
    return V
