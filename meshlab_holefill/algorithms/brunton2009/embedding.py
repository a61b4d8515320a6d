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

Beyond the paper, :func:`.tangential_relaxation.tangential_relaxation` (option ``tangential`` of the filter) keeps the
shape E_DF gives and moves the interior vertices within their tangent planes to where the
tangential part of U vanishes, the distribution E_AREA would give.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...errors import HoleFillError
from ...geometry.sparse_lu import symmetric_lu
from ._embedding_kernels import area_normal_equations
from .recent_solves import RecentSolves
from .tangential_relaxation import tangential_relaxation
from .umbrella import umbrella_operator

__all__ = ["energy_rows", "embedding_energy", "minimise_embedding_energy", "minimise_area_energy", "embed_patch",
           "relax_patch"]


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
    F = np.ascontiguousarray(F, np.int64)
    X[free] = AREA_SOLVES.computed(AREA_SOLVES.key(X, F, free), lambda: _least_squares_mesh(X.copy(), F, free)[free])
    return X


def _least_squares_mesh(X, F, free):
    """:func:`minimise_area_energy` without the kept solves; X (float64) gets its free rows solved."""
    ok, indptr, indices, data, rhs = area_normal_equations(F, free, X)
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


#: Least-squares meshes kept by :func:`minimise_area_energy`, by the content of their input. A fill
#: embeds the same triangulation again without the tangential relaxation that follows the solve,
#: and the pipeline fills a hole once more, after the other holes when they are filled in one
#: process, where its patch crossed faces beyond its rings: the noisy cow of
#: ``scripts/unseen_holes.py`` (seed 5) solved 20 of its 87 systems twice. 32 MB holds those 87
#: solutions twelve times over.
AREA_SOLVES = RecentSolves(1 << 25)


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
