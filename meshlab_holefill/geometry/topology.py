"""Edge topology of small face lists (patches): half-edge twins, interior edges, 1-rings."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["interior_edges", "one_ring_matrix", "undirected_keys", "edge_pair_set", "face_adjacency"]


def interior_edges(F, n):
    """Interior (two-face) edges of a consistently oriented face list.

    Returns
    -------
    edges : (e, 2) int64
        (a, b) as traversed by face ``f1``.
    f1, c1 : (e,) int64
        Face holding half-edge a -> b and the corner index of ``a`` in it.
    f2, c2 : (e,) int64
        Face holding the twin half-edge b -> a and the corner index of ``b`` in it.
    """
    F = np.asarray(F, np.int64)
    a = F.ravel()
    b = np.roll(F, -1, axis=1).ravel()
    key = a * n + b
    twin_key = b * n + a
    order = np.argsort(key)
    pos = np.searchsorted(key[order], twin_key)
    pos = np.minimum(pos, len(key) - 1)
    has = key[order][pos] == twin_key
    he = np.flatnonzero(has & (a < b))
    tw = order[pos[he]]
    return (np.stack([a[he], b[he]], axis=1), he // 3, he % 3, tw // 3, tw % 3)


def one_ring_matrix(F, n):
    """Symmetric sparse (n, n) adjacency of vertices sharing an edge (CSR, ones)."""
    F = np.asarray(F, np.int64)
    i = np.concatenate([F[:, 0], F[:, 1], F[:, 2], F[:, 1], F[:, 2], F[:, 0]])
    j = np.concatenate([F[:, 1], F[:, 2], F[:, 0], F[:, 0], F[:, 1], F[:, 2]])
    A = sp.coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n)).tocsr()
    A.data[:] = 1.0
    return A


def undirected_keys(E, n):
    """One int64 key per undirected edge: min * n + max, (e,) for E : (e, 2) int with indices < n."""
    E = np.sort(np.asarray(E, np.int64).reshape(-1, 2), axis=1)
    return E[:, 0] * n + E[:, 1]


def edge_pair_set(E):
    """Set of sorted (a, b) tuples of an edge list E : (e, 2), for O(1) membership in Python loops."""
    return {tuple(e) for e in np.sort(np.asarray(E, np.int64).reshape(-1, 2), axis=1).tolist()}


def face_adjacency(F):
    """Faces sharing an edge, as a symmetric sparse matrix.

    Parameters
    ----------
    F : (m, 3) int

    Returns
    -------
    (m, m) scipy.sparse CSR float64, 1 where two faces share an edge
    """
    F = np.asarray(F, np.int64)
    m = len(F)
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    keys = E[:, 0] * (F.max() + 1) + E[:, 1]
    order = np.argsort(keys)
    ks = keys[order]
    same = np.flatnonzero(ks[1:] == ks[:-1])
    a, b = order[same] % m, order[same + 1] % m
    return sp.coo_matrix((np.ones(2 * len(a)), (np.r_[a, b], np.r_[b, a])), shape=(m, m)).tocsr()
