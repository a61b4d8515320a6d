"""Compiled kernels of :mod:`.laplacian` (numba): the vertex adjacency's CSR arrays, and the rounds of the
tangential umbrella smoothing, bit for bit the numpy/scipy code of
:func:`.laplacian.tangential_umbrella_smoothing_numpy`.

:func:`adjacency_arrays` gives the arrays scipy's COO-to-CSR conversion gives for the unique edges of
:func:`.quality.unique_edges` entered both ways (sorted rows, a repeated entry summed: 2.0 on the diagonal for
the edge a degenerate face has from a vertex to itself).

Each round does, element by element, that code's IEEE operations in its order: the vertex normals of
:func:`._quality_kernels.unit_vertex_normals`, scipy's CSR product ``A @ V`` (each row's entries summed in
storage order from 0.0, each stored value times the coordinate), the division by the degree, the normal part
removed with np.einsum's row dot (:func:`._vector_kernels.dot3`) and the step added to the free rows.
tests/geometry/test_laplacian.py checks it against the numpy code.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ._quality_kernels import unit_vertex_normals
from ._vector_kernels import dot3

__all__ = ["adjacency_arrays", "tangential_umbrella_rounds"]


@njit(cache=True)
def adjacency_arrays(F, n):
    """(data, indices, indptr) of the (n, n) CSR adjacency of F (m, 3) int64 with indices in [0, n).

    The unique undirected edges (a <= b) in the order of the keys a n + b are entered as (a, b) and (b, a); taken
    in that order, every row's columns come out ascending (the (y, r) with y < r before the (r, x) with x >= r).
    """
    m = F.shape[0]
    keys = np.empty(3 * m, np.int64)
    for f in range(m):
        for c in range(3):
            a, b = F[f, c], F[f, (c + 1) % 3]
            keys[3 * f + c] = min(a, b) * n + max(a, b)
    keys = np.unique(keys)
    counts = np.zeros(n + 1, np.int64)
    for key in keys:
        a, b = key // n, key % n
        counts[a + 1] += 1
        if b != a:
            counts[b + 1] += 1
    indptr = np.cumsum(counts)
    fill = indptr[:-1].copy()
    indices = np.empty(indptr[n], np.int64)
    data = np.empty(indptr[n])
    for key in keys:
        a, b = key // n, key % n
        indices[fill[a]], data[fill[a]] = b, 2.0 if a == b else 1.0
        fill[a] += 1
        if b != a:
            indices[fill[b]], data[fill[b]] = a, 1.0
            fill[b] += 1
    return data, indices, indptr


@njit(cache=True)
def tangential_umbrella_rounds(V, F, data, indptr, indices, free, iterations, step):
    """``iterations`` rounds of tangential umbrella smoothing of the rows ``free`` of V, in place.

    Parameters
    ----------
    V : (n, 3) float64, C-contiguous
    F : (m, 3) int64  valid indices
    data, indptr, indices : the CSR arrays of the (n, n) adjacency of F (:func:`adjacency_arrays`)
    free : (s,) int64  the vertices that move
    iterations : int
    step : float
    """
    n = V.shape[0]
    degree = np.ones(n)  # max(A.sum(axis=1), 1): whole numbers
    for v in free:
        total = 0.0
        for p in range(indptr[v], indptr[v + 1]):
            total += data[p]
        degree[v] = max(total, 1.0)
    D = V.copy()  # only the free rows are written and read
    for _ in range(iterations):
        N = unit_vertex_normals(V, F, n)
        for v in free:
            for c in range(3):
                s = 0.0
                for p in range(indptr[v], indptr[v + 1]):
                    s += data[p] * V[indices[p], c]
                D[v, c] = s / degree[v] - V[v, c]
            along = dot3((D[v, 0], D[v, 1], D[v, 2]), (N[v, 0], N[v, 1], N[v, 2]))
            for c in range(3):
                D[v, c] = D[v, c] - along * N[v, c]
        for v in free:
            for c in range(3):
                V[v, c] = V[v, c] + step * D[v, c]
