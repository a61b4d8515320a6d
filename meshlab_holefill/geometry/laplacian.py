"""Sparse graph and cotangent Laplacians."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ._laplacian_kernels import adjacency_arrays, tangential_umbrella_rounds
from .quality import corner_angles, unique_edges, vertex_normals

__all__ = ["adjacency_matrix", "adjacency_matrix_numpy", "tangential_umbrella_smoothing",
           "tangential_umbrella_smoothing_numpy", "uniform_laplacian", "cotangent_weights", "cotangent_laplacian",
           "lowest_dirichlet_frequency", "vertices_near"]


def _faces_within(F, n):
    """Whether F is an (m, 3) integer array with every index in [0, n): what the kernels index without checks."""
    return F.ndim == 2 and F.shape[1] == 3 and F.dtype.kind in "iu" and (not len(F) or (F.min() >= 0 and F.max() < n))


def adjacency_matrix(F, n):
    """Symmetric vertex adjacency (1 where an edge exists), (n, n) CSR.

    Built compiled (:func:`._laplacian_kernels.adjacency_arrays`: the arrays of :func:`adjacency_matrix_numpy`).
    """
    F = np.asarray(F)
    if len(F) and _faces_within(F, n) and n < np.iinfo(np.int32).max // 4:
        data, indices, indptr = adjacency_arrays(np.ascontiguousarray(F, np.int64), int(n))
        return sp.csr_matrix((data, indices.astype(np.int32), indptr.astype(np.int32)), shape=(n, n))
    return adjacency_matrix_numpy(F, n)  # no faces, other shapes and types, numpy's errors


def adjacency_matrix_numpy(F, n):
    """:func:`adjacency_matrix` by scipy's COO-to-CSR conversion (the reference of the compiled arrays)."""
    E = unique_edges(np.asarray(F))
    data = np.ones(2 * len(E))
    A = sp.coo_matrix((data, (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])), shape=(n, n))
    return A.tocsr()


def tangential_umbrella_smoothing(V, F, fixed, iterations, step=0.5):
    """Move the free vertices toward the mean of their neighbours within their tangent planes.

    x += step * (I - n n^T) (mean of neighbours - x) for every free vertex, ``iterations``
    times, n the area-weighted vertex normal of the current positions. Evens out triangles
    while leaving the shape (the normal component of the positions) alone to first order.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int
    fixed : (n,) bool  vertices that stay put
    iterations : int
    step : float  fraction of the tangential umbrella vector applied per iteration

    Returns
    -------
    (n, 3) float64  a copy

    The rounds are compiled (:func:`._laplacian_kernels.tangential_umbrella_rounds`, the bits of
    :func:`tangential_umbrella_smoothing_numpy`).
    """
    V = np.array(V, np.float64)
    free = ~np.asarray(fixed, bool)
    if iterations <= 0 or not free.any():
        return V
    F = np.asarray(F)
    if free.shape != (len(V),) or not _faces_within(F, len(V)):
        return tangential_umbrella_smoothing_numpy(V, F, fixed, iterations, step)  # numpy's errors, other shapes
    A = adjacency_matrix(F, len(V))
    tangential_umbrella_rounds(V, np.ascontiguousarray(F, np.int64), A.data, A.indptr.astype(np.int64),
                               A.indices.astype(np.int64), np.flatnonzero(free), int(iterations), float(step))
    return V


def tangential_umbrella_smoothing_numpy(V, F, fixed, iterations, step=0.5):
    """:func:`tangential_umbrella_smoothing` in numpy and scipy (the reference of the compiled rounds)."""
    V = np.array(V, np.float64)
    free = ~np.asarray(fixed, bool)
    if iterations <= 0 or not free.any():
        return V
    A = adjacency_matrix(F, len(V))
    degree = np.maximum(np.asarray(A.sum(axis=1)).ravel(), 1)
    for _ in range(iterations):
        N = vertex_normals(V, F, len(V))
        D = (A @ V) / degree[:, None] - V
        D -= np.einsum("ij,ij->i", D, N)[:, None] * N
        V[free] += step * D[free]
    return V


