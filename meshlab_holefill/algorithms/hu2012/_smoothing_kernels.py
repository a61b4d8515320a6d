"""Compiled guard of the tangential smoothing (numba): :func:`.tangential_smoothing._refuse_worse_numpy`.

The guard runs after every trial move of every smoothing round, on a few hundred faces, and
its numpy form is dominated by the overhead of small array operations. The kernel does the
same IEEE operations in the same order (face qualities as :func:`geometry.quality.triangle_quality`,
cross products as ``cross_rows``, the flip test's dot in numpy's einsum order), and takes
minima, which are exact, so it returns the same bits. tests/algorithms/hu2012/test_smoothing_kernels.py
checks it against the numpy code.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...geometry._quality_kernels import face_cross, face_quality
from ...geometry._vector_kernels import dot3
from ._bilateral_kernels import undo_moves

__all__ = ["refuse_worse"]


@njit(cache=True)
def _minimum(a, b):
    """np.minimum of two floats (NaN wins, as in np.minimum.at)."""
    if a != a or b != b:
        return np.nan
    return a if a <= b else b


@njit(cache=True)
def _quality_or_flipped(V, F, f, n_old):
    c = face_cross(V, F, f)
    if dot3((n_old[f, 0], n_old[f, 1], n_old[f, 2]), c) <= 0:
        return -1.0
    return face_quality(V, F[f, 0], F[f, 1], F[f, 2])


@njit(cache=True)
def refuse_worse(V_old, V_new, F, moved):
    """V_new with the moves undone that lower the smallest quality around a moved vertex or flip a face.

    V_old, V_new : (n, 3) float64; F : (m, 3) int64 (valid indices); moved : (n,) bool.
    """
    n, m = V_old.shape[0], F.shape[0]
    worst_old = np.full(n, np.inf)
    n_old = np.empty((m, 3))
    for f in range(m):
        q = face_quality(V_old, F[f, 0], F[f, 1], F[f, 2])
        for c in range(3):
            worst_old[F[f, c]] = _minimum(worst_old[F[f, c]], q)
        n_old[f, 0], n_old[f, 1], n_old[f, 2] = face_cross(V_old, F, f)
    V = V_new.copy()
    moved = moved.copy()
    q = np.empty(m)
    for f in range(m):
        q[f] = _quality_or_flipped(V, F, f, n_old)
    back = np.zeros(n, np.bool_)
    for _ in range(n):
        worst = np.full(n, np.inf)
        for f in range(m):
            for c in range(3):
                worst[F[f, c]] = _minimum(worst[F[f, c]], q[f])
        anything = False
        for v in range(n):
            back[v] = moved[v] and worst[v] < worst_old[v] - 1e-12
            anything = anything or back[v]
        if not anything:
            break
        undo_moves(V, V_old, moved, back)
        for f in range(m):
            if back[F[f, 0]] or back[F[f, 1]] or back[F[f, 2]]:
                q[f] = _quality_or_flipped(V, F, f, n_old)
    return V
