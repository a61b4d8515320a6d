"""Compiled steps of the tangential smoothing (numba): its moves and its guard.

:func:`tangential_steps` is :func:`.tangential_smoothing._tangential_steps_numpy` (each round's
move of every movable vertex), :func:`refuse_worse` is :func:`.tangential_smoothing._refuse_worse_numpy`
(the guard run after every trial move). Both run on a few hundred faces, every round, and their
numpy forms are dominated by the overhead of small array operations. The kernels do the same
IEEE operations in the same order (face qualities as :func:`geometry.quality.triangle_quality`,
cross products as ``cross_rows``, row norms and dots as numpy's add.reduce and einsum, sums
over faces in bincount's order), and take minima, which are exact, so they return the same
bits. tests/algorithms/hu2012/test_smoothing_kernels.py checks them against the numpy code.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...geometry._quality_kernels import face_cross, face_quality
from ...geometry._vector_kernels import dot3, norm3, npmax
from ._bilateral_kernels import undo_moves

__all__ = ["refuse_worse", "tangential_steps"]

_HALF_SQRT3 = np.sqrt(3.0) / 2.0  # the numpy code's constant, the same double


@njit(cache=True)
def tangential_steps(V, F, movable):
    """Each movable vertex's step to the mean apex of its faces, its part along the vertex normal removed.

    V : (n, 3) float64; F : (m, 3) int64 (valid indices); movable : (n,) bool.
    Returns d (n, 3) float64 (zero rows where not ``ok``) and ok (n,) bool: movable and on a face.
    """
    n, m = V.shape[0], F.shape[0]
    count = np.zeros(n)
    for f in range(m):
        for c in range(3):
            count[F[f, c]] += 1.0
    unit = np.empty((m, 3))
    for f in range(m):
        x = face_cross(V, F, f)
        length = npmax(norm3(x), 1e-300)
        unit[f, 0], unit[f, 1], unit[f, 2] = x[0] / length, x[1] / length, x[2] / length
    # target[:, j] += bincount(F[:, c], apex[:, j]) for c = 0, 1, 2: three sums, each from zero in
    # face order, added to the target in turn.
    target = np.zeros((n, 3))
    part = np.empty((n, 3))
    for c in range(3):
        part[:] = 0.0
        for f in range(m):
            v, a, b = F[f, c], F[f, (c + 1) % 3], F[f, (c + 2) % 3]
            e0, e1, e2 = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
            u0, u1, u2 = unit[f, 0], unit[f, 1], unit[f, 2]
            part[v, 0] += 0.5 * (V[a, 0] + V[b, 0]) + _HALF_SQRT3 * (u1 * e2 - u2 * e1)
            part[v, 1] += 0.5 * (V[a, 1] + V[b, 1]) + _HALF_SQRT3 * (u2 * e0 - u0 * e2)
            part[v, 2] += 0.5 * (V[a, 2] + V[b, 2]) + _HALF_SQRT3 * (u0 * e1 - u1 * e0)
        for v in range(n):
            for j in range(3):
                target[v, j] += part[v, j]
    # vertex_normals: the face cross products summed at the corners (corner_sums' order: every
    # face's corner 0, then corner 1, then corner 2), divided by their norm where it is > 0.
    normal = np.zeros((n, 3))
    for c in range(3):
        for f in range(m):
            x = face_cross(V, F, f)
            v = F[f, c]
            normal[v, 0] += x[0]
            normal[v, 1] += x[1]
            normal[v, 2] += x[2]
    d = np.zeros((n, 3))
    ok = np.zeros(n, np.bool_)
    for v in range(n):
        ok[v] = movable[v] and count[v] > 0
        if not ok[v]:
            continue
        nv = (normal[v, 0], normal[v, 1], normal[v, 2])
        length = norm3(nv)
        if length > 0:
            nv = (nv[0] / length, nv[1] / length, nv[2] / length)
        t = (target[v, 0] / count[v] - V[v, 0], target[v, 1] / count[v] - V[v, 1], target[v, 2] / count[v] - V[v, 2])
        along = dot3(t, nv)
        d[v, 0], d[v, 1], d[v, 2] = t[0] - along * nv[0], t[1] - along * nv[1], t[2] - along * nv[2]
    return d, ok


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
