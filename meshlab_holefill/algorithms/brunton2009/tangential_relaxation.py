"""Tangential relaxation of an embedded patch (beyond Brunton et al. 2009; option ``tangential``).

E_DF (Sec. 3.3, :mod:`.embedding`) gives the patch its shape; this step keeps the shape and moves
the interior vertices within their tangent planes to where the tangential part of the umbrella U
vanishes, the distribution E_AREA would give, solved at once as one sparse system.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...geometry.quality import corner_sums, cross_rows
from ...geometry.sparse_lu import symmetric_lu
from ._tangential_kernels import face_cross, faces_touching, frame_pairs, free_frames, free_umbrella, rows_times
from .recent_solves import RecentSolves
from .umbrella import umbrella_operator

__all__ = ["vertex_normals", "tangent_frames", "tangential_system", "tangential_relaxation"]


def vertex_normals(X, F):
    """Area-weighted unit vertex normals, (n, 3) (zero rows for isolated vertices)."""
    X = np.asarray(X, np.float64)
    F = np.asarray(F, np.int64)
    face_normals = cross_rows(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])
    N = corner_sums(F, face_normals, len(X))
    length = np.linalg.norm(N, axis=1)
    return N / np.where(length > 0, length, 1.0)[:, None]


def tangent_frames(N):
    """Two unit vectors spanning the plane orthogonal to each unit row of N, (s, 3) each."""
    N = np.asarray(N, np.float64)
    helper = np.where(np.abs(N[:, [0]]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    b1 = cross_rows(N, helper)
    b1 /= np.maximum(np.linalg.norm(b1, axis=1), 1e-300)[:, None]
    return b1, cross_rows(N, b1)


def tangential_relaxation(X, F, free):
    """Move the free vertices within their tangent planes until U has no tangential part.

    Not in the paper (option ``tangential`` of the curve-unfolding filter). The uniform
    umbrella U of Sec. 3.3 depends on connectivity only, and E_DF extrapolates the slope of
    the border: next to a long border edge or a border vertex whose surface leaves a wide
    opening, E_DF pulls the nearest interior vertex almost onto the border and squeezes its
    triangle (measured on the face scan's natural holes: planar quality 0.4-0.7, embedded
    0.04-0.1), while E_AREA, whose minimiser puts every interior vertex at the centroid of
    its 1-ring, leaves those triangles well shaped but is flat (worse distance to the
    surface). This step keeps E_DF's shape and takes E_AREA's distribution within it: with
    unit normal n_p of the embedded surface (area weighted over the patch and its
    surroundings) and a tangent frame B_p = [b1_p, b2_p], the free vertices move to
    x_p + B_p t_p where

        B_p^T U(p) = 0   for every free p,

    the fixed point of tangential Laplacian smoothing (Botsch and Kobbelt 2004, "A remeshing
    approach to multiresolution modeling", tangential relaxation), solved at once as one
    sparse system of 2 s unknowns t (blocks W_pq B_p^T B_q, diagonal -I: diagonally dominant
    like the Laplacian) rather than by iterating. The normals are those of the input, so
    the shape moves only to second order in the tangential displacement. If the full step
    flips a face of the free vertices' stars it is halved (at most 4 times, then no move),
    unless the patch was folded (edges between faces more than 90 degrees apart) and the step
    leaves no fold: unfolding flips the folded faces (a flat 64-gon in a one-face-wide
    annulus: the energy's placement folds 66 of 244 faces in the plane, the relaxation then
    leaves none). Taking also steps that leave fewer folds but some moved a 296-edge hole of
    ``scripts/large_holes.py`` (airplane, seed 1) from 5.10 to 11.57 per mille.

    Parameters
    ----------
    X : (n, 3) float64  all vertex positions (fixed and free)
    F : (t, 3) int  faces of the joint mesh (patch and surroundings)
    free : (s,) int  indices of the vertices to move

    Returns
    -------
    X : (n, 3) float64  a copy with the free rows moved
    """
    X = np.array(X, np.float64)
    F = np.asarray(F, np.int64)
    free = np.asarray(free, np.int64)
    if len(free) == 0:
        return X
    X[free] = TANGENTIAL_STEPS.computed(TANGENTIAL_STEPS.key(X, F, free), lambda: _relaxed(X, F, free)[free])
    return X


#: Relaxations kept by :func:`tangential_relaxation`, by the content of their input: as
#: :data:`.embedding.AREA_SOLVES`, the noisy cow's 250-edge hole (seed 5) relaxed 15 of its 112
#: patches twice, 0.13 of 0.69 s.
TANGENTIAL_STEPS = RecentSolves(1 << 25)


def _relaxed(X, F, free):
    """:func:`tangential_relaxation` of X (a copy, float64) on F (int64) with ``free`` (s,) int64, s > 0."""
    s = len(free)
    # The free vertices' rows of U and their normals only see the faces around them: built on
    # those faces they are the same numbers (the same edges, degrees and sums, in the same order).
    star = faces_touching(np.ascontiguousarray(F), free, len(X))
    b1, b2 = free_frames(X, star, free)  # tangent_frames(vertex_normals(X, star)[free]), compiled
    A, U = tangential_system(star, X, free, (b1, b2))
    b = -np.concatenate([np.einsum("ij,ij->i", b1, U), np.einsum("ij,ij->i", b2, U)])
    try:
        t = symmetric_lu(A).solve(b)
    except RuntimeError:
        return X
    if not np.all(np.isfinite(t)):
        return X
    step = t[:s, None] * b1 + t[s:, None] * b2
    before = face_cross(X, star)
    # Where the patch is folded already, unfolding it flips the folded faces: a step that
    # leaves no fold is taken although it flips faces (one that leaves some, on a curved
    # patch, can carry vertices far off the surface). The folds are counted only once a step
    # flips a face (most full steps flip none).
    pairs, folds = None, 0
    alpha = 1.0
    for _ in range(5):
        Y = X.copy()
        Y[free] += alpha * step
        after = face_cross(Y, star)
        if np.all(np.einsum("ij,ij->i", before, after) > 0.0):
            return Y
        if pairs is None:
            pairs = _face_pairs(star)
            folds = _fold_count(before, pairs)
        if folds and _fold_count(after, pairs) == 0:
            return Y
        alpha *= 0.5
    return X


def _face_pairs(F):
    """The pairs of faces that share an edge, (e, 2) int64 (edges held by one face or by more than two left out)."""
    F = np.asarray(F, np.int64)
    edges = np.sort(np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)  # (3 t, 2): face f's at 3 f..3 f+2
    order = np.lexsort((edges[:, 1], edges[:, 0]))
    same = np.all(edges[order[1:]] == edges[order[:-1]], axis=1)
    first = np.flatnonzero(same)
    single = np.ones(len(first), bool)  # an edge of three faces or more is no fold of two
    if len(first) > 1:
        single &= np.r_[True, first[1:] != first[:-1] + 1] & np.r_[first[:-1] + 1 != first[1:], True]
    first = first[single]
    return np.stack([order[first] // 3, order[first + 1] // 3], axis=1)


def _fold_count(face_normals, pairs):
    """Edges whose two faces turn their normals more than 90 degrees apart."""
    return int(np.count_nonzero(np.einsum("ij,ij->i", face_normals[pairs[:, 0]], face_normals[pairs[:, 1]]) < 0.0))


def tangential_system(star, X, free, frames, direct=True):
    """The system of :func:`tangential_relaxation`: its matrix A (2 s, 2 s) and the umbrellas U of the free vertices.

    A has the blocks W_pq b_i(p) . b_j(q) (i, j = 1, 2) over the free vertices p, q, W the
    umbrella operator of ``star`` (:func:`umbrella_operator`); U = W[free] @ X. ``direct``
    builds the free rows of W and the CSC arrays of A from the star's edges (the same entries,
    values and storage order as scipy's construction, so SuperLU and the product see the same
    numbers); False is that construction (a sparse operator for all vertices, fancy indexing, a
    COO to CSC conversion), the reference the tests compare with, also taken for degenerate faces.

    Parameters
    ----------
    star : (t, 3) int64  the faces touching a free vertex
    X : (n, 3) float64
    free : (s,) int64
    frames : ((s, 3), (s, 3)) float64  tangent frames b1, b2 of the free vertices

    Returns
    -------
    A : (2 s, 2 s) CSC float64
    U : (s, 3) float64
    """
    n, s = len(X), len(free)
    if not direct:
        return _tangential_system_sparse(star, X, free, frames)
    ok, indptr, indices, data, r, c, w, a_indptr, a_indices, slots = free_umbrella(
        np.ascontiguousarray(star, np.int64), np.ascontiguousarray(free, np.int64), n)
    if not ok:
        return _tangential_system_sparse(star, X, free, frames)
    # The values as the reference computes them: the same einsum rows, entry by entry (the four
    # blocks' rows in one call).
    left, right = frame_pairs(*(np.ascontiguousarray(b, np.float64) for b in frames), r, c)
    values = np.empty(4 * len(w))
    values[slots.ravel()] = np.tile(w, 4) * np.einsum("ij,ij->i", left, right)
    A = sp.csc_matrix((values, a_indices, a_indptr.astype(np.int32)), shape=(2 * s, 2 * s))
    return A, rows_times(indptr, indices, data, X)  # U[free] @ X as scipy's product sums it


def _tangential_system_sparse(star, X, free, frames):
    """:func:`tangential_system` by scipy's general sparse construction (the reference)."""
    s = len(free)
    W = umbrella_operator(star, len(X))
    Wf = W[free]
    Wff = _principal_entries(W, free)
    blocks_r, blocks_c, blocks_v = [], [], []
    for i in range(2):
        for j in range(2):
            dots = np.einsum("ij,ij->i", frames[i][Wff.row], frames[j][Wff.col])
            blocks_r.append(Wff.row + i * s)
            blocks_c.append(Wff.col + j * s)
            blocks_v.append(Wff.data * dots)
    A = sp.csc_matrix((np.concatenate(blocks_v), (np.concatenate(blocks_r), np.concatenate(blocks_c))),
                      shape=(2 * s, 2 * s))
    return A, Wf @ X


def _principal_entries(W, rows):
    """The stored entries of W[rows][:, rows] as COO, renumbered (in W's storage order).

    The same (row, column, value) triples as scipy's fancy indexing then ``tocoo`` (the order
    of the triples does not matter to the matrix built from them), without its overhead.
    """
    n = W.shape[0]
    pos = np.full(n, -1, np.int64)
    pos[rows] = np.arange(len(rows))
    r = pos[np.repeat(np.arange(n), np.diff(W.indptr))]
    c = pos[W.indices]
    keep = (r >= 0) & (c >= 0)
    return sp.coo_matrix((W.data[keep], (r[keep], c[keep])), shape=(len(rows), len(rows)))
