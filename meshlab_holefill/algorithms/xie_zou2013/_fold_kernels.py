"""Compiled kernel of the fold repair's swap score (numba): the agreement of face pairs.

:func:`pair_agreements` does, element by element, the IEEE operations of the numpy
``folds._pair_agreement`` in the same order (no fastmath): the unit normals of
``geometry.quality.face_normals`` (row cross product, norm, division; zero rows for
degenerate faces), the einsum dots of :mod:`meshlab_holefill.geometry._vector_kernels` and
numpy's ``minimum`` (NaN propagates). tests/algorithms/xie_zou2013/test_fold_kernels.py checks
it against the numpy code.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...geometry._vector_kernels import cross3, dot3, norm3, npmin, sub3

__all__ = ["pair_agreements", "fold_swap_scores"]


@njit(cache=True)
def _unit_normal(V, f):
    """face_normals(V, f[None])[0]: the right-hand-rule normal divided by its length, 0 if that is not > 0."""
    p0 = (V[f[0], 0], V[f[0], 1], V[f[0], 2])
    p1 = (V[f[1], 0], V[f[1], 1], V[f[1], 2])
    p2 = (V[f[2], 0], V[f[2], 1], V[f[2], 2])
    n = cross3(sub3(p1, p0), sub3(p2, p0))
    ln = norm3(n)
    if ln > 0:
        return (n[0] / ln, n[1] / ln, n[2] / ln)
    return (0.0, 0.0, 0.0)


@njit(cache=True)
def _border_agreement(f, n, border_normals):
    """folds._border_agreement of one face: the smallest dot of n with the mesh normals across its loop edges (1 if none)."""
    k = border_normals.shape[0]
    out = 1.0
    for c in range(3):
        u, v = f[c], f[(c + 1) % 3]
        if u < k and v == (u + 1) % k:
            b = (border_normals[u, 0], border_normals[u, 1], border_normals[u, 2])
            out = npmin(out, dot3(n, b))
    return out


@njit(cache=True)
def pair_agreements(V, faces, border_normals):
    """folds._pair_agreement of the face pairs (faces[2 t, i], faces[2 t + 1, i]) for each t.

    Parameters
    ----------
    V : (n, 3) float64
    faces : (2 T, s, 3) int64  T sets of pairs, first faces then second faces
    border_normals : (k, 3) float64  mesh normal across each loop edge (0 rows: no loop edges)

    Returns
    -------
    agreement : (T, s) float64
    proper : (T, s) bool  both faces non-degenerate (a non-zero unit normal)
    """
    T, s = faces.shape[0] // 2, faces.shape[1]
    agreement = np.empty((T, s))
    proper = np.empty((T, s), np.bool_)
    for t in range(T):
        for i in range(s):
            agreement[t, i], proper[t, i] = _agreement(V, faces[2 * t, i], faces[2 * t + 1, i], border_normals)
    return agreement, proper


@njit(cache=True)
def fold_swap_scores(V, old1, old2, new1, new2, border_normals):
    """(old, new): the scores of folds.unfold_by_swaps, the agreements of :func:`pair_agreements` on (s, 3) faces.

    old = the agreement of the pairs (old1[i], old2[i]); new = that of (new1[i], new2[i]) where
    old < 0 and both new faces are non-degenerate, else -inf (only folds are swapped). The
    swapped pair is scored only for the folded edges, a few of a patch's.
    """
    s = old1.shape[0]
    old = np.empty(s)
    new = np.full(s, -np.inf)
    for i in range(s):
        old[i] = _agreement(V, old1[i], old2[i], border_normals)[0]
        if old[i] < 0.0:
            agreement, proper = _agreement(V, new1[i], new2[i], border_normals)
            if proper:
                new[i] = agreement
    return old, new


@njit(cache=True)
def _agreement(V, fa, fb, border_normals):
    """(agreement, proper) of the face pair (fa, fb), as :func:`pair_agreements` computes them."""
    na, nb = _unit_normal(V, fa), _unit_normal(V, fb)
    across = npmin(_border_agreement(fa, na, border_normals), _border_agreement(fb, nb, border_normals))
    proper = (na[0] != 0 or na[1] != 0 or na[2] != 0) and (nb[0] != 0 or nb[1] != 0 or nb[2] != 0)
    return npmin(dot3(na, nb), across), proper
