"""Embedding a planar hole triangulation in space by the energies of Brunton et al. 2009, Sec. 3.3.

The boundary vertices sit on the hole's loop; the interior vertices P_Int minimise either the
least-squares mesh energy E_AREA = sum_{p in P_Int} |U(p)|^2, with the umbrella operator
U(p) = (1 / |N_1(p)|) sum_{q in N_1(p)} q - p, or the discrete fairing energy
E_DF = sum_{p in P_Int} |U^2(p)|^2, U^2(p) = (1 / |N_1(p)|) sum_{q in N_1(p)} U(q) - U(p).
Both energies are quadratic in the interior positions, so each minimiser is one sparse
linear solve; the paper reaches the same minimisers with a quasi-Newton method (E_AREA) and
by iteration (E_DF).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..geometry.laplacian import uniform_laplacian
from ..patch import HoleFillError


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
    L = uniform_laplacian(np.asarray(F, np.int64), n)
    degree = -L.diagonal()
    inverse = np.where(degree > 0, 1.0 / np.maximum(degree, 1.0), 0.0)
    return (sp.diags(inverse) @ L).tocsr()


def energy_rows(F, n, free, order):
    """Residual operator R of the embedding energy E = |R X|^2 (Sec. 3.3, E_AREA / E_DF).

    Parameters
    ----------
    F : (t, 3) int  faces of the mesh the operator is built on
    n : int  number of vertices
    free : (n,) bool  the interior vertices P_Int (one residual row each)
    order : {1, 2}  1: R = U restricted to P_Int (E_AREA); 2: R = U^2 = U U restricted (E_DF)

    Returns
    -------
    R : (f, n) CSR float64, f = free.sum()
    """
    W = umbrella_operator(F, n)
    rows = W[np.flatnonzero(free)]
    if order == 2:
        rows = rows @ W
    return rows.tocsr()


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


def minimise_embedding_energy(X, R, free):
    """Free positions minimising |R X|^2 with the other rows of X fixed (Sec. 3.3).

    The minimiser solves the normal equations R_f^T R_f X_f = -R_f^T R_c X_c. R_f is square
    (one row per interior vertex) and non-singular for a patch whose interior is connected to
    its boundary, so this is the single sparse LU solve R_f X_f = -R_c X_c, where the residual
    and hence the gradient vanish: the same minimiser as the paper's quasi-Newton (E_AREA) and
    iterative (E_DF) solves, exactly and in one step.

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
        X[fi] = spla.splu(A).solve(b)
    except RuntimeError:
        # Singular (interior not connected to the boundary): least squares is still a minimiser.
        M = (A.T @ A).tocsc() + 1e-12 * sp.identity(len(fi), format="csc")
        X[fi] = spla.splu(M).solve(A.T @ b)
    if not np.all(np.isfinite(X[fi])):
        raise HoleFillError("embedding energy solve produced non-finite positions")
    return X


def embed_patch(ctx, n_interior, F, energy="fairing", boundary=None, extra_faces=None):
    """Embed a triangulated hole in space (Sec. 3.3).

    Boundary vertices go to their loop positions, interior vertices minimise E_AREA
    (``energy='area'``) or E_DF (``'fairing'``). The operators are built on the patch joined
    to the surrounding faces of ``ctx``: U of an interior vertex only sees the patch, while
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
    energy : {'area', 'fairing'}
    boundary : (b,) int, optional
        Local vertex index in ``ctx`` of each patch boundary vertex (default: the whole loop).
    extra_faces : (e, 3) int, optional
        Faces in ``ctx`` local indices already added to the hole (e.g. clipped ears).

    Returns
    -------
    interior : (n_interior, 3) float64
    """
    boundary = np.arange(ctx.size) if boundary is None else np.asarray(boundary, np.int64)
    if n_interior == 0:
        return np.zeros((0, 3))
    n_ctx = len(ctx.vertices)
    to_joint = np.concatenate([boundary, n_ctx + np.arange(n_interior)])
    parts = [np.asarray(ctx.faces, np.int64).reshape(-1, 3), to_joint[np.asarray(F, np.int64)]]
    if extra_faces is not None:
        parts.append(np.asarray(extra_faces, np.int64).reshape(-1, 3))
    n = n_ctx + n_interior
    X = np.zeros((n, 3))
    X[:n_ctx] = ctx.vertices
    free = np.arange(n) >= n_ctx
    R = energy_rows(np.concatenate(parts), n, free, order=1 if energy == "area" else 2)
    return minimise_embedding_energy(X, R, free)[n_ctx:]
