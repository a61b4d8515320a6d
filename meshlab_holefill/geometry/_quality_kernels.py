"""Compiled per-triangle measures (numba), bit for bit the numpy expressions of :mod:`.quality`.

The per-hole loops call :func:`quality.triangle_quality` thousands of times on a few faces;
its numpy form spends nearly all of that in the overhead of some twenty small array
operations. The kernel does, element by element, the same IEEE operations in the same order
(no fastmath, no contraction to FMA; row sums and products of three left to right, as numpy's
add.reduce and multiply.reduce do on rows of three), so it returns the same bits.
tests/geometry/test_quality.py checks it against the numpy code.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._vector_kernels import norm3

__all__ = ["face_cross", "face_quality", "triangle_quality_kernel", "face_normals_kernel", "vertex_normals_kernel",
           "unit_vertex_normals"]


@njit(cache=True)
def face_cross(V, F, f):
    """(b - a) x (c - a) of face f = (a, b, c) of V, as ``cross_rows`` computes it (valid index)."""
    i, j, k = F[f, 0], F[f, 1], F[f, 2]
    u0, u1, u2 = V[j, 0] - V[i, 0], V[j, 1] - V[i, 1], V[j, 2] - V[i, 2]
    w0, w1, w2 = V[k, 0] - V[i, 0], V[k, 1] - V[i, 1], V[k, 2] - V[i, 2]
    return (u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0)


@njit(cache=True)
def face_quality(V, i, j, k):
    """2r/R of the face (i, j, k) of V, as triangle_quality computes it (valid indices)."""
    p0x, p0y, p0z = V[i, 0], V[i, 1], V[i, 2]
    p1x, p1y, p1z = V[j, 0], V[j, 1], V[j, 2]
    p2x, p2y, p2z = V[k, 0], V[k, 1], V[k, 2]
    ax, ay, az = p1x - p2x, p1y - p2y, p1z - p2z
    bx, by, bz = p2x - p0x, p2y - p0y, p2z - p0z
    cx, cy, cz = p0x - p1x, p0y - p1y, p0z - p1z
    la = math.sqrt((ax * ax + ay * ay) + az * az)
    lb = math.sqrt((bx * bx + by * by) + bz * bz)
    lc = math.sqrt((cx * cx + cy * cy) + cz * cz)
    ux, uy, uz = p1x - p0x, p1y - p0y, p1z - p0z
    wx, wy, wz = p2x - p0x, p2y - p0y, p2z - p0z
    nx = uy * wz - uz * wy
    ny = uz * wx - ux * wz
    nz = ux * wy - uy * wx
    area = 0.5 * math.sqrt((nx * nx + ny * ny) + nz * nz)
    denom = ((la + lb) + lc) * ((la * lb) * lc)
    v = 0.0
    if denom > 0:
        v = 16.0 * (area * area) / denom
    # np.clip(v, 0, 1): NaN passes through
    if v < 0.0:
        v = 0.0
    elif v > 1.0:
        v = 1.0
    return v


@njit(cache=True)
def triangle_quality_kernel(V, F):
    """(q, ok): Field's 2r/R of each face (V (n, 3) float64, F (m, 3) int64); ok is False when an
    index is out of range (q is then meaningless and the caller uses numpy, which raises)."""
    n, m = V.shape[0], F.shape[0]
    q = np.zeros(m)
    for f in range(m):
        i, j, k = F[f, 0], F[f, 1], F[f, 2]
        if i < -n or i >= n or j < -n or j >= n or k < -n or k >= n:
            return q, False
        q[f] = face_quality(V, i % n, j % n, k % n)
    return q, True


@njit(cache=True)
def face_normals_kernel(V, F, normalize):
    """(N, ok): :func:`quality.face_normals` of V (n, 3) float64, F (m, 3) int64; ok is False when an
    index is out of range (negative ones wrap, as numpy's indexing does)."""
    n, m = V.shape[0], F.shape[0]
    out = np.zeros((m, 3))
    for f in range(m):
        i, j, k = F[f, 0], F[f, 1], F[f, 2]
        if i < -n or i >= n or j < -n or j >= n or k < -n or k >= n:
            return out, False
        i, j, k = i % n, j % n, k % n
        u0, u1, u2 = V[j, 0] - V[i, 0], V[j, 1] - V[i, 1], V[j, 2] - V[i, 2]
        w0, w1, w2 = V[k, 0] - V[i, 0], V[k, 1] - V[i, 1], V[k, 2] - V[i, 2]
        x = (u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0)
        if not normalize:
            out[f, 0], out[f, 1], out[f, 2] = x
            continue
        length = norm3(x)
        if length > 0:  # a degenerate face (or a NaN length) keeps its zero row
            out[f, 0], out[f, 1], out[f, 2] = x[0] / length, x[1] / length, x[2] / length
    return out, True


@njit(cache=True)
def vertex_normals_kernel(V, F, n):
    """(N, ok): :func:`quality.vertex_normals` for ``n`` vertices; ok is False when an index is
    negative or not below n and len(V) (numpy then raises, or gives more rows)."""
    for f in range(F.shape[0]):
        for c in range(3):
            if F[f, c] < 0 or F[f, c] >= n or F[f, c] >= V.shape[0]:
                return np.zeros((n, 3)), False
    return unit_vertex_normals(V, F, n), True


@njit(cache=True)
def unit_vertex_normals(V, F, n):
    """:func:`quality.vertex_normals` bit for bit (valid indices below n): face cross products summed
    at the corners in corner_sums' order (corner 0 of every face, then 1, then 2), unit length."""
    m = F.shape[0]
    N = np.zeros((n, 3))
    C = np.empty((m, 3))
    for f in range(m):
        C[f, 0], C[f, 1], C[f, 2] = face_cross(V, F, f)
    for c in range(3):
        for f in range(m):
            v = F[f, c]
            N[v, 0] += C[f, 0]
            N[v, 1] += C[f, 1]
            N[v, 2] += C[f, 2]
    for v in range(n):
        length = norm3((N[v, 0], N[v, 1], N[v, 2]))
        if length > 0:
            N[v, 0], N[v, 1], N[v, 2] = N[v, 0] / length, N[v, 1] / length, N[v, 2] / length
    return N
