"""Edge topology of small face lists (patches): half-edge twins, interior edges, 1-rings."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ._flip_kernels import _interior_edges as _interior_edge_table

__all__ = ["boundary_edges_and_chords", "interior_edges", "interior_edges_numpy", "one_ring_matrix", "undirected_keys", "edge_pair_set",
           "face_adjacency", "vertex_face_runs"]


def boundary_edges_and_chords(k, forbidden_edges):
    """(k + p, 2) int64: a hole loop's edges (i, i + 1) and the boundary pairs already joined by the mesh.

    The edges of a patch no swap may touch, in loop indices.
    """
    loop_edges = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    return np.concatenate([loop_edges, np.asarray(forbidden_edges, np.int64).reshape(-1, 2)])


def interior_edges(F, n):
    """Interior (two-face) edges of a consistently oriented face list, in the order of their half-edges a -> b, a < b.

    From the compiled half-edge table (:func:`._flip_kernels._interior_edges`); where a directed
    edge repeats or an index is out of range, by :func:`interior_edges_numpy`, whose answer it is.

    Returns
    -------
    edges : (e, 2) int64
        (a, b) as traversed by face ``f1``.
    f1, c1 : (e,) int64
        Face holding half-edge a -> b and the corner index of ``a`` in it.
    f2, c2 : (e,) int64
        Face holding the twin half-edge b -> a and the corner index of ``b`` in it.
    """
    F = np.ascontiguousarray(F, np.int64)
    if F.ndim != 2 or F.shape[1] != 3:
        return interior_edges_numpy(F, n)
    he, tw, _, _, _, ok = _interior_edge_table(F, n)
    if not ok:
        return interior_edges_numpy(F, n)
    f1, c1 = he // 3, he % 3
    return np.stack([F[f1, c1], F[f1, (c1 + 1) % 3]], axis=1), f1, c1, tw // 3, tw % 3


def interior_edges_numpy(F, n):
    """:func:`interior_edges` by sorting the half-edge keys a * n + b (the reference of the compiled table)."""
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


def vertex_face_runs(F, n):
    """The faces at each vertex, ascending (a face once per corner at it), as runs of one array.

    What ``for f, tri in enumerate(F.tolist()): for v in tri: incident[v].append(f)`` lists,
    without the m row lists of ``tolist``, whose allocations set off the garbage collector's
    scans of the whole heap in the per-hole loops.

    Parameters
    ----------
    F : (m, 3) int, indices < n
    n : int

    Returns
    -------
    faces : (3 m,) int64
        faces[start[v]:start[v + 1]] are vertex v's faces.
    start : (n + 1,) int64
    """
    flat = np.asarray(F, np.int64).ravel()
    # A stable sort keeps each vertex's corners in face order.
    faces = np.argsort(flat, kind="stable") // 3
    start = np.zeros(n + 1, np.int64)
    np.cumsum(np.bincount(flat, minlength=n), out=start[1:])
    return faces, start


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