def uniform_laplacian(F, n):
    """Umbrella operator L = A - D, so that (L @ V)[i] = sum_j (v_j - v_i) over neighbours j.

    Parameters
    ----------
    F : (m, 3) int
    n : int
        Number of vertices.

    Returns
    -------
    L : (n, n) CSR float64
    """
    A = adjacency_matrix(F, n)
    deg = np.asarray(A.sum(axis=1)).ravel()
    return (A - sp.diags(deg)).tocsr()


def cotangent_weights(V, F):
    """Per-face cotangents of the three corner angles, (m, 3): column k is cot of the angle at F[:, k]."""
    angles = corner_angles(V, F)
    return np.cos(angles) / np.maximum(np.sin(angles), 1e-300)


def cotangent_laplacian(V, F, n=None, cotangents=None):
    """Cotangent Laplacian L with L_ij = (cot a_ij + cot b_ij) / 2 and L_ii = -sum_j L_ij.

    (L @ V)[i] = sum_j w_ij (v_j - v_i); negative semi-definite for a well-shaped mesh.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int
    n : int, optional
        Matrix size (defaults to len(V)).
    cotangents : (m, 3) float64, optional
        The faces' corner cotangents (:func:`cotangent_weights`) to use instead of those of V,
        e.g. of the same triangles laid out in another embedding.

    Returns
    -------
    L : (n, n) CSR float64
    """
    n = len(V) if n is None else n
    C = cotangent_weights(V, F) if cotangents is None else cotangents
    rows, cols, vals = [], [], []
    for k in range(3):
        i, j = F[:, (k + 1) % 3], F[:, (k + 2) % 3]
        rows += [i, j]
        cols += [j, i]
        vals += [0.5 * C[:, k], 0.5 * C[:, k]]
    W = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)).tocsr()
    deg = np.asarray(W.sum(axis=1)).ravel()
    return (W - sp.diags(deg)).tocsr()


def lowest_dirichlet_frequency(F, n, free, adjacency=None):
    """Smallest eigenvalue of the umbrella operator K = I - D^-1 A on the free vertices.

    With the other vertices held fixed (a Dirichlet boundary), ``free`` vertices evolve under
    umbrella smoothing x <- x - t K x, whose eigenvalues ("frequencies", Taubin 1995) lie in
    (0, 2]; the lowest one belongs to the smoothest shape the free vertices can take over the
    fixed boundary. K is similar to the symmetric D^-1/2 (D - A) D^-1/2 restricted to the free
    vertices, whose spectrum is computed instead; its diagonal is 1, so the lowest frequency is
    at most 1.

    Parameters
    ----------
    F : (m, 3) int
    n : int  number of vertices
    free : (n,) bool
    adjacency : (n, n) sparse, optional  :func:`adjacency_matrix` of F, if the caller has it

    Returns
    -------
    float  the lowest frequency (nan when there is no free vertex)
    """
    free = np.flatnonzero(np.asarray(free, bool))
    if len(free) == 0:
        return float("nan")
    A = adjacency_matrix(F, n) if adjacency is None else adjacency
    deg = np.maximum(np.asarray(A.sum(axis=1)).ravel()[free], 1.0)
    scale = sp.diags(1.0 / np.sqrt(deg))
    S = (sp.identity(len(free)) - scale @ A[free][:, free] @ scale).tocsc()
    if len(free) <= 400:
        return float(np.linalg.eigvalsh(S.toarray())[0])
    from scipy.sparse.linalg import eigsh

    # Shift-invert about 0: S is positive definite when every free component touches the boundary.
    return float(eigsh(S, k=1, sigma=0.0, which="LM", return_eigenvectors=False)[0])


def vertices_near(F, n, faces, rings):
    """Vertices of ``faces`` and those within ``rings`` edges of them, as an (n,) bool mask.

    Parameters
    ----------
    F : (m, 3) int
    n : int
        Vertex count.
    faces : (m,) bool or (k,) int
        The faces to start from (e.g. triangles below a quality floor).
    rings : int
    """
    A = adjacency_matrix(F, n)
    region = np.zeros(n, bool)
    region[F[faces].ravel()] = True
    for _ in range(rings):
        region |= (A @ region.astype(np.float64)) > 0
    return region
