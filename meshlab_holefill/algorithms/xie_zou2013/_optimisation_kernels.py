"""Compiled kernel of the decimation of Sec. 4.7 (numba): the independent set of edges collapsed in one round.

Integer logic only, so the result is exactly that of the sparse-matrix expression it replaces
(tests/algorithms/xie_zou2013/test_de_kernels.py checks it against that expression).
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["independent_link_edges"]


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
