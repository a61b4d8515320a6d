"""Compiled normal equations of the least-squares mesh (E_AREA with the loop's rows, :mod:`.embedding`, Sec. 3.3).

:func:`area_normal_equations` builds, from the faces and the free vertices, the matrix
R_f^T R_f and the right-hand side -R_f^T R_c X_c that :func:`.embedding.minimise_embedding_energy`
forms with scipy from :func:`.embedding.energy_rows` (``order=1, anchors=True``), the same
numbers to the last bit: every sum is taken in the order scipy's sparse products take it
(R_c X_c column by column, R_f^T's rows in storage order, the product's entries accumulated over
R's rows in increasing order from zero, exact zeros dropped). Measured on the benchmark's 45 cut
holes: scipy's construction (the operator over every vertex of the surroundings, row and column
indexing, two conversions and two products) took about as long as the factorisations of these
small systems.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ._tangential_kernels import _free_neighbours

__all__ = ["area_normal_equations"]


@njit(cache=True)
def _sort_pairs(keys, values, lo, hi):
    """Sort keys[lo:hi] in place, values along (a vertex's 1-ring: a few entries)."""
    for i in range(lo + 1, hi):
        k, v, j = keys[i], values[i], i - 1
        while j >= lo and keys[j] > k:
            keys[j + 1], values[j + 1] = keys[j], values[j]
            j -= 1
        keys[j + 1], values[j + 1] = k, v


@njit(cache=True)
def _residual_rows(free, start, buf, degree):
    """Row of each vertex in R (-1: none): the free vertices in order, then the fixed ones with a free neighbour."""
    n = free.shape[0]
    row = np.full(n, -1, np.int64)
    k = 0
    for p in range(n):
        if free[p]:
            row[p] = k
            k += 1
    for p in range(n):
        if not free[p]:
            for e in range(start[p], start[p] + degree[p]):
                if free[buf[e]]:
                    row[p] = k
                    k += 1
                    break
    return row, k


@njit(cache=True)
def _free_columns(free, row, start, buf, degree, inverse, diagonal, nf):
    """R_f in CSC (column i: free vertex i's rows, increasing) and in CSR (row k: its free columns, increasing)."""
    n = free.shape[0]
    vertex = np.empty(nf, np.int64)
    for p in range(n):
        if free[p]:
            vertex[row[p]] = p
    colptr = np.zeros(nf + 1, np.int64)
    for i in range(nf):
        q = vertex[i]
        count = 1 if degree[q] > 0 else 0
        for e in range(start[q], start[q] + degree[q]):
            if row[buf[e]] >= 0:
                count += 1
        colptr[i + 1] = colptr[i] + count
    rows, vals = np.empty(colptr[nf], np.int64), np.empty(colptr[nf])
    for i in range(nf):  # R[k, q] is stored where q is vertex k or in its 1-ring (the 1-rings are symmetric)
        q, k = vertex[i], colptr[i]
        if degree[q] > 0:
            rows[k], vals[k] = row[q], diagonal[q]
            k += 1
        for e in range(start[q], start[q] + degree[q]):
            p = buf[e]
            if row[p] >= 0:
                rows[k], vals[k] = row[p], inverse[p]
                k += 1
        _sort_pairs(rows, vals, colptr[i], colptr[i + 1])
    n_rows = 0
    for p in range(n):
        if row[p] >= 0:
            n_rows += 1
    rowptr = np.zeros(n_rows + 1, np.int64)
    for e in range(colptr[nf]):
        rowptr[rows[e] + 1] += 1
    for k in range(n_rows):
        rowptr[k + 1] += rowptr[k]
    cols, cvals = np.empty(colptr[nf], np.int64), np.empty(colptr[nf])
    fill = rowptr[:n_rows].copy()
    for i in range(nf):
        for e in range(colptr[i], colptr[i + 1]):
            cols[fill[rows[e]]], cvals[fill[rows[e]]] = i, vals[e]
            fill[rows[e]] += 1
    return colptr, rows, vals, rowptr, cols, cvals


@njit(cache=True)
def _add_fixed(b, k, a, X, j, free):
    """b[k] += a X[j] when column j is fixed (one term of R_c X_c)."""
    if not free[j]:
        for d in range(X.shape[1]):
            b[k, d] += a * X[j, d]


@njit(cache=True)
def _fixed_part(X, free, row, n_rows, start, buf, degree, inverse, diagonal):
    """-(R_c X_c), (rows, 3): each row's fixed columns in increasing order, summed from zero."""
    b = np.zeros((n_rows, X.shape[1]))
    for p in range(free.shape[0]):
        k = row[p]
        if k < 0 or degree[p] == 0:
            continue
        own = False  # the vertex's own column, in its place among its 1-ring's
        for e in range(start[p], start[p] + degree[p]):
            if not own and buf[e] > p:
                _add_fixed(b, k, diagonal[p], X, p, free)
                own = True
            _add_fixed(b, k, inverse[p], X, buf[e], free)
        if not own:
            _add_fixed(b, k, diagonal[p], X, p, free)
    return -b


@njit(cache=True)
def _gram(colptr, rows, vals, rowptr, cols, cvals, nf):
    """R_f^T R_f in CSC: entry (i, j) summed over R's rows in increasing order from zero, exact zeros left out.

    Row i of the product is accumulated as scipy's sparse product does (its entries in the order
    they are met), then the rows are transposed into columns as scipy's conversion to CSC does
    (each column's rows increasing).
    """
    bound = 0
    for i in range(nf):
        for e in range(colptr[i], colptr[i + 1]):
            bound += rowptr[rows[e] + 1] - rowptr[rows[e]]
    row_ptr = np.zeros(nf + 1, np.int64)
    row_cols = np.empty(bound, np.int64)
    row_vals = np.empty(bound)
    sums = np.zeros(nf)
    mark = np.full(nf, -1, np.int64)
    touched = np.empty(nf, np.int64)
    nnz = 0
    for i in range(nf):
        count = 0
        for e in range(colptr[i], colptr[i + 1]):
            v, k = vals[e], rows[e]
            for kk in range(rowptr[k], rowptr[k + 1]):
                j = cols[kk]
                if mark[j] != i:
                    mark[j], sums[j] = i, 0.0
                    touched[count] = j
                    count += 1
                sums[j] += v * cvals[kk]
        for t in range(count):
            j = touched[t]
            if sums[j] != 0.0:
                row_cols[nnz], row_vals[nnz] = j, sums[j]
                nnz += 1
        row_ptr[i + 1] = nnz
    indptr = np.zeros(nf + 1, np.int64)
    for e in range(nnz):
        indptr[row_cols[e] + 1] += 1
    for j in range(nf):
        indptr[j + 1] += indptr[j]
    indices, data = np.empty(nnz, np.int32), np.empty(nnz)
    fill = indptr[:nf].copy()
    for i in range(nf):
        for e in range(row_ptr[i], row_ptr[i + 1]):
            j = row_cols[e]
            indices[fill[j]], data[fill[j]] = i, row_vals[e]
            fill[j] += 1
    return indptr, indices, data


@njit(cache=True)
def area_normal_equations(F, free, X):
    """Normal equations of the least-squares mesh over the free vertices, as scipy builds them.

    Parameters
    ----------
    F : (t, 3) int64  faces (the patch joined to its surroundings)
    free : (n,) bool  the interior vertices P_Int
    X : (n, 3) float64  positions (the free rows are not read)

    Returns
    -------
    ok : bool
        False for no face, a face repeating a vertex, no free vertex or no fixed row (R_f square):
        the caller takes scipy's general construction.
    indptr, indices, data : CSC arrays of R_f^T R_f (f, f), f = free.sum()
    rhs : (f, 3) float64  -R_f^T R_c X_c
    """
    n = X.shape[0]
    nothing = (False, np.zeros(1, np.int64), np.zeros(0, np.int32), np.zeros(0), np.zeros((0, X.shape[1])))
    if F.shape[0] == 0:
        return nothing
    start, buf, degree = _free_neighbours(F, np.arange(n), n)
    if start[0] < 0:
        return nothing
    inverse, diagonal = np.zeros(n), np.zeros(n)
    for p in range(n):
        if degree[p] > 0:
            inverse[p] = 1.0 / max(float(degree[p]), 1.0)
            diagonal[p] = inverse[p] * -float(degree[p])
    row, n_rows = _residual_rows(free, start, buf, degree)
    nf = 0
    for p in range(n):
        if free[p]:
            nf += 1
    if nf == 0 or n_rows == nf:
        return nothing
    colptr, rows, vals, rowptr, cols, cvals = _free_columns(free, row, start, buf, degree, inverse, diagonal, nf)
    b = _fixed_part(X, free, row, n_rows, start, buf, degree, inverse, diagonal)
    rhs = np.zeros((nf, X.shape[1]))
    for i in range(nf):  # R_f^T b: column i's entries in storage order
        for e in range(colptr[i], colptr[i + 1]):
            for d in range(X.shape[1]):
                rhs[i, d] += vals[e] * b[rows[e], d]
    indptr, indices, data = _gram(colptr, rows, vals, rowptr, cols, cvals, nf)
    return True, indptr, indices, data, rhs
