"""Embedding a planar hole triangulation in space by the energies of Brunton et al. 2009, Sec. 3.3.

The boundary vertices sit on the hole's loop; the interior vertices P_Int minimise either the
least-squares mesh energy E_AREA = sum_p |U(p)|^2, with the umbrella operator
U(p) = (1 / |N_1(p)|) sum_{q in N_1(p)} q - p, or the discrete fairing energy
E_DF = sum_{p in P_Int} |U^2(p)|^2, U^2(p) = (1 / |N_1(p)|) sum_{q in N_1(p)} U(q) - U(p).
Both energies are quadratic in the interior positions, so each minimiser is one sparse
linear solve; the paper reaches the same minimisers with a quasi-Newton method (E_AREA) and
by iteration (E_DF).

E_AREA's sum: the paper prints it over P_Int and calls its minimiser a least-squares mesh
(Sorkine and Cohen-Or 2004, its ref. [24]), whose system has a Laplacian row for every vertex
with the known ones as anchors. The two differ: over P_Int alone the minimiser is U(p) = 0
at every interior vertex, a membrane spanning the loop; the least-squares mesh also keeps the
rows of the loop vertices, whose 1-rings reach into the surrounding surface (their rows are the
only ones that involve the unknowns besides P_Int's), so the patch leaves the loop along the
surrounding surface's slope. ``energy='area'`` is the least-squares mesh; ``'area_interior'``
the sum over P_Int as printed (measured on the benchmark's cut holes, small / medium / large,
per mille of the diagonal: 0.174 / 1.688 / 1.883 against 0.706 / 6.775 / 19.55, MeshLab 0.296 /
5.905 / 21.43).

Beyond the paper, :func:`tangential_relaxation` (option ``tangential`` of the filter) keeps the
shape E_DF gives and moves the interior vertices within their tangent planes to where the
tangential part of U vanishes, the distribution E_AREA would give.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...geometry.laplacian import uniform_laplacian
from ...geometry.quality import corner_sums, cross_rows, unique_edges
from ...errors import HoleFillError
from ._embedding_kernels import area_normal_equations
from ._tangential_kernels import face_cross, faces_touching, frame_pairs, free_frames, free_umbrella, rows_times

__all__ = ["symmetric_lu", "umbrella_operator", "energy_rows", "embedding_energy", "minimise_embedding_energy",
           "minimise_area_energy", "vertex_normals",
           "tangent_frames", "tangential_system", "tangential_relaxation", "embed_patch", "relax_patch"]


def umbrella_operator(F, n):
    """U of Sec. 3.3 as a sparse matrix: (W @ X)[p] = mean of p's 1-ring - p.

    Parameters
    ----------
    F : (t, 3) int
    n : int  number of vertices

    Returns
    -------
    W : (n, n) CSR float64  (rows of isolated vertices are zero)
    """
    F = np.asarray(F, np.int64)
    E = unique_edges(F)
    if len(E) == 0 or np.any(E[:, 0] == E[:, 1]):  # degenerate faces: the general sparse algebra
        L = uniform_laplacian(F, n)
        degree = -L.diagonal()
        inverse = np.where(degree > 0, 1.0 / np.maximum(degree, 1.0), 0.0)
        return (sp.diags(inverse) @ L).tocsr()
    return _umbrella_from_edges(E, n)


def _umbrella_from_edges(E, n):
    """diags(1 / degree) @ (A - diags(degree)) built directly, entry for entry as scipy builds it.

    Same values (1 / d and -d / d), same stored entries and the same order within each row
    (scipy's sparse product leaves the columns of a row in decreasing order), so every later
    sparse product and factorisation sees the identical matrix; scipy's construction (a COO
    to CSR conversion, a sparse difference and a sparse product) took most of the operator's
    time on a patch.
    """
    rows = np.concatenate([E[:, 0], E[:, 1]])
    cols = np.concatenate([E[:, 1], E[:, 0]])
    degree = np.bincount(rows, minlength=n).astype(np.float64)
    inverse = np.where(degree > 0, 1.0 / np.maximum(degree, 1.0), 0.0)
    has = np.flatnonzero(degree > 0)
    rows = np.concatenate([rows, has])
    cols = np.concatenate([cols, has])
    values = np.concatenate([inverse[rows[: 2 * len(E)]], inverse[has] * -degree[has]])
    order = np.argsort(rows * n + (n - 1 - cols), kind="stable")
    indptr = np.zeros(n + 1, np.int64)
    np.cumsum(np.bincount(rows, minlength=n), out=indptr[1:])
    W = sp.csr_matrix((values[order], cols[order].astype(np.int32), indptr.astype(np.int32)), shape=(n, n))
    W.has_sorted_indices = False
    return W


def energy_rows(F, n, free, order, anchors=False):
    """Residual operator R of the embedding energy E = |R X|^2 (Sec. 3.3, E_AREA / E_DF).

    Parameters
    ----------
    F : (t, 3) int  faces of the mesh the operator is built on
    n : int  number of vertices
    free : (n,) bool  the interior vertices P_Int (one residual row each)
    order : {1, 2}  1: R = U restricted to P_Int (E_AREA); 2: R = U^2 = U U restricted (E_DF)
    anchors : bool
        Also the rows of the fixed vertices whose umbrella involves a free vertex (the loop):
        the least-squares mesh of Sorkine and Cohen-Or, known vertices as hard anchors.

    Returns
    -------
    R : (f, n) CSR float64, f = free.sum() (plus the anchor rows, free rows first)
    """
    W = umbrella_operator(F, n)
    rows = np.flatnonzero(free)
    if anchors:
        # Rows with a stored entry in a free column (U stores no zeros): the column slice's
        # absolute row sums > 0, without the slice.
        touching = np.zeros(n, bool)
        touching[np.repeat(np.arange(n), np.diff(W.indptr))[np.asarray(free, bool)[W.indices]]] = True
        rows = np.concatenate([rows, np.flatnonzero(touching & ~np.asarray(free, bool))])
    R = W[rows]
    if order == 2:
        R = R @ W
    return R.tocsr()


def embedding_energy(X, R, free):
    """The energy |R X|^2 and its gradient with respect to the free vertices.

    Parameters
    ----------
    X : (n, 3) float64
    R : (f, n) sparse  from :func:`energy_rows`
    free : (n,) bool

    Returns
    -------
    energy : float
    gradient : (f, 3) float64  d energy / d X[free]
    """
    residual = R @ X
    return float(np.sum(residual ** 2)), 2.0 * (R[:, np.flatnonzero(free)].T @ residual)


SYMMETRIC_LU = dict(permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1, options=dict(SymmetricMode=True))


def symmetric_lu(A):
    """Sparse LU of a matrix with symmetric structure and a dominant diagonal (SuperLU's symmetric mode).

    The normal equations of E_AREA are symmetric positive definite and the tangential
    relaxation's system is block diagonally dominant with a symmetric pattern; SuperLU's
    default (COLAMD on A^T A, partial pivoting) treats them as general matrices. Ordered by
    minimum degree on A + A^T and preferring diagonal pivots (a pivot is taken off the
    diagonal only below 0.1 of its column's largest entry), the factors have 20-40 % fewer
    entries and take 1.5-2 times less time on the benchmark's large holes (3000-6400
    unknowns). The solutions change in the last bits only (relative 3e-13 for E_AREA, 3e-15
    for the tangential system on the 264-edge real-size hole; tested).

    Parameters
    ----------
    A : (n, n) sparse

    Returns
    -------
    scipy.sparse.linalg.SuperLU
    """
    return spla.splu(A.tocsc(), **SYMMETRIC_LU)


def minimise_embedding_energy(X, R, free):
    """Free positions minimising |R X|^2 with the other rows of X fixed (Sec. 3.3).

    The minimiser solves the normal equations R_f^T R_f X_f = -R_f^T R_c X_c. With one row per
    interior vertex R_f is square and non-singular for a patch whose interior is connected to
    its boundary, so this is the single sparse LU solve R_f X_f = -R_c X_c, where the residual
    and hence the gradient vanish: the same minimiser as the paper's quasi-Newton (E_AREA) and
    iterative (E_DF) solves, exactly and in one step. With anchor rows (least-squares mesh) R_f
    has more rows than columns and the normal equations are solved (sparse LU of R_f^T R_f,
    symmetric positive definite); the gradient 2 R_f^T (R X) vanishes there.

    Parameters
    ----------
    X : (n, 3) float64  fixed rows set; free rows are ignored
    R : (f, n) sparse
    free : (n,) bool

    Returns
    -------
    X : (n, 3) float64  with the free rows solved
    """
    X = np.array(X, np.float64)
    fi = np.flatnonzero(free)
    ci = np.flatnonzero(~np.asarray(free, bool))
    if len(fi) == 0:
        return X
    R = R.tocsc()
    A = R[:, fi].tocsc()
    b = -(R[:, ci] @ X[ci])
    try:
        if A.shape[0] > A.shape[1]:
            X[fi] = symmetric_lu((A.T @ A).tocsc()).solve(A.T @ b)
        else:
            X[fi] = spla.splu(A).solve(b)
    except RuntimeError:
        # Singular (interior not connected to the boundary): least squares is still a minimiser.
        M = (A.T @ A).tocsc() + 1e-12 * sp.identity(len(fi), format="csc")
        X[fi] = spla.splu(M).solve(A.T @ b)
    if not np.all(np.isfinite(X[fi])):
        raise HoleFillError("embedding energy solve produced non-finite positions")
    return X


def minimise_area_energy(X, F, free):
    """The least-squares mesh (E_AREA with the loop's rows, Sec. 3.3) over the faces F.

    ``minimise_embedding_energy(X, energy_rows(F, len(X), free, 1, anchors=True), free)``, the
    same bits, with the normal equations built compiled (:func:`._embedding_kernels.area_normal_equations`);
    scipy's construction for what the kernel leaves to it (degenerate faces, no fixed row).

    Parameters
    ----------
    X : (n, 3) float64  fixed rows set; free rows are ignored
    F : (t, 3) int
    free : (n,) bool

    Returns
    -------
    X : (n, 3) float64  with the free rows solved
    """
    X = np.array(X, np.float64)
    free = np.asarray(free, bool)
    ok, indptr, indices, data, rhs = area_normal_equations(np.ascontiguousarray(F, np.int64), free, X)
    if not ok:
        return minimise_embedding_energy(X, energy_rows(F, len(X), free, 1, anchors=True), free)
    fi = np.flatnonzero(free)
    M = sp.csc_matrix((data, indices, indptr.astype(np.int32)), shape=(len(fi), len(fi)))
    try:
        X[fi] = symmetric_lu(M).solve(rhs)
    except RuntimeError:
        # Singular (interior not connected to the boundary): as minimise_embedding_energy.
        X[fi] = spla.splu(M + 1e-12 * sp.identity(len(fi), format="csc")).solve(rhs)
    if not np.all(np.isfinite(X[fi])):
        raise HoleFillError("embedding energy solve produced non-finite positions")
    return X


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
    s = len(free)
    if s == 0:
        return X
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


def embed_patch(ctx, n_interior, F, energy="fairing", boundary=None, extra_faces=None, tangential=False):
    """Embed a triangulated hole in space (Sec. 3.3).

    Boundary vertices go to their loop positions, interior vertices minimise E_AREA
    (``energy='area'``: the least-squares mesh, loop rows included; ``'area_interior'``: the
    sum over P_Int only, a membrane) or E_DF (``'fairing'``). The operators are built on the
    patch joined to the surrounding faces of ``ctx``: U of an interior vertex only sees the patch, while
    U of a boundary vertex, needed by E_DF, uses its whole 1-ring in the filled model, which
    carries the slope of the surrounding surface into the patch (the boundary condition of
    Kobbelt et al.'s discrete fairing, which the paper cites for E_DF).

    Parameters
    ----------
    ctx : HoleContext
    n_interior : int  number of interior (new) vertices
    F : (t, 3) int64
        Patch faces: index i < b is boundary vertex i, b + j is interior vertex j, where b is
        the number of boundary vertices.
    energy : {'area', 'area_interior', 'fairing'}
    boundary : (b,) int, optional
        Local vertex index in ``ctx`` of each patch boundary vertex (default: the whole loop).
    extra_faces : (e, 3) int, optional
        Faces in ``ctx`` local indices already added to the hole (e.g. clipped ears).
    tangential : bool
        Follow the energy solve by :func:`tangential_relaxation` (beyond the paper).

    Returns
    -------
    interior : (n_interior, 3) float64
    """
    if n_interior == 0:
        return np.zeros((0, 3))
    X, joint, free = _joint_mesh(ctx, n_interior, F, boundary, extra_faces)
    if energy == "area":
        X = minimise_area_energy(X, joint, free)
    else:
        X = minimise_embedding_energy(X, energy_rows(joint, len(X), free, order=2 if energy == "fairing" else 1), free)
    if tangential:
        X = tangential_relaxation(X, joint, np.flatnonzero(free))
    return X[len(ctx.vertices):]


def _joint_mesh(ctx, n_interior, F, boundary=None, extra_faces=None, interior=None):
    """The patch joined to the surrounding faces: positions (interior rows zero unless given), faces, free mask."""
    boundary = np.arange(ctx.size) if boundary is None else np.asarray(boundary, np.int64)
    n_ctx = len(ctx.vertices)
    to_joint = np.concatenate([boundary, n_ctx + np.arange(n_interior)])
    parts = [np.asarray(ctx.faces, np.int64).reshape(-1, 3), to_joint[np.asarray(F, np.int64)]]
    if extra_faces is not None:
        parts.append(np.asarray(extra_faces, np.int64).reshape(-1, 3))
    n = n_ctx + n_interior
    X = np.zeros((n, 3))
    X[:n_ctx] = ctx.vertices
    if interior is not None:
        X[n_ctx:] = interior
    return X, np.concatenate(parts), np.arange(n) >= n_ctx


def relax_patch(ctx, interior, F, boundary=None, extra_faces=None):
    """:func:`tangential_relaxation` of a placed patch's interior vertices, on the patch joined to its surroundings.

    Parameters as :func:`embed_patch`; ``interior`` (s, 3) float64 the current interior positions.

    Returns
    -------
    interior : (s, 3) float64
    """
    interior = np.asarray(interior, np.float64)
    if len(interior) == 0:
        return interior
    X, joint, free = _joint_mesh(ctx, len(interior), F, boundary, extra_faces, interior)
    return tangential_relaxation(X, joint, np.flatnonzero(free))[len(ctx.vertices):]
