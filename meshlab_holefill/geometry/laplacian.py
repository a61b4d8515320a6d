"""Sparse graph and cotangent Laplacians."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .quality import corner_angles, unique_edges


def adjacency_matrix(F, n):
    """Symmetric vertex adjacency (1 where an edge exists), (n, n) CSR."""
    E = unique_edges(np.asarray(F))
    data = np.ones(2 * len(E))
    A = sp.coo_matrix((data, (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])), shape=(n, n))
    return A.tocsr()


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


def cotangent_laplacian(V, F, n=None):
    """Cotangent Laplacian L with L_ij = (cot a_ij + cot b_ij) / 2 and L_ii = -sum_j L_ij.

    (L @ V)[i] = sum_j w_ij (v_j - v_i); negative semi-definite for a well-shaped mesh.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int
    n : int, optional
        Matrix size (defaults to len(V)).

    Returns
    -------
    L : (n, n) CSR float64
    """
    n = len(V) if n is None else n
    C = cotangent_weights(V, F)
    rows, cols, vals = [], [], []
    for k in range(3):
        i, j = F[:, (k + 1) % 3], F[:, (k + 2) % 3]
        rows += [i, j]
        cols += [j, i]
        vals += [0.5 * C[:, k], 0.5 * C[:, k]]
    W = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)).tocsr()
    deg = np.asarray(W.sum(axis=1)).ravel()
    return (W - sp.diags(deg)).tocsr()
