"""Compiled kernels of the decimation of Sec. 4.7 (numba): the edge table and vertex adjacency of a
face list, and the independent set of edges collapsed in one round.

Integer logic only, so the results are exactly those of the numpy / sparse-matrix expressions
they replace (tests/algorithms/xie_zou2013/test_de_kernels.py checks them against those).
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["independent_link_edges", "edge_adjacency", "faces_around_edges"]


@njit(cache=True)
def independent_link_edges(indptr, indices, a, b, n):
    """Edges (a[r], b[r]), r in priority order, that may collapse together in one round, (C,) bool.

    Edge r is kept when no earlier edge's closed neighbourhood (the ends and their neighbours)
    shares a vertex with its own (every vertex is claimed by the first edge that reaches it, and an
    edge reaching a vertex claimed by another is lost), and its ends have exactly two common
    neighbours (the link condition). ``indptr``, ``indices``: CSR adjacency without self loops.
    """
    C = len(a)
    claim = np.full(n, C, np.int64)
    for r in range(C):
        for v in (a[r], b[r]):
            if claim[v] == C:
                claim[v] = r
            for p in range(indptr[v], indptr[v + 1]):
                w = indices[p]
                if claim[w] == C:
                    claim[w] = r
    keep = np.zeros(C, np.bool_)
    mark = np.zeros(n, np.int64) - 1
    for r in range(C):
        ok = True
        for v in (a[r], b[r]):
            if claim[v] != r:
                ok = False
            for p in range(indptr[v], indptr[v + 1]):
                if claim[indices[p]] != r:
                    ok = False
        if not ok:
            continue
        for p in range(indptr[a[r]], indptr[a[r] + 1]):
            mark[indices[p]] = r
        common = 0
        for p in range(indptr[b[r]], indptr[b[r] + 1]):
            if mark[indices[p]] == r:
                common += 1
        keep[r] = common == 2
    return keep


@njit(cache=True)
def edge_adjacency(F, n):
    """Unique edges and the CSR vertex adjacency of a face list on n vertices.

    The face edges are grouped by their smaller end and each group (a vertex's few edges)
    sorted by insertion (:func:`_edges_by_smaller_end`): the same rows as sorting the keys
    a n + b of all 3 m face edges, in a fifth of the time.

    Returns
    -------
    E : (e, 2) int64  rows (a, b), a < b, in lexicographic order (optimisation.sorted_edges)
    indptr : (n + 1,) int64, indices : (2 e,) int64
        The symmetric adjacency, each row's neighbours ascending (scipy's canonical CSR of
        the pairs (a, b) and (b, a)): one pass over E in order appends b to row a and a to
        row b, and every row's smaller neighbours come from edges before its larger ones.
    """
    start, higher = _edges_by_smaller_end(F, n)
    e = 0
    for v in range(n):
        for p in range(start[v], start[v + 1]):
            e += p == start[v] or higher[p] != higher[p - 1]
    E = np.empty((e, 2), np.int64)
    r = 0
    for v in range(n):  # the distinct edges (v, b), b ascending
        for p in range(start[v], start[v + 1]):
            if p == start[v] or higher[p] != higher[p - 1]:
                E[r, 0] = v
                E[r, 1] = higher[p]
                r += 1
    indptr = np.zeros(n + 1, np.int64)
    for r in range(e):
        indptr[E[r, 0] + 1] += 1
        indptr[E[r, 1] + 1] += 1
    for v in range(n):
        indptr[v + 1] += indptr[v]
    fill = indptr[:-1].copy()
    indices = np.empty(2 * e, np.int64)
    for r in range(e):
        a, b = E[r, 0], E[r, 1]
        indices[fill[a]] = b
        fill[a] += 1
        indices[fill[b]] = a
        fill[b] += 1
    return E, indptr, indices


@njit(cache=True)
def _edges_by_smaller_end(F, n):
    """(start (n + 1,), higher (3 m,)): the larger ends of the face edges, grouped by the smaller end, ascending.

    higher[start[v]:start[v + 1]] are the larger ends of the face edges whose smaller end is v
    (an edge twice if two faces hold it).
    """
    m = F.shape[0]
    start = np.zeros(n + 1, np.int64)
    for f in range(m):
        for c in range(3):
            start[min(F[f, c], F[f, (c + 1) % 3]) + 1] += 1
    for v in range(n):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    higher = np.empty(3 * m, np.int64)
    for f in range(m):
        for c in range(3):
            u, w = F[f, c], F[f, (c + 1) % 3]
            higher[fill[min(u, w)]] = max(u, w)
            fill[min(u, w)] += 1
    for v in range(n):  # insertion sort of each group
        for p in range(start[v] + 1, start[v + 1]):
            x = higher[p]
            q = p - 1
            while q >= start[v] and higher[q] > x:
                higher[q + 1] = higher[q]
                q -= 1
            higher[q + 1] = x
    return start, higher


@njit(cache=True)
def faces_around_edges(F, n, a, b):
    """(rows, faces): for each edge r = (a[r], b[r]) the faces holding exactly one of its ends.

    Ordered by r, then face index: the nonzeros of (VF[a] + VF[b]) below 2, VF the (n, m)
    vertex-face incidence, in scipy's canonical order.
    """
    m = F.shape[0]
    start = np.zeros(n + 1, np.int64)
    for f in range(m):
        for c in range(3):
            start[F[f, c] + 1] += 1
    for v in range(n):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    faces_of = np.empty(3 * m, np.int64)
    for f in range(m):  # faces ascending within each vertex
        for c in range(3):
            faces_of[fill[F[f, c]]] = f
            fill[F[f, c]] += 1
    total = 0
    for r in range(len(a)):
        total += start[a[r] + 1] - start[a[r]] + start[b[r] + 1] - start[b[r]]
    rows = np.empty(total, np.int64)
    faces = np.empty(total, np.int64)
    out = 0
    for r in range(len(a)):
        i, i_end = start[a[r]], start[a[r] + 1]
        j, j_end = start[b[r]], start[b[r] + 1]
        while i < i_end or j < j_end:  # merge the two ascending lists, dropping the shared faces
            if j == j_end or (i < i_end and faces_of[i] < faces_of[j]):
                f = faces_of[i]
                i += 1
            elif i == i_end or faces_of[j] < faces_of[i]:
                f = faces_of[j]
                j += 1
            else:
                i += 1
                j += 1
                continue
            rows[out] = r
            faces[out] = f
            out += 1
    return rows[:out], faces[:out]
