"""Per-triangle measures: areas, normals, angles and the 2r/R quality of Field (2000)."""
from __future__ import annotations

import numpy as np

from ._quality_kernels import face_normals_kernel, triangle_quality_kernel, vertex_normals_kernel

__all__ = ["cross_rows", "face_normals", "face_areas", "vertex_normals", "edge_lengths", "triangle_quality",
           "corner_angles", "corner_sums", "unique_edges", "mean_edge_length"]


def cross_rows(a, b):
    """Cross products of (..., 3) arrays along the last axis, broadcasting like np.cross.

    The same arithmetic as np.cross (bit-identical results), without its axis handling, which
    dominates on the small arrays the per-hole loops use.
    """
    out = np.empty(np.broadcast_shapes(np.shape(a), np.shape(b)))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def face_normals(V, F, normalize=True):
    """Face normals from the right-hand rule.

    Compiled (:func:`._quality_kernels.face_normals_kernel`, the bits of :func:`face_normals_numpy`):
    the per-hole loops call it thousands of times on a few hundred faces.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int
    normalize : bool
        If False, return cross products (length = twice the area).

    Returns
    -------
    N : (m, 3) float64
        Zero rows for degenerate faces when normalised.
    """
    V_arr, F_arr = np.asarray(V, dtype=np.float64), np.asarray(F)
    if _kernel_shapes(V_arr, F_arr):
        N, ok = face_normals_kernel(np.ascontiguousarray(V_arr), np.ascontiguousarray(F_arr, np.int64),
                                    bool(normalize))
        if ok:
            return N
    return face_normals_numpy(V_arr, F_arr, normalize)  # other shapes, and the IndexError of a bad index


def face_normals_numpy(V, F, normalize=True):
    """:func:`face_normals` in numpy (the reference of the compiled kernel)."""
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F)
    N = cross_rows(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    if not normalize:
        return N
    lengths = np.linalg.norm(N, axis=1)
    out = np.zeros_like(N)
    ok = lengths > 0
    out[ok] = N[ok] / lengths[ok, None]
    return out


def _kernel_shapes(V, F):
    """Whether the compiled kernels take V and F: (n, 3) floats and (m, 3) integers."""
    return V.ndim == 2 and V.shape[1] == 3 and F.ndim == 2 and F.shape[1] == 3 and F.dtype.kind in "iu"


def face_areas(V, F):
    """Triangle areas, (m,) float64."""
    return 0.5 * np.linalg.norm(face_normals(V, F, normalize=False), axis=1)


def vertex_normals(V, F, n_vertices=None):
    """Area-weighted vertex normals (sum of face cross products), unit length.

    Vertices without faces get a zero normal. Compiled
    (:func:`._quality_kernels.vertex_normals_kernel`, the bits of :func:`vertex_normals_numpy`).

    Returns
    -------
    N : (n, 3) float64
    """
    n = len(V) if n_vertices is None else n_vertices
    V_arr, F_arr = np.asarray(V, dtype=np.float64), np.asarray(F)
    if _kernel_shapes(V_arr, F_arr):
        N, ok = vertex_normals_kernel(np.ascontiguousarray(V_arr), np.ascontiguousarray(F_arr, np.int64), int(n))
        if ok:
            return N
    return vertex_normals_numpy(V_arr, F_arr, n)


def vertex_normals_numpy(V, F, n_vertices=None):
    """:func:`vertex_normals` in numpy (the reference of the compiled kernel)."""
    n = len(V) if n_vertices is None else n_vertices
    C = face_normals_numpy(V, F, normalize=False)
    N = corner_sums(F, C, n)
    lengths = np.linalg.norm(N, axis=1)
    ok = lengths > 0
    N[ok] /= lengths[ok, None]
    return N


def corner_sums(F, C, n):
    """Sum of the face rows C (m, 3) at each face's three corners, (n, 3).

    The additions of ``np.add.at(N, F[:, k], C)`` for k = 0, 1, 2 in the same order (bincount
    adds its weights in input order too), so the same bits, without add.at's slow loop.
    """
    index = np.asarray(F, np.int64).T.ravel()
    W = np.concatenate([C, C, C])
    return np.stack([np.bincount(index, weights=W[:, c], minlength=n) for c in range(3)], axis=1)


def edge_lengths(V, F):
    """Lengths of the edges opposite each corner: column k is |V[F[:,k+1]] - V[F[:,k+2]]|, (m, 3)."""
    V = np.asarray(V, dtype=np.float64)
    a = np.linalg.norm(V[F[:, 1]] - V[F[:, 2]], axis=1)
    b = np.linalg.norm(V[F[:, 2]] - V[F[:, 0]], axis=1)
    c = np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1)
    return np.stack([a, b, c], axis=1)


