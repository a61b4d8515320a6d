"""Compiled structure of the tangential relaxation's system (:func:`.tangential_relaxation.tangential_relaxation`).

:func:`free_umbrella` builds, from the faces around the free vertices, the rows of the umbrella
operator U of Sec. 3.3 for the free vertices (as :func:`.umbrella.umbrella_operator` then row
indexing stores them: entries in decreasing column order, values 1 / d and (1 / d) * -d) and the
CSC layout of the 2 x 2 block matrix over the free vertices (entries sorted by column, then
row, as scipy's COO to CSC conversion leaves them). The values that need the tangent frames stay
numpy's (:func:`.tangential_relaxation.tangential_system`), so the matrix SuperLU factorises is the same to the
last bit. Measured on the 219 systems of the benchmark's 45 cut holes (process time): scipy's
construction (an operator over every vertex of the surroundings, fancy indexing, a COO to CSC
conversion) 0.39 s against 0.53 s for their factorisations; this one 0.14 s.

:func:`faces_touching`, :func:`free_frames` (the free vertices' tangent frames), :func:`rows_times`
(U[free] @ X), :func:`frame_pairs` (the rows whose dot products are the system's values) and
:func:`face_cross` repeat numpy's and scipy's arithmetic operation for operation (sums in the
same order) or only copy: the numpy versions made a few dozen arrays per relaxation, most of its
time outside the solve on the benchmark's many small patches. The dot products themselves stay
numpy's einsum, whose order of summation depends on the processor's vector width.
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["free_umbrella", "faces_touching", "free_frames", "rows_times", "frame_pairs", "face_cross"]


@njit(cache=True)
def _insertion_sort(a, lo, hi):
    """Sort a[lo:hi] in place (segments of a few entries: a vertex's 1-ring)."""
    for i in range(lo + 1, hi):
        v, j = a[i], i - 1
        while j >= lo and a[j] > v:
            a[j + 1] = a[j]
            j -= 1
        a[j + 1] = v


@njit(cache=True)
def _free_neighbours(star, pos, s):
    """Sorted unique neighbours of each free vertex: (start, neighbours, degree); start[0] = -1 on a degenerate face."""
    start = np.zeros(s + 1, np.int64)
    for f in range(star.shape[0]):
        for k in range(3):
            a, b = star[f, k], star[f, (k + 1) % 3]
            if a == b:
                start[0] = -1
                return start, np.zeros(0, np.int64), np.zeros(0, np.int64)
            if pos[a] >= 0:
                start[pos[a] + 1] += 1
            if pos[b] >= 0:
                start[pos[b] + 1] += 1
    for r in range(s):
        start[r + 1] += start[r]
    buf = np.empty(start[s], np.int64)
    fill = start[:s].copy()
    for f in range(star.shape[0]):
        for k in range(3):
            a, b = star[f, k], star[f, (k + 1) % 3]
            if pos[a] >= 0:
                buf[fill[pos[a]]] = b
                fill[pos[a]] += 1
            if pos[b] >= 0:
                buf[fill[pos[b]]] = a
                fill[pos[b]] += 1
    degree = np.zeros(s, np.int64)
    for r in range(s):
        _insertion_sort(buf, start[r], start[r + 1])
        d = 0
        for i in range(start[r], start[r + 1]):
            if i == start[r] or buf[i] != buf[i - 1]:
                buf[start[r] + d] = buf[i]
                d += 1
        degree[r] = d
    return start, buf, degree


@njit(cache=True)
def free_umbrella(star, free, n):
    """Rows ``free`` of the umbrella operator of ``star`` and the CSC layout of the tangential system.

    Parameters
    ----------
    star : (t, 3) int64  every face touching a free vertex (so a free vertex's 1-ring is complete)
    free : (s,) int64  the free vertices
    n : int  number of vertices

    Returns
    -------
    ok : bool  False for a face repeating a vertex (the caller takes scipy's general construction)
    indptr, indices, data : the CSR arrays of U[free] (s, n)
    r, c, w : the entries of U[free][:, free] in CSC order (column c, rows r ascending), positions in ``free``
    a_indptr, a_indices : CSC layout of the (2 s, 2 s) matrix of the blocks (i, j) = U_ff * (frame_i . frame_j)
    slots : (4, f) int64  where block (i, j) = slots[2 i + j] puts entry e of (r, c, w) in that layout
    """
    s = free.shape[0]
    pos = np.full(n, -1, np.int64)
    for r in range(s):
        pos[free[r]] = r
    start, buf, degree = _free_neighbours(star, pos, s)
    e64 = np.zeros(0, np.int64)
    if start[0] < 0:
        return (False, e64, np.zeros(0, np.int32), np.zeros(0), e64, e64, np.zeros(0), e64,
                np.zeros(0, np.int32), np.zeros((4, 0), np.int64))
    inverse = np.zeros(s)
    diagonal = np.zeros(s)
    indptr = np.zeros(s + 1, np.int64)
    for r in range(s):
        if degree[r] > 0:
            inverse[r] = 1.0 / max(float(degree[r]), 1.0)
            diagonal[r] = inverse[r] * -float(degree[r])
            indptr[r + 1] = indptr[r] + degree[r] + 1
        else:
            indptr[r + 1] = indptr[r]
    indices = np.empty(indptr[s], np.int32)
    data = np.empty(indptr[s])
    colptr = np.zeros(s + 1, np.int64)
    for r in range(s):  # U[free]: the 1-ring and the vertex itself, decreasing columns
        if degree[r] == 0:
            continue
        p, k, placed = free[r], indptr[r], False
        for i in range(degree[r] - 1, -1, -1):
            q = buf[start[r] + i]
            if not placed and p > q:
                indices[k], data[k], placed = p, diagonal[r], True
                k += 1
            indices[k], data[k] = q, inverse[r]
            k += 1
        if not placed:
            indices[k], data[k] = p, diagonal[r]
        colptr[r + 1] = 1
        for i in range(degree[r]):
            if pos[buf[start[r] + i]] >= 0:
                colptr[r + 1] += 1
    for c in range(s):
        colptr[c + 1] += colptr[c]
    f = colptr[s]
    rr, cc, w = np.empty(f, np.int64), np.empty(f, np.int64), np.empty(f)
    for c in range(s):  # column c of U_ff: the free 1-ring of c and c itself (U's pattern is symmetric)
        k = colptr[c]
        for i in range(degree[c]):
            q = pos[buf[start[c] + i]]
            if q >= 0:
                rr[k] = q
                k += 1
        if colptr[c + 1] > colptr[c]:
            rr[k] = c
        _insertion_sort(rr, colptr[c], colptr[c + 1])
        for e in range(colptr[c], colptr[c + 1]):
            cc[e] = c
            w[e] = diagonal[rr[e]] if rr[e] == c else inverse[rr[e]]
    a_indptr = np.zeros(2 * s + 1, np.int64)
    a_indices = np.empty(4 * f, np.int32)
    slots = np.empty((4, f), np.int64)
    for j in range(2):
        for c in range(s):
            col = j * s + c
            count = colptr[c + 1] - colptr[c]
            a_indptr[col + 1] = a_indptr[col] + 2 * count
            for i in range(2):
                for e in range(colptr[c], colptr[c + 1]):
                    slot = a_indptr[col] + i * count + (e - colptr[c])
                    a_indices[slot] = rr[e] + i * s
                    slots[2 * i + j, e] = slot
    return True, indptr, indices, data, rr, cc, w, a_indptr, a_indices, slots


@njit(cache=True)
def _norm3(x, y, z):
    """np.linalg.norm of a row of three: the squares summed left to right."""
    return np.sqrt(x * x + y * y + z * z)


@njit(cache=True)
def free_frames(X, star, free):
    """Tangent frames of the free vertices: ``tangent_frames(vertex_normals(X, star)[free])`` of :mod:`.embedding`, bit for bit.

    The face cross products are summed at the corners in bincount's order (every face's first
    corner, then the second ones, then the third ones, from zero), normalised (a zero sum stays
    zero), and each frame is the unit cross product with the x axis (the y axis where the
    normal's x component reaches 0.9 or is NaN) and the normal's cross product with that.

    Parameters
    ----------
    X : (n, 3) float64
    star : (t, 3) int64  the faces touching a free vertex
    free : (s,) int64

    Returns
    -------
    b1, b2 : (s, 3) float64
    """
    s = free.shape[0]
    pos = np.full(X.shape[0], -1, np.int64)
    for r in range(s):
        pos[free[r]] = r
    C = face_cross(X, star)
    N = np.zeros((s, 3))
    for k in range(3):
        for f in range(star.shape[0]):
            r = pos[star[f, k]]
            if r >= 0:
                for d in range(3):
                    N[r, d] += C[f, d]
    b1, b2 = np.empty((s, 3)), np.empty((s, 3))
    for r in range(s):
        length = _norm3(N[r, 0], N[r, 1], N[r, 2])
        if not length > 0.0:
            length = 1.0
        n0, n1, n2 = N[r, 0] / length, N[r, 1] / length, N[r, 2] / length
        h0, h1, h2 = (1.0, 0.0, 0.0) if abs(n0) < 0.9 else (0.0, 1.0, 0.0)
        c0, c1, c2 = n1 * h2 - n2 * h1, n2 * h0 - n0 * h2, n0 * h1 - n1 * h0
        length = _norm3(c0, c1, c2)
        if length < 1e-300:  # np.maximum(length, 1e-300): NaN stays NaN
            length = 1e-300
        c0, c1, c2 = c0 / length, c1 / length, c2 / length
        b1[r, 0], b1[r, 1], b1[r, 2] = c0, c1, c2
        b2[r, 0], b2[r, 1], b2[r, 2] = n1 * c2 - n2 * c1, n2 * c0 - n0 * c2, n0 * c1 - n1 * c0
    return b1, b2


@njit(cache=True)
def rows_times(indptr, indices, data, X):
    """CSR rows (indptr, indices, data) times the dense X, (rows, X.shape[1]): scipy's csr_matvecs, entries in storage order."""
    rows = indptr.shape[0] - 1
    out = np.zeros((rows, X.shape[1]))
    for i in range(rows):
        for e in range(indptr[i], indptr[i + 1]):
            j, a = indices[e], data[e]
            for k in range(X.shape[1]):
                out[i, k] += a * X[j, k]
    return out


@njit(cache=True)
def faces_touching(F, free, n):
    """The rows of F with a vertex in ``free`` (n vertices), in F's order: ``F[is_free[F].any(axis=1)]``."""
    is_free = np.zeros(n, np.bool_)
    for r in range(free.shape[0]):
        is_free[free[r]] = True
    keep = np.zeros(F.shape[0], np.bool_)
    count = 0
    for f in range(F.shape[0]):
        if is_free[F[f, 0]] or is_free[F[f, 1]] or is_free[F[f, 2]]:
            keep[f] = True
            count += 1
    out = np.empty((count, 3), np.int64)
    k = 0
    for f in range(F.shape[0]):
        if keep[f]:
            out[k, 0], out[k, 1], out[k, 2] = F[f, 0], F[f, 1], F[f, 2]
            k += 1
    return out


@njit(cache=True)
def frame_pairs(b1, b2, r, c):
    """Left and right rows of the tangential system's values, (4 f, 3) each, f = len(r).

    Block k = 2 i + j (rows k f .. (k + 1) f) holds frame i at the entries' rows r and frame j at
    their columns c (frames b1, b2): its row-wise dot products, times the umbrella weights, are
    the matrix's block (i, j).
    """
    f = r.shape[0]
    left, right = np.empty((4 * f, 3)), np.empty((4 * f, 3))
    for i in range(2):
        bi = b1 if i == 0 else b2
        for j in range(2):
            bj = b1 if j == 0 else b2
            base = (2 * i + j) * f
            for e in range(f):
                for d in range(3):
                    left[base + e, d] = bi[r[e], d]
                    right[base + e, d] = bj[c[e], d]
    return left, right


@njit(cache=True)
def face_cross(X, F):
    """Unnormalised face normals, ``cross_rows(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])``, (t, 3)."""
    out = np.empty((F.shape[0], 3))
    for f in range(F.shape[0]):
        a, b, c = F[f, 0], F[f, 1], F[f, 2]
        u0, u1, u2 = X[b, 0] - X[a, 0], X[b, 1] - X[a, 1], X[b, 2] - X[a, 2]
        v0, v1, v2 = X[c, 0] - X[a, 0], X[c, 1] - X[a, 1], X[c, 2] - X[a, 2]
        out[f, 0] = u1 * v2 - u2 * v1
        out[f, 1] = u2 * v0 - u0 * v2
        out[f, 2] = u0 * v1 - u1 * v0
    return out
