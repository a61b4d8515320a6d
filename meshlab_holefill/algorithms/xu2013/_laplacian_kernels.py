"""Compiled CSR construction of the normalised cotangent Laplacian (:func:`.poisson_patch.normalized_cotangent_laplacian`).

The two kernels build, entry for entry, the arrays scipy's construction (a COO to CSR
conversion summing duplicates, two sparse differences with diagonal matrices) leaves: the
same stored entries, in the same order (columns increasing within a row), with the same
values. Every later slice, product and factorisation then sees the identical matrix, and the
construction no longer takes most of a patch's Laplacian time.

An edge's weight is the sum of its (at most two) faces' half cotangents: a sum of two
numbers does not depend on their order, so it is bit for bit scipy's. Meshes where an edge
has more faces, or a face repeats a vertex, are left to scipy (``ok`` False).
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["edge_weight_rows", "with_unit_diagonal"]


@njit(cache=True)
def edge_weight_rows(F, half, n):
    """Off-diagonal entries of W, W_ij = sum of half[f, k] over the faces' corners k opposite edge ij.

    Parameters
    ----------
    F : (m, 3) int64
    half : (m, 3) float64  half the corner cotangents
    n : int  rows (> every vertex id)

    Returns
    -------
    ok : bool  False when an edge has more than two faces or a face repeats a vertex
    indptr : (n + 1,) int64
    indices : (e,) int64  columns increasing within each row
    data : (e,) float64  W_ij; entries whose sum is 0 are left out, as a sparse difference drops them
    """
    m = F.shape[0]
    start = np.zeros(n + 1, np.int64)
    for f in range(m):
        for k in range(3):
            i, j = F[f, (k + 1) % 3], F[f, (k + 2) % 3]
            if i == j:
                return False, start, np.zeros(0, np.int64), np.zeros(0)
            start[i + 1] += 1
            start[j + 1] += 1
    for r in range(n):
        start[r + 1] += start[r]
    fill = start[:n].copy()
    cols = np.empty(start[n], np.int64)
    vals = np.empty(start[n])
    for f in range(m):
        for k in range(3):
            i, j = F[f, (k + 1) % 3], F[f, (k + 2) % 3]
            cols[fill[i]], vals[fill[i]] = j, half[f, k]
            fill[i] += 1
            cols[fill[j]], vals[fill[j]] = i, half[f, k]
            fill[j] += 1
    indptr = np.zeros(n + 1, np.int64)
    out = 0
    for r in range(n):
        a, b = start[r], start[r + 1]
        for s in range(a + 1, b):  # rows are short: insertion sort by column
            c, v, t = cols[s], vals[s], s
            while t > a and cols[t - 1] > c:
                cols[t], vals[t] = cols[t - 1], vals[t - 1]
                t -= 1
            cols[t], vals[t] = c, v
        s = a
        while s < b:
            total, e = vals[s], s + 1
            if e < b and cols[e] == cols[s]:
                total += vals[e]
                e += 1
                if e < b and cols[e] == cols[s]:
                    return False, start, np.zeros(0, np.int64), np.zeros(0)
            if total != 0.0:
                cols[out], vals[out] = cols[s], total
                out += 1
            s = e
        indptr[r + 1] = out
    return True, indptr, cols[:out].copy(), vals[:out].copy()


@njit(cache=True)
def with_unit_diagonal(indptr, indices, data, has):
    """CSR arrays of W - diags(has) for W without diagonal entries: -1 inserted where ``has``, zeros left out.

    Parameters
    ----------
    indptr : (n + 1,) int64, indices : (e,) int64, data : (e,) float64  W, columns increasing in each row
    has : (n,) bool

    Returns
    -------
    indptr : (n + 1,) int64, indices : (e2,) int64, data : (e2,) float64
    """
    n = has.shape[0]
    out_ptr = np.zeros(n + 1, np.int64)
    out_idx = np.empty(indices.shape[0] + n, np.int64)
    out_val = np.empty(indices.shape[0] + n)
    out = 0
    for r in range(n):
        diagonal = has[r]
        for s in range(indptr[r], indptr[r + 1]):
            if diagonal and indices[s] > r:
                out_idx[out], out_val[out] = r, -1.0
                out += 1
                diagonal = False
            if data[s] != 0.0:
                out_idx[out], out_val[out] = indices[s], data[s]
                out += 1
        if diagonal:
            out_idx[out], out_val[out] = r, -1.0
            out += 1
        out_ptr[r + 1] = out
    return out_ptr, out_idx[:out].copy(), out_val[:out].copy()
