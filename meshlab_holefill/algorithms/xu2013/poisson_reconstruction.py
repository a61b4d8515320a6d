"""The Poisson reconstruction of the patch (Xu, Li and Tan 2013, Sec. 2.3, 3.4, Eq. 16-19).

The inner vertices of the initial patch are placed by L x = Delta', L the patch's normalised
cotangent Laplacian (:func:`.poisson_patch.normalized_cotangent_laplacian`), Delta' the
Laplacians the LS-SVM predicts (:mod:`.laplacian_regression`), the hole boundary fixed and its
vertices' own Laplacian rows added (``poisson_boundary``); then the safeguards beyond the paper
(:func:`reposition`: relaxation, unfolding, damping against crossings).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...core.holes import boundary_halfedges
from ...geometry.laplacian import cotangent_weights, tangential_umbrella_smoothing
from ...geometry.sparse_lu import symmetric_lu
from .laplacian_regression import patch_laplacians
from .poisson_patch import (context_hits, normalized_cotangent_laplacian, relax_patch, repair_slivers,
                            solve_folds)

__all__ = ["with_context", "boundary_rows", "solve_poisson", "poisson_reposition", "unfold", "poisson_solves",
           "reposition", "TANGENTIAL_ITERATIONS", "SLIVER_QUALITY"]

# Tangential smoothing steps after the Poisson solve (with relax): 3 raised the benchmark's
# minimum triangle quality from 0.11 to 0.48 without changing the distance to the ground truth.
TANGENTIAL_ITERATIONS = 3
# Beyond the paper: triangles still below this quality after the smoothing get local tangential
# steps (repair_slivers); 0.3 is the minimum quality below which a triangle counts as poor
# (docs/notes/xu2013_lssvm_poisson.md).
SLIVER_QUALITY = 0.3


def with_context(X, F, ctx):
    """The patch joined to the HoleContext's surrounding faces: patch vertices first, then the context's others."""
    k, p = ctx.size, len(X) - ctx.size
    allX = np.concatenate([X, ctx.vertices[k:]])
    context = np.where(ctx.faces >= k, ctx.faces + p, ctx.faces)
    return allX, np.concatenate([np.asarray(F, np.int64), context])


def boundary_rows(X, F, ctx):
    """Hole-boundary vertices whose Laplacian row (Eq. 1) is complete once the patch closes the hole.

    Left out: those also on another border of the surrounding mesh (another hole, the mesh
    border), where Eq. 1 is not defined.
    """
    allX, allF = with_context(X, F, ctx)
    he, _ = boundary_halfedges(allF)
    on_border = np.zeros(len(allX), bool)
    on_border[he.ravel()] = True
    return np.flatnonzero(~on_border[:ctx.size]), allX, allF


def solve_poisson(X, F, free, rhs, boundary=None, cotangents=None, boundary_weight=1.0):
    """Positions of the free vertices solving Eq. 18, the three coordinates with one factorisation.

    Without ``boundary``: the square system L_ff x_f = rhs - L_fb x_b (Dirichlet boundary).
    With ``boundary = (rows, allX, allF, rhs_rows)``: the hole-boundary vertices' rows of the
    Laplacian of the patch joined to the surrounding mesh are added, each asking that vertex's
    Laplacian to equal its prediction too, and the system is solved in the least-squares
    sense (normal equations), the boundary still fixed; ``boundary_weight`` multiplies those
    rows (their squared residuals count ``boundary_weight ** 2`` times an inner row's).
    ``cotangents`` ((len(F), 3)) are the patch faces' corner cotangents when they are not those
    of X (:func:`poisson_reposition`'s ``layout``); the surrounding faces always have their own.
    """
    free_idx = np.flatnonzero(free)
    if boundary is None:
        L = normalized_cotangent_laplacian(X, F, cotangents=cotangents)
        B = rhs - L[free][:, ~free] @ X[~free]
        return spla.splu(L[free][:, free].tocsc()).solve(B)
    rows, allX, allF, rhs_rows = boundary
    if cotangents is not None:
        cotangents = np.concatenate([cotangents, cotangent_weights(allX, allF[len(F):])])
    L = normalized_cotangent_laplacian(allX, allF, cotangents=cotangents)
    known = np.ones(len(allX), bool)
    known[free_idx] = False
    LR = L[np.concatenate([free_idx, rows])]
    A = LR[:, free_idx].tocsc()
    B = np.concatenate([rhs, rhs_rows]) - LR[:, known] @ allX[known]
    At = A.T
    if boundary_weight != 1.0:
        row_weights = np.concatenate([np.ones(len(free_idx)), np.full(len(rows), float(boundary_weight) ** 2)])
        At = At @ sp.diags(row_weights)  # A^T W A x = A^T W B: the weighted normal equations
    return symmetric_lu(At @ A).solve(At @ B)  # At @ A is symmetric positive definite


def poisson_reposition(X, F, fixed, regressors=None, iterations=1, update_rhs=False, relax_ctx=None, boundary_ctx=None,
                       layout=None, boundary_weight=1.0):
    """Poisson reconstruction of the patch (Sec. 2.3, 3.4, Eq. 16-19).

    Solves L_Vn V'_d = Delta'_d (Eq. 18) for the inner vertices, d = x, y, z, with L_Vn the
    normalised cotangent Laplacian of the patch (Eq. 5-6), Delta' the predicted Laplacians
    (Eq. 19; zero without regressors) and the boundary vertices as Dirichlet conditions; one
    sparse LU factorisation per solve serves the three coordinates (:func:`solve_poisson`).

    The boundary condition. Sec. 2.3 takes as known "the collection of divergence values at
    all boundary vertices formulated by Eq. (1) ... as the boundary condition", and Sec. 3.4
    computes the patch "in the least squares sense". With ``boundary_ctx`` (the default of
    :func:`fill`, ``poisson_boundary='laplacian'``) that is the reading: the boundary stays
    fixed, and each boundary vertex's Laplacian (Eq. 1 over its whole 1-ring, mesh and patch)
    is one more equation, asked to equal the prediction at that vertex; the overdetermined
    system is solved by least squares. Those rows tie the first ring of the patch to the
    surface around the hole, so the patch continues the surface's slope instead of meeting it
    at an angle. Measured on the benchmark's 42 holes with ground truth (mean patch-to-ground-
    truth distance, per mille of the bounding-box diagonal; ``scripts/benchmark.py`` cases
    without the natural-hole scans): 3.80 with the square Dirichlet system, 2.13 with the
    boundary rows (small holes 0.203 -> 0.139, medium 3.27 -> 2.43, large 5.63 -> 2.19,
    creased 7.00 -> 3.96, crossing 0.74 -> 0.32; cow.obj's 68-edge hole 8.80 -> 8.32,
    creased_box's 93-edge 23.1 -> 14.8, airplane.obj's 165-edge 9.29 -> 3.20).

    The weight of the boundary rows (``boundary_weight``; the paper does not weigh the
    equations). Weighted as an inner row, the k boundary equations are drowned out on large
    holes by the inner ones (a round hole of k edges has about k^2 / 11), and the patch leaves
    the surrounding surface's slope to follow the interior predictions, which are
    extrapolations. The weight is chosen as the one of 1, 2, 3, 4 and 6 with the lowest mean
    patch-to-ground-truth distance (per mille of the bounding-box diagonal) over the holes of
    ``scripts/unseen_holes.py`` (LS-SVM alone through ``evaluation.comparison.run_comparison``;
    closed, creased and CAD groups seeds 1-3, 157 holes, and real-size seeds 1-6, 18 holes):
    2.0, with 3.183 / 2.901 / 2.911 / 3.017 / 3.105 for the five weights. Per group, 1 -> 2:

    - closed, creased and CAD 3.408 -> 3.108 (CGAL's Liepa fill 4.252; holes under 30 edges
      0.863 -> 0.749); seeds 4-6, which the choice did not see (153 holes), 4.132 -> 3.946
      (CGAL 5.425);
    - real-size 1.219 -> 1.098 (CGAL 1.130; 17 of the 18 holes closer, bunny_212k s3's
      152-edge hole 1.03 -> 0.89, s5's 251-edge 2.58 -> 1.98);
    - noisy cow seeds 1-4, 1.801 -> 1.803 (CGAL 1.447; 9 of 15 holes farther: the boundary
      Laplacians of a noisy mesh are noise, and a heavier row follows it); range scans seeds
      1-2, 0.035 either way;
    - the benchmark's 49 cut holes 1.868 -> 1.744 (CGAL 2.844); ``scripts/large_holes.py``
      3.137 -> 2.886; ``scripts/strip_holes.py`` 0.292 -> 0.260.

    Rows made constraints (weight 30) give 1.128 on the real-size holes. With either weight no
    hole of these has a face crossing the mesh, and none but one noisy-cow hole (0.067 both
    times) a triangle below 0.1.

    L_Vn of the first solve is the Laplacian of the triangles the advancing front made. Where
    it made them in a plane (the developed or projected fallback of
    :func:`.poisson_patch.initial_patches`, ``layout``), their weights are taken there, not
    from the harmonic lift that places them in 3D: the lift is a membrane spanning the loop,
    its triangles shrunk and sheared towards the middle of a curved hole, while the planar
    triangles are the front's well-shaped ones and, on a developable surface, congruent to
    the surface's own. Measured on the benchmark's 45 holes with ground truth (6 of them on
    the developed fallback; command in docs/notes/xu2013_lssvm_poisson.md): mean
    patch-to-ground-truth distance 1.967 -> 1.849 per mille of the bounding-box diagonal
    (creased 3.883 -> 3.507; the real-size bunny's 3 holes 1.164 -> 0.914, CGAL's Liepa
    fill 0.877; large 2.017 -> 2.211; medium 1.982 -> 2.096): creased_box's 93-edge hole
    14.7 -> 9.3, the real-size 151-edge hole 1.68 -> 1.01, union's 69-edge 6.8 -> 6.2;
    worse on airplane.obj's 165-edge hole (3.3 -> 4.1) and bone.ply's 60-edge hole (4.5 ->
    5.2), both strongly doubly curved, where the development distorts the metric most. The
    lowest triangle quality over the holes went from 0.356 to 0.290 (bone.ply's hole: a
    triangle of three border vertices that the swaps after the solve leave).

    Delta' is predicted once, at the initial patch's vertices (and the boundary's): predicting
    it again at each solve's result made the iteration diverge on several benchmark holes (the
    bulge raises the prediction, which raises the bulge). L_Vn depends on the positions, so
    ``iterations`` > 1 solves again with the weights of the previous result (after Delaunay
    swaps when ``relax_ctx`` is given). One solve is the default: weights from the
    well-shaped initial patch gave the lower distance to the ground truth on the benchmark's
    medium holes (Dirichlet system: mean 3.1 per mille of the bounding-box diagonal with 1
    solve, 3.7 with 2, 3.6 with 3) and better triangles. A solve that folds the patch where it
    moves it (:func:`.poisson_patch.solve_folds`: a degenerate triangle, or neighbours at a
    dihedral angle over 120 degrees) and that :func:`unfold` cannot unfold (with
    ``relax_ctx``; folds the patch had before the solve excepted) is discarded and the
    iteration stops.

    Parameters
    ----------
    X : (n, 3) float64  patch vertices (boundary ones included)
    F : (m, 3) int64    patch faces
    fixed : (n,) bool   Dirichlet vertices (the hole boundary)
    regressors : list of 3 callables, NormalFrameRegressor or None
    iterations : int
    update_rhs : bool   predict Delta' again before each solve (diverges, see above)
    relax_ctx : HoleContext, optional  swap edges between solves and where a solve folds
        (:func:`relax_patch`)
    boundary_ctx : HoleContext, optional  add the boundary vertices' Laplacian rows
        (:func:`boundary_rows`) and solve by least squares
    layout : (n, 3) float64, optional  the patch's planar layout: the first solve's weights
    boundary_weight : float  the weight of the boundary vertices' rows against the inner rows' (with
        ``boundary_ctx``; :func:`solve_poisson`)

    Returns
    -------
    X : (n, 3) float64
    F : (m, 3) int64  (changed only by swaps between solves)
    info : dict  ``poisson_solves``, ``poisson_last_change`` (max displacement of the last
        accepted solve relative to the first), ``poisson_rejected`` (a solve was discarded)
    """
    X = np.array(X, np.float64)
    free = ~np.asarray(fixed, bool)
    info = {"poisson_solves": 0, "poisson_last_change": 0.0, "poisson_rejected": False}
    if not free.any():
        return X, F, info
    first_change = None
    rhs = patch_laplacians(regressors, X, F, free)
    rhs_rows = None
    for _ in range(iterations):
        if update_rhs and regressors is not None:
            rhs = patch_laplacians(regressors, X, F, free)
        boundary = None
        if boundary_ctx is not None:
            rows, allX, allF = boundary_rows(X, F, boundary_ctx)
            if rhs_rows is None:
                rhs_rows = patch_laplacians(regressors, allX, allF, rows)
            boundary = (rows, allX, allF, rhs_rows)
        layouts = [layout, None] if layout is not None and not info["poisson_solves"] else [None]
        for weights_from in layouts:
            Y, G = _unfolded_solve(X, F, free, rhs, boundary, weights_from, relax_ctx, boundary_weight)
            if Y is not None:
                info["poisson_layout_weights"] = weights_from is not None
                break
        if Y is None:
            info["poisson_rejected"] = True
            break
        F = G
        change = float(np.abs(Y - X).max())
        first_change = change if first_change is None else first_change
        info["poisson_last_change"] = change / first_change if first_change > 0 else 0.0
        info["poisson_solves"] += 1
        X = Y
        if relax_ctx is not None and iterations > 1:
            F, _ = relax_patch(X, F, relax_ctx)
    return X, F, info


def _unfolded_solve(X, F, free, rhs, boundary, layout, relax_ctx, boundary_weight):
    """One solve (:func:`solve_poisson`, the patch faces' weights from ``layout`` if given), unfolded; (None, F) if it fails."""
    Y = X.copy()
    Y[free] = solve_poisson(X, F, free, rhs, boundary, None if layout is None else cotangent_weights(layout, F),
                            boundary_weight)
    if not np.all(np.isfinite(Y)):
        return None, F
    if solve_folds(Y, F, ~free):
        return unfold(Y, F, ~free, relax_ctx, X)
    return Y, F


def unfold(Y, F, fixed, relax_ctx=None, before=None):
    """A folded Poisson solution unfolded by the relaxation that follows every solve, or (None, F).

    A fold across one edge is often a quad the solve turned over: its other diagonal (the
    Delaunay swap, :func:`.poisson_patch.relax_patch`) unfolds it, and discarding the whole
    solve for it lost the predicted shape (airplane's large hole: 10.2 per mille from the
    ground truth without the solve, 8.7 with it). Where swaps are not enough, the solve has
    pressed free vertices against a spike of the boundary; the tangential smoothing that
    follows the solve anyway (``TANGENTIAL_ITERATIONS`` steps, then swaps) spreads them again.
    On bone.ply's 66-edge irregular hole (holes cut with ``scripts/benchmark.py --seed 1
    --holes 6``) the solve was discarded for such a fold, leaving the patch 3.9 per mille of
    the bounding-box diagonal from the ground truth; unfolded, 0.39 (CGAL's Liepa fill 0.26).
    When the solve with the planar layout's weights cannot be unfolded, the lift's own weights
    are tried before the solve is discarded. Without ``relax_ctx`` (``relax`` off) a fold
    discards the solve. Where neither unfolds it, the folds left may be those the patch had
    ``before`` the solve (its positions then): they are not the solve's
    (:func:`.poisson_patch.solve_folds`), and the solve is kept, swapped, then smoothed if
    the swaps alone leave a fold of its own.

    Returns
    -------
    Y : (n, 3) float64 or None, F : (m, 3) int64
    """
    if relax_ctx is None:
        return None, F
    G = relax_patch(Y, F, relax_ctx)[0]
    if not solve_folds(Y, G, fixed):
        return Y, G
    Z = tangential_umbrella_smoothing(Y, G, fixed, TANGENTIAL_ITERATIONS)
    H = relax_patch(Z, G, relax_ctx)[0]
    if not solve_folds(Z, H, fixed):
        return Z, H
    if before is not None:
        if not solve_folds(Y, G, fixed, before):
            return Y, G
        if not solve_folds(Z, H, fixed, before):
            return Z, H
    return None, F


def poisson_solves(stats, poisson_iterations):
    """How many Poisson solves (Sec. 3.4) an initial patch gets: at least two on the loop's development.

    The first solve of a patch the front built on the loop's development takes the layout's
    weights (:func:`poisson_reposition`), which are the surface's own on a developable surface,
    creases included, and not where the loop encloses Gaussian curvature: the development keeps
    the loop's perimeter and spreads the curvature it encloses evenly along it, right for a round
    cap only. A second solve takes the first result's own weights, and the filter keeps it only
    when its patch meets the surrounding surface with the smaller border bend
    (:func:`.lssvm_poisson._less_bent`, the criterion curve unfolding chooses its domain by). On
    holes of a unit sphere, mean distance of the patch from the sphere with one and two solves: a
    round cap 0.0060 and 0.0061, an ellipse of half-axes 1.2 and 0.4 0.0074 and 0.0040, a
    three-lobed hole 0.0107 and 0.0072 (``tests/algorithms/xu2013/test_planar_layout_weights.py``).

    Measured (mean patch-to-ground-truth distance, per mille of the bounding-box diagonal):
    without the bend choice, two solves on every developed patch lost on flat-sided ones
    (creased_box's 93-edge hole, enclosing no curvature: 9.33 -> 11.98), so the second solve was
    made only where the loop encloses more than 0.37 rad (a round cap's development is then 2 %
    short of its geodesic radius): ``scripts/large_holes.py --filters
    meshing_close_holes_lssvm_poisson`` 3.451 -> 3.290 (CGAL's Liepa fill 3.001; bone2_s1's
    271-edge hole 1.44 -> 0.58, bunny1_s1's 265-edge 2.40 -> 1.56). With the bend choice the
    threshold is not needed: every developed patch gets the second solve.
    ``scripts/unseen_holes.py --seeds 1,2,3,4,5,6`` (LS-SVM alone) against the threshold: real-size
    1.250 -> 1.219 (three holes better, none worse: 0.442 -> 0.354, 1.401 -> 1.328, 1.506 -> 1.094;
    CGAL 1.130), closed 1.158 -> 1.156, creased (3.827), CAD (9.157) and noisy (2.114) unchanged;
    ``scripts/large_holes.py`` 3.143 -> 3.137 (bone2_s2's 299-edge hole 0.31 -> 0.17, no other
    hole changed); ``scripts/strip_holes.py`` unchanged (0.292).

    Parameters
    ----------
    stats : dict  the initial patch's, from :func:`.poisson_patch.initial_patches`
    poisson_iterations : int  the filter's parameter

    Returns
    -------
    int
    """
    if stats.get("domain") == "developed":
        return max(poisson_iterations, 2)
    return poisson_iterations


def reposition(ctx, X, F, regressors, iterations, relax, poisson_boundary="laplacian", layout=None, boundary_weight=1.0):
    """Relax, Poisson reconstruction (Sec. 3.4), relax; checked against the surrounding mesh.

    With ``relax`` (beyond the paper) the solve is followed by swaps, :func:`geometry.laplacian.tangential_umbrella_smoothing`,
    swaps again and :func:`repair_slivers` around triangles still below ``SLIVER_QUALITY``
    (dropped again if only the repaired patch touches the surrounding mesh).

    The initial patch is (nearly always) clear of the surrounding mesh; the swaps and the
    Poisson solve may not be (a bulge into a fold of the surface next to the hole). Then the
    swaps are undone and the displacement damped (beyond the paper) until the patch is clear,
    down to the initial patch itself.

    Returns
    -------
    X : (n, 3) float64 or None (not even the initial patch is clear of the mesh)
    F : (q, 3) int64
    info : dict  Poisson counts, ``swaps``, ``poisson_damping`` (1 = the full solve); where X is None and
        ``ctx.crossings_allowed``, ``crossing_patch``: (X, F) of the full solve, which crosses the mesh
    """
    k = ctx.size
    X_front, F_front = X, F
    swaps = 0
    if relax:
        F, swaps = relax_patch(X, F, ctx)
    fixed = np.arange(len(X)) < k
    X, F, info = poisson_reposition(X, F, fixed, regressors, iterations, relax_ctx=ctx if relax else None,
                                    boundary_ctx=ctx if poisson_boundary == "laplacian" else None, layout=layout,
                                    boundary_weight=boundary_weight)
    if not np.all(np.isfinite(X)):
        X, F = X_front, F_front
    repaired = 0
    if relax:
        F, more = relax_patch(X, F, ctx)
        X = tangential_umbrella_smoothing(X, F, fixed, TANGENTIAL_ITERATIONS)
        F, again = relax_patch(X, F, ctx)
        swaps += more + again
        X_smooth, F_smooth = X, F
        X, F, repaired = repair_slivers(X, F, fixed, ctx, SLIVER_QUALITY)
    info.update(swaps=swaps, poisson_damping=1.0, sliver_repairs=repaired)
    if not len(context_hits(X, F, ctx)):
        return X, F, info
    if repaired and not len(context_hits(X_smooth, F_smooth, ctx)):
        info["sliver_repairs"] = 0
        return X_smooth, F_smooth, info
    info["swaps"] = 0
    for t in (1.0, 0.5, 0.25, 0.0):
        Y = X_front + t * (X - X_front)
        if not len(context_hits(Y, F_front, ctx)):
            info["poisson_damping"] = t
            return Y, F_front, info
    if ctx.crossings_allowed:
        info["crossing_patch"] = (X, F)
    return None, F_front, info
