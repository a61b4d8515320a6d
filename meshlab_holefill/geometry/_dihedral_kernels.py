"""Compiled dynamic programme of :mod:`.dihedral_triangulation` (numba)."""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["best_splits"]


@njit(cache=True)
def _unit_normal(P, a, b, c):
    """Unit normal and area of the triangle (a, b, c) of points P; a zero normal for a degenerate one."""
    u0, u1, u2 = P[b, 0] - P[a, 0], P[b, 1] - P[a, 1], P[b, 2] - P[a, 2]
    v0, v1, v2 = P[c, 0] - P[a, 0], P[c, 1] - P[a, 1], P[c, 2] - P[a, 2]
    n0, n1, n2 = u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0
    s = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    if s == 0.0:
        return 0.0, 0.0, 0.0, 0.0
    return n0 / s, n1 / s, n2 / s, 0.5 * s


@njit(cache=True)
def _bend(n0, n1, n2, m):
    """1 - cos of the angle between unit normals (n0, n1, n2) and m: 0 flat, 2 folded back."""
    return 1.0 - (n0 * m[0] + n1 * m[1] + n2 * m[2])


@njit(cache=True)
def _border_bend(n0, n1, n2, m):
    """:func:`_bend` against the mesh face on a loop edge; 0 where that face has no normal (a zero row)."""
    if m[0] == 0.0 and m[1] == 0.0 and m[2] == 0.0:
        return 0.0
    return _bend(n0, n1, n2, m)


@njit(cache=True)
def _is_banned(banned, code):
    at = np.searchsorted(banned, code)
    return at < len(banned) and banned[at] == code


@njit(cache=True)
def best_splits(P, border_normals, forbidden, banned):
    """Split vertex of every sub-polygon (i .. j) minimising (largest bend, area) in that order.

    ``forbidden[i, j]``: the pair may not be an edge; ``banned``: sorted codes (i k + m) k + j of
    triangles (i, m, j), i < m < j, that may not be used. Bends are 1 - cos of the angle between
    the normals of two triangles sharing an edge; on a loop edge (i, i + 1) the neighbour is the
    mesh face there (``border_normals[i]``, unit; a zero row bends nothing).

    Returns
    -------
    split : (k, k) int64  best m for (i, j), -1 where none
    worst : float  the largest bend of the whole triangulation (inf where there is none)
    """
    k = len(P)
    bend = np.full((k, k), np.inf)
    area = np.full((k, k), np.inf)
    split = np.full((k, k), -1, np.int64)
    normal = np.zeros((k, k, 3))  # unit normal of the best triangle on (i, j)
    for i in range(k - 1):
        bend[i, i + 1] = 0.0
        area[i, i + 1] = 0.0
    for span in range(2, k):
        for i in range(k - span):
            j = i + span
            if forbidden[i, j] and not (i == 0 and j == k - 1):
                continue
            best_bend, best_area = np.inf, np.inf
            for m in range(i + 1, j):
                inner = max(bend[i, m], bend[m, j])
                # the sides' own bends already exceed the best: this split loses whatever its triangle
                # (the cheap test first; inf, no triangulation of a side, is one of them)
                if inner > best_bend or inner == np.inf:
                    continue
                if len(banned) and _is_banned(banned, (i * k + m) * k + j):
                    continue
                n0, n1, n2, a = _unit_normal(P, i, m, j)
                if a == 0.0:
                    continue
                left = _border_bend(n0, n1, n2, border_normals[i]) if m == i + 1 else _bend(n0, n1, n2, normal[i, m])
                right = _border_bend(n0, n1, n2, border_normals[m]) if j == m + 1 else _bend(n0, n1, n2, normal[m, j])
                worst = max(inner, max(left, right))
                if i == 0 and j == k - 1:  # the closing loop edge (k - 1, 0)
                    worst = max(worst, _border_bend(n0, n1, n2, border_normals[k - 1]))
                total = area[i, m] + area[m, j] + a
                if worst < best_bend or (worst == best_bend and total < best_area):
                    best_bend, best_area = worst, total
                    split[i, j] = m
                    normal[i, j, 0], normal[i, j, 1], normal[i, j, 2] = n0, n1, n2
            bend[i, j], area[i, j] = best_bend, best_area
    return split, bend[0, k - 1]
