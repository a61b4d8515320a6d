"""Compiled kernels of the fold tests (numba): the agreement of face pairs, and the folded faces.

:func:`pair_agreements` and :func:`folded_faces` do, element by element, the IEEE operations of the numpy
``folds._pair_agreement`` in the same order (no fastmath): the unit normals of
``geometry.quality.face_normals`` (row cross product, norm, division; zero rows for
degenerate faces), the einsum dots of :mod:`meshlab_holefill.geometry._vector_kernels` and
numpy's ``minimum`` (NaN propagates); :func:`folded_faces` is ``folds.local_folds_numpy``'s test on
those normals. tests/algorithms/xie_zou2013/test_fold_kernels.py checks them against the numpy code.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...geometry._flip_kernels import _find, _interior_edges, apply_scored_swaps, sorted_contains
from ...geometry._vector_kernels import cross3, dot3, norm3, npmin, sub3

__all__ = ["pair_agreements", "fold_swap_scores", "fold_swap_rounds", "folded_faces"]


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


@njit(cache=True)
def fold_swap_rounds(V, F, fixed, border_normals, max_rounds):
    """The rounds of folds.unfold_by_swaps: ``geometry.flips.relax_edges`` with the fold score, compiled.

    Each round makes, in order, the numpy rounds' choices (``flips._relax_numpy`` with the scored
    criterion of :func:`fold_swap_scores`, its priority ``-old``, no orientation test; each face's
    normal and border agreement computed once per round, the same numbers): the
    interior edges in half-edge order (``geometry._flip_kernels._interior_edges``), the edges whose
    swap raises the agreement by more than 1e-9 ranked by a stable sort of ``old``, the swaps that
    keep (c, d) distinct, create no existing edge and touch no ``fixed`` key, one claiming pass
    (the highest priority takes a face), then the first of each new edge in priority order.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64  changed in place
    fixed : (p,) int64  sorted distinct keys min * n + max of the edges no swap may touch or create
    border_normals : (k, 3) float64  as for :func:`fold_swap_scores`
    max_rounds : int

    Returns
    -------
    swaps : int
    rounds : int  rounds made (each that ended in swaps, plus the one that stopped)
    unsure : bool  the edge table of the last round needs the numpy code (a directed edge repeats,
        or an index is out of range): F holds the swaps of the rounds before it, which that code continues
    """
    n, m = V.shape[0], F.shape[0]
    swaps = 0
    for r in range(max_rounds):
        he, tw, start, half, tip, fine = _interior_edges(F, n)
        if not fine:
            return swaps, r, True
        e = he.shape[0]
        if e == 0:
            return swaps, r + 1, False
        # Each face's unit normal and agreement with the mesh across its loop edges, once per round:
        # the values _agreement computes for every pair holding the face.
        normal = np.empty((m, 3))
        across = np.empty(m)
        for f in range(m):
            nf = _unit_normal(V, F[f])
            normal[f, 0], normal[f, 1], normal[f, 2] = nf
            across[f] = _border_agreement(F[f], nf, border_normals)
        a = np.empty(e, np.int64)
        b = np.empty(e, np.int64)
        c = np.empty(e, np.int64)
        d = np.empty(e, np.int64)
        f1 = he // 3
        f2 = tw // 3
        old = np.empty(e)
        new = np.full(e, -np.inf)
        pair1 = np.empty(3, np.int64)
        pair2 = np.empty(3, np.int64)
        for i in range(e):
            c1, c2 = he[i] % 3, tw[i] % 3
            a[i], b[i] = F[f1[i], c1], F[f1[i], (c1 + 1) % 3]
            c[i], d[i] = F[f1[i], (c1 + 2) % 3], F[f2[i], (c2 + 2) % 3]
            na = (normal[f1[i], 0], normal[f1[i], 1], normal[f1[i], 2])
            nb = (normal[f2[i], 0], normal[f2[i], 1], normal[f2[i], 2])
            old[i] = npmin(dot3(na, nb), npmin(across[f1[i]], across[f2[i]]))
            if old[i] < 0.0:  # fold_swap_scores: the swapped pair is scored for folds only
                pair1[0], pair1[1], pair1[2] = a[i], d[i], c[i]
                pair2[0], pair2[1], pair2[2] = b[i], c[i], d[i]
                agreement, proper = _agreement(V, pair1, pair2, border_normals)
                if proper:
                    new[i] = agreement
        failing = np.flatnonzero(new > old + 1e-9)
        if failing.shape[0] == 0:
            return swaps, r + 1, False
        priority = np.zeros(e, np.int64)
        order = np.argsort(old[failing], kind="mergesort")  # -gain = -(-old): the worst fold first
        for rank in range(order.shape[0]):
            priority[failing[order[rank]]] = failing.shape[0] - rank
        cand = np.empty(failing.shape[0], np.int64)
        count = 0
        for i in failing:
            key = min(c[i], d[i]) * n + max(c[i], d[i])
            # an edge of F at the round's start, either way round (its half-edge table)
            if c[i] == d[i] or _find(start, half, tip, c[i], d[i]) >= 0 or _find(start, half, tip, d[i], c[i]) >= 0:
                continue
            if fixed.shape[0] and (sorted_contains(fixed, min(a[i], b[i]) * n + max(a[i], b[i]))
                                   or sorted_contains(fixed, key)):
                continue
            cand[count] = i
            count += 1
        if count == 0:
            return swaps, r + 1, False
        cand = cand[:count]  # edge order, as np.flatnonzero(ok)
        new_key = np.empty(e, np.int64)
        new1 = np.empty((e, 3), np.int64)
        new2 = np.empty((e, 3), np.int64)
        for i in range(e):
            new_key[i] = min(c[i], d[i]) * n + max(c[i], d[i])
            new1[i, 0], new1[i, 1], new1[i, 2] = a[i], d[i], c[i]
            new2[i, 0], new2[i, 1], new2[i, 2] = b[i], c[i], d[i]
        swaps += apply_scored_swaps(F, f1, f2, cand, priority, new_key, new1, new2)
    return swaps, max_rounds, False


@njit(cache=True)
def folded_faces(V, F, border_normals, limit):
    """(bad, ok): ``folds.local_folds`` of V (n, 3) float64 and F (m, 3) int64 with the cosine ``limit``.

    A face is folded where its unit normal is zero (degenerate), where its normal and a neighbour's
    across an interior edge have a dot below ``limit``, or, on a loop edge (i, i + 1) of the k rows of
    ``border_normals`` (k = 0: no loop test), where its normal and row i have. ok is False where an
    index is out of range or a directed edge repeats (the numpy code decides then).
    """
    n, m = V.shape[0], F.shape[0]
    bad = np.zeros(m, np.bool_)
    for f in range(m):
        for c in range(3):
            if F[f, c] < 0 or F[f, c] >= n:
                return bad, False
    he, tw, _, _, _, fine = _interior_edges(F, n)
    if not fine:
        return bad, False
    N = np.empty((m, 3))
    for f in range(m):
        N[f, 0], N[f, 1], N[f, 2] = _unit_normal(V, F[f])
        bad[f] = N[f, 0] == 0 and N[f, 1] == 0 and N[f, 2] == 0
    for e in range(he.shape[0]):
        f1, f2 = he[e] // 3, tw[e] // 3
        if dot3((N[f1, 0], N[f1, 1], N[f1, 2]), (N[f2, 0], N[f2, 1], N[f2, 2])) < limit:
            bad[f1] = True
            bad[f2] = True
    k = border_normals.shape[0]
    for f in range(m):
        for c in range(3):
            a, b = F[f, c], F[f, (c + 1) % 3]
            if a < k and b == (a + 1) % k:
                across = (border_normals[a, 0], border_normals[a, 1], border_normals[a, 2])
                if dot3((N[f, 0], N[f, 1], N[f, 2]), across) < limit:
                    bad[f] = True
    return bad, True