def triangle_quality(V, F):
    """Field's quality 2r/R (twice inradius over circumradius), as used by Hu et al. Sec. IV.

    Equals 1 for an equilateral triangle and 0 for a degenerate one. Compiled
    (:func:`._quality_kernels.triangle_quality_kernel`, the same bits as
    :func:`triangle_quality_numpy`): the per-hole loops call it thousands of times on a few faces.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int

    Returns
    -------
    q : (m,) float64 in [0, 1]
    """
    F_arr = np.asarray(F)
    V_arr = np.asarray(V, dtype=np.float64)
    if F_arr.ndim == 2 and F_arr.shape[1] == 3 and V_arr.ndim == 2 and V_arr.shape[1] == 3 \
            and F_arr.dtype.kind in "iu":
        q, ok = triangle_quality_kernel(np.ascontiguousarray(V_arr), np.ascontiguousarray(F_arr, np.int64))
        if ok:
            return q
    return triangle_quality_numpy(V_arr, F_arr)  # other shapes, and the IndexError of a bad index


def triangle_quality_numpy(V, F):
    """:func:`triangle_quality` in numpy (the reference of the compiled kernel)."""
    # One gather of the corners; the same arithmetic as edge_lengths and face_areas.
    P = np.asarray(V, dtype=np.float64)[np.asarray(F)]
    a, b, c = P[:, 1] - P[:, 2], P[:, 2] - P[:, 0], P[:, 0] - P[:, 1]
    L = np.sqrt(np.stack([(a * a).sum(axis=1), (b * b).sum(axis=1), (c * c).sum(axis=1)], axis=1))
    N = cross_rows(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    area = 0.5 * np.sqrt((N * N).sum(axis=1))
    # r = 2A / (a+b+c), R = abc / (4A)  =>  2r/R = 16 A^2 / ((a+b+c) abc)
    denom = L.sum(axis=1) * L.prod(axis=1)
    q = np.zeros(len(F))
    ok = denom > 0
    q[ok] = 16.0 * area[ok] ** 2 / denom[ok]
    return np.clip(q, 0.0, 1.0)


def corner_angles(V, F):
    """Interior angle at each corner, (m, 3) float64 radians (column k is the angle at F[:, k])."""
    V = np.asarray(V, dtype=np.float64)
    out = np.empty((len(F), 3))
    for k in range(3):
        p = V[F[:, k]]
        u = V[F[:, (k + 1) % 3]] - p
        w = V[F[:, (k + 2) % 3]] - p
        out[:, k] = np.arctan2(np.linalg.norm(cross_rows(u, w), axis=1), np.einsum("ij,ij->i", u, w))
    return out


def unique_edges(F):
    """Undirected edges of a face list, sorted per row and unique, (e, 2) int64."""
    F = np.asarray(F).astype(np.int64, copy=False).reshape(-1, 3)
    if len(F) == 0:
        return np.zeros((0, 2), np.int64)
    # One int64 key min * n + max per edge, ordered as the sorted rows are lexicographically:
    # sorting the keys is the row-wise unique without its structured-dtype sort (several times slower).
    n = int(F.max()) + 1
    G = np.roll(F, -1, axis=1)
    keys = np.sort((np.minimum(F, G) * n + np.maximum(F, G)).ravel())
    keys = keys[np.concatenate([[True], keys[1:] != keys[:-1]])]
    return np.stack([keys // n, keys % n], axis=1)


def mean_edge_length(V, F):
    """Mean length of the unique edges of F (0.0 for an empty face list)."""
    if len(F) == 0:
        return 0.0
    E = unique_edges(F)
    return float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())
